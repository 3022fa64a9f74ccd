"""Test courses for the GO1: a straight stair and a ramp between two landings.

Each course is a world spec (collision boxes in group ``COLLISION``, a floor plane at z = 0)
climbing along +x from ``x = 0``; the robot starts on the lower landing at ``START_X`` facing +x
(heading π/2) or on the upper landing facing −x. :func:`stairs_spec` and :func:`ramp_spec`
return the spec and the :class:`Course` facts a benchmark needs (where the flight starts and
ends, how high it climbs).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco

from havln_mj import groups
from havln_mj.errors import InvalidArgumentError
from havln_mj.robot.go1.model import flat_floor_spec

START_X = -1.0  # metres: the robot's start on the lower landing, 1 m before the first riser
LANDING = 2.0  # metres: length of the upper landing
_RGBA = (0.55, 0.5, 0.45, 1.0)


@dataclass(frozen=True)
class Course:
    """Where a course's flight lies.

    Attributes:
        kind: ``"stairs"`` or ``"ramp"``.
        run: Horizontal length of the flight (m), from ``x = 0``.
        rise: Height of the upper landing (m).
        width: Width of the flight (m), centred on ``y = 0``.
    """

    kind: str
    run: float
    rise: float
    width: float

    @property
    def top_x(self) -> float:
        """A point on the upper landing as far past the flight as ``START_X`` is before it."""
        return self.run - START_X


def stairs_spec(
    riser: float = 0.17, tread: float = 0.28, risers: int = 12, width: float = 1.0
) -> tuple[mujoco.MjSpec, Course]:
    """A straight stair of ``risers`` equal risers and treads, then an upper landing.

    The last riser lands on the upper landing, so the flight has ``risers − 1`` treads.
    """
    if not (0.0 < riser <= 0.3 and 0.1 <= tread <= 1.0 and 1 <= risers <= 40 and width > 0.3):
        raise InvalidArgumentError(
            f"stairs need riser in (0, 0.3] m, tread in [0.1, 1] m, 1-40 risers and width "
            f"> 0.3 m; got riser={riser!r}, tread={tread!r}, risers={risers!r}, width={width!r}"
        )
    spec = flat_floor_spec()
    run = (risers - 1) * tread
    for k in range(1, risers):
        add_box(spec, f"step{k}", (k - 1) * tread, k * tread, width, k * riser)
    add_box(spec, "landing", run, run + LANDING, width, risers * riser)
    return spec, Course("stairs", run, risers * riser, width)


def ramp_spec(
    degrees: float = 20.0, run: float = 2.5, width: float = 1.0
) -> tuple[mujoco.MjSpec, Course]:
    """A ramp climbing at ``degrees`` over a horizontal ``run``, then an upper landing."""
    if not (0.0 < degrees <= 45.0 and 0.5 <= run <= 10.0 and width > 0.3):
        raise InvalidArgumentError(
            f"ramps need degrees in (0, 45], run in [0.5, 10] m and width > 0.3 m; got "
            f"degrees={degrees!r}, run={run!r}, width={width!r}"
        )
    spec = flat_floor_spec()
    a = math.radians(degrees)
    rise = run * math.tan(a)
    add_slab(spec, "ramp", 0.0, run, a, width)
    add_box(spec, "landing", run, run + LANDING, width, rise)
    return spec, Course("ramp", run, rise, width)


def add_box(spec: mujoco.MjSpec, name: str, x0: float, x1: float, width: float, top: float) -> None:
    """A collision block from the floor up to ``top``, over ``x0…x1``, centred across."""
    spec.worldbody.add_geom(
        name=name,
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=(0.5 * (x1 - x0), 0.5 * width, 0.5 * top),
        pos=(0.5 * (x0 + x1), 0.0, 0.5 * top),
        group=groups.COLLISION,
        rgba=_RGBA,
    )


def add_slab(
    spec: mujoco.MjSpec, name: str, x_low: float, run: float, a: float, width: float
) -> None:
    """A ramp slab whose top face changes height by ``run·tan(a)`` over ``run``.

    Climbing (``a > 0``) its top starts at the floor at ``x_low``; descending it ends there.
    """
    rise = run * math.tan(abs(a))
    thick = 0.05
    cx = x_low + 0.5 * run if a > 0 else x_low - 0.5 * run
    # The top face's centre lies at (cx, rise / 2); the slab's centre half a thickness below.
    spec.worldbody.add_geom(
        name=name,
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=(0.5 * run / math.cos(a), 0.5 * width, thick),
        pos=(cx + thick * math.sin(a), 0.0, 0.5 * rise - thick * math.cos(a)),
        quat=(math.cos(a / 2), 0.0, -math.sin(a / 2), 0.0),
        group=groups.COLLISION,
        rgba=_RGBA,
    )
