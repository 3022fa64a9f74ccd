"""How a level is rasterised (``GridSpec``), and the checks every point argument goes through."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from havln_mj.errors import InvalidArgumentError

# Body heights (above the floor) that count as obstacles.
LEGGED_BAND = (0.1, 0.6)  # a GO1-sized quadruped: legs of tables block, table tops do not
PERSON_BAND = (0.05, 1.8)  # a person-height body (the point body's procedural sweep)

NEIGHBOURS = (8, 16, 32)


@dataclass(frozen=True)
class GridSpec:
    """How to rasterise a level.

    The defaults fit a GO1-sized quadruped: about 0.65 m long and 0.3 m wide, so a disc of
    radius 0.25 m is a compromise between its half width (0.15 m) and half length
    (0.33 m), and a body from 0.1 m to 0.6 m above the floor (legs and trunk; the feet may
    step over door sills and rugs, table tops above 0.6 m do not block but table legs do).
    For a person-height body use ``GridSpec(z_band=PERSON_BAND, robot_radius=0.2)``, the
    body the procedural houses' navigation graphs are checked with.

    Attributes:
        resolution: Cell size in metres.
        robot_radius: Radius in metres by which obstacles are inflated (0 for none).
        z_band: (low, high) heights above the floor; a geom blocks where its body lies
            between them.
        margin: Free border in metres added around the collision geometry's extent when
            the grid bounds are not given.
        neighbours: 8, 16 or 32: the moves of the geodesic graph (more is more accurate and
            slower; see ``havln_mj.nav``).
    """

    resolution: float = 0.05
    robot_radius: float = 0.25
    z_band: tuple[float, float] = LEGGED_BAND
    margin: float = 0.5
    neighbours: int = 16

    def __post_init__(self) -> None:
        if not (finite(self.resolution) and 0 < self.resolution <= 1.0):
            raise InvalidArgumentError(
                f"resolution must be in (0, 1] metres, got {self.resolution!r}"
            )
        if not (finite(self.robot_radius) and 0 <= self.robot_radius <= 5.0):
            raise InvalidArgumentError(
                f"robot_radius must be in [0, 5] metres, got {self.robot_radius!r}"
            )
        try:
            band = tuple(self.z_band)
        except TypeError:
            band = ()
        if len(band) != 2 or not all(finite(v) for v in band) or not band[0] < band[1]:
            raise InvalidArgumentError(
                f"z_band must be two finite heights (low, high) with low < high, "
                f"got {self.z_band!r}"
            )
        object.__setattr__(self, "z_band", (float(band[0]), float(band[1])))
        if not (finite(self.margin) and self.margin >= 0):
            raise InvalidArgumentError(f"margin must be >= 0 metres, got {self.margin!r}")
        if self.neighbours not in NEIGHBOURS:
            raise InvalidArgumentError(
                f"neighbours must be one of {NEIGHBOURS}, got {self.neighbours!r}"
            )


def finite(value: object) -> bool:
    """Whether ``value`` is a finite real number (Python or numpy scalar)."""
    return isinstance(value, int | float | np.floating | np.integer) and math.isfinite(value)


def point_xy(point: object, name: str) -> np.ndarray:
    """One point as a float (2,) array (a z coordinate is dropped).

    Raises:
        InvalidArgumentError: ``point`` (the argument ``name``) is not a finite 2-D or 3-D
            point.
    """
    try:
        p = np.asarray(point, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InvalidArgumentError(f"{name} must be a point (x, y[, z]), got {point!r}") from None
    if len(p) not in (2, 3) or not np.all(np.isfinite(p)):
        raise InvalidArgumentError(f"{name} must be a finite point (x, y[, z]), got {point!r}")
    return p[:2]


def points_xy(points: object, name: str) -> np.ndarray:
    """Points as a float (..., 2) array (z coordinates are dropped).

    Raises:
        InvalidArgumentError: ``points`` (the argument ``name``) are not finite points of
            shape (..., 2) or (..., 3).
    """
    try:
        p = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise InvalidArgumentError(f"{name} must be points (..., 2 or 3), got {points!r}") from None
    if p.ndim == 0 or p.shape[-1] not in (2, 3) or not np.all(np.isfinite(p)):
        raise InvalidArgumentError(
            f"{name} must be finite points of shape (..., 2) or (..., 3), got shape {p.shape}"
        )
    return p[..., :2]
