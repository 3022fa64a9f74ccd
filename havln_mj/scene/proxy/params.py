"""How a graph proxy is drawn, and the body it is checked for."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from havln_mj.errors import InvalidArgumentError


@dataclass(frozen=True)
class ProxyParams:
    """How a graph proxy is drawn, and the body whose walk it is checked for.

    Attributes:
        cell: Grid resolution in metres.
        viewpoint_radius: Free floor around each viewpoint.
        corridor_half_width: Free floor on each side of an edge.
        layer_gap: Floors differing by more than this in one cell go to separate layers.
        wall_height: Wall height above the floor beside it.
        slab: Floor and stair slab thickness.
        min_slab: Thinnest a slab is drawn: over a walkway below, a slab is thinned to keep
            the bodies walking there clear.
        stair_rise: An edge climbing more than this is drawn as stairs (its own material).
        riser: Highest riser of a stair (drawn risers are whole floor quanta no higher than
            this rounded up to one).
        headroom: Floors this far apart may overlap (storeys); closer ones may not. At least
            ``body_z[1] + slab``, so that a body passes under the floor above it.
        body_radius: Half side of the square footprint of the body whose walk is checked.
        body_z: Heights above the floor the body's trunk occupies: a step lower than the
            band's bottom beside the path is stepped over, not bumped into.
        step: Largest rise or drop between neighbouring points of a path (a stair riser).
        max_grade: Steepest climb or descent a path may have (rise over run) over any
            stretch ``grade_window`` long: 1.0 is 45°, steeper than any stair a building
            code allows. An edge steeper end to end is never drawn.
        grade_window: Length of the stretches ``max_grade`` is measured over.
        route_ratio: A route through other viewpoints may be at most this many times as
            long as its edge.
        stair_grade: Steepest climb of a flight drawn for an edge the graph cannot route
            (rise over run; 0.75 is 37°, a common stair: risers of ``riser`` on treads of
            0.24 m).
    """

    cell: float = 0.1
    viewpoint_radius: float = 0.9
    corridor_half_width: float = 0.5
    layer_gap: float = 1.0
    headroom: float = 1.95
    wall_height: float = 2.5
    slab: float = 0.1
    min_slab: float = 0.02
    stair_rise: float = 0.3
    riser: float = 0.18
    body_radius: float = 0.2
    body_z: tuple[float, float] = (0.3, 1.8)
    step: float = 0.2
    max_grade: float = 1.0
    grade_window: float = 1.0
    route_ratio: float = 1.5
    stair_grade: float = 0.75

    @property
    def reach_cells(self) -> int:
        """How many cells from the cell it stands on a body's footprint reaches boxes.

        A body's centre lies in the cell under it (at most half a cell from that cell's
        centre), and its square footprint meets a cell's box within ``body_radius`` plus half
        a cell of its centre: cells fewer than ``body_radius / cell + 1`` cells away.
        """
        return int(np.ceil(round((self.body_radius + self.cell) / self.cell, 9))) - 1

    def __post_init__(self) -> None:
        if not 0.02 <= self.cell <= 0.5:
            raise InvalidArgumentError(f"ProxyParams.cell={self.cell!r}; valid: 0.02–0.5 m")
        if self.corridor_half_width < self.body_radius + self.cell:
            raise InvalidArgumentError(
                f"ProxyParams.corridor_half_width={self.corridor_half_width!r} must be at least "
                f"body_radius + cell = {self.body_radius + self.cell:.2f} m"
            )
        if self.headroom < self.body_z[1] + self.slab:
            raise InvalidArgumentError(
                f"ProxyParams.headroom={self.headroom!r} must be at least body_z[1] + slab = "
                f"{self.body_z[1] + self.slab:.2f} m"
            )
        if not self.max_grade > 0.0:
            raise InvalidArgumentError(f"ProxyParams.max_grade={self.max_grade!r} must be > 0")
        if not 0.0 < self.stair_grade <= self.max_grade:
            raise InvalidArgumentError(
                f"ProxyParams.stair_grade={self.stair_grade!r}; valid: > 0 and at most "
                f"max_grade = {self.max_grade}"
            )
