"""What a GO1 primitive reports: the trunk pose, and a primitive's outcome."""

from __future__ import annotations

import math
from dataclasses import dataclass

from havln_mj.frames import wrap_angle


@dataclass(frozen=True)
class Go1Pose:
    """A trunk pose. ``heading`` follows :mod:`havln_mj.frames` (0 = +y, turning right)."""

    x: float
    y: float
    z: float
    yaw: float
    heading: float


@dataclass(frozen=True)
class PrimitiveResult:
    """What a primitive did.

    Attributes:
        kind: ``"forward"``, ``"turn"`` or ``"stand"``.
        target: Asked distance (m) or heading change (rad, + right).
        distance: True displacement along the start heading (m).
        lateral: True displacement across the start heading (m, + left).
        heading_change: True heading change (rad, + right).
        est_distance: ``distance`` according to the controller's estimate.
        est_lateral: ``lateral`` according to the estimate.
        est_heading_change: ``heading_change`` according to the estimate.
        duration: Physics time (s), settling included.
        steps: Physics steps taken.
        fell: The robot fell (tipped over or trunk too low); it needs a ``reset``.
        timed_out: The target was not reached: out of time, or no progress for 1 s (e.g.
            blocked by a wall).
    """

    kind: str
    target: float
    distance: float
    lateral: float
    heading_change: float
    est_distance: float
    est_lateral: float
    est_heading_change: float
    duration: float
    steps: int
    fell: bool
    timed_out: bool

    @property
    def error(self) -> float:
        """Achieved minus target, in metres for forward, radians for turn, 0 for stand."""
        if self.kind == "forward":
            return self.distance - self.target
        if self.kind == "turn":
            return wrap_angle(self.heading_change - self.target)
        return 0.0

    @classmethod
    def between(
        cls,
        kind: str,
        target: float,
        truth: tuple[Go1Pose, Go1Pose],
        estimate: tuple[Go1Pose, Go1Pose],
        **rest: float | int | bool,
    ) -> PrimitiveResult:
        """The result of a primitive from its start and end poses, true and estimated.

        ``rest`` holds ``duration``, ``steps``, ``fell`` and ``timed_out``.
        """
        along, lat, dh = _displacement(*truth)
        e_along, e_lat, e_dh = _displacement(*estimate)
        return cls(kind, target, along, lat, dh, e_along, e_lat, e_dh, **rest)


def _displacement(p0: Go1Pose, p1: Go1Pose) -> tuple[float, float, float]:
    """Along and across ``p0``'s heading (m), and the heading change (rad, + right)."""
    c, s = math.cos(p0.yaw), math.sin(p0.yaw)
    dx, dy = p1.x - p0.x, p1.y - p0.y
    return c * dx + s * dy, -s * dx + c * dy, -wrap_angle(p1.yaw - p0.yaw)
