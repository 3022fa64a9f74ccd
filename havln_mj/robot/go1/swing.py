"""One swing foot's flight: where it aims (the Raibert point), where it lands, how it flies.

A :class:`Swing` starts where the foot lifted off. While it is not locked, each control
step re-aims it at the Raibert point of the commanded twist (:func:`raibert_point`): the
foothold is moved off edges and the height profile follows the ground it crosses
(:mod:`~havln_mj.robot.go1.footholds`). :meth:`Swing.target` gives the foot's world target
at each phase of the swing.
"""

from __future__ import annotations

import math

from havln_mj.robot.go1 import constants as const
from havln_mj.robot.go1.footholds import (
    Ground,
    foothold,
    swing_along,
    swing_height,
    swing_heights,
)
from havln_mj.robot.go1.gains import TerrainGains


class Swing:
    """One swing: lift-off point, foothold, height profile."""

    __slots__ = ("aim", "goal", "locked", "start", "zs")

    def __init__(self, start: tuple[float, float, float]) -> None:
        self.start = start
        self.aim = (math.inf, math.inf)  # the Raibert point the foothold was found for
        self.goal = start
        self.zs: list[float] | None = None
        self.locked = False

    def aim_at(self, aim: tuple[float, float], ground: Ground, g: TerrainGains) -> None:
        """Finds the foothold and height profile again when the Raibert point has moved."""
        ax, ay = aim
        if not math.hypot(ax - self.aim[0], ay - self.aim[1]) > 0.005:  # not moved
            return
        self.aim = (ax, ay)
        gx, gy = ax, ay
        dx, dy = gx - self.start[0], gy - self.start[1]
        d = math.hypot(dx, dy)
        if d > 0.02:
            gx, gy = foothold(ground, gx, gy, dx / d, dy / d, g)
        if self.zs is None or math.hypot(gx - self.goal[0], gy - self.goal[1]) > 0.01:
            gz = ground(gx, gy) + const.FOOT_RADIUS - g.touchdown_depth
            if not math.isfinite(gz):  # under an obstacle: aim where the foot left
                gz = self.start[2]
            self.goal = (gx, gy, gz)
            self.zs = swing_heights(ground, self.start, self.goal, g)

    def target(self, s: float, dt: float, g: TerrainGains) -> tuple[float, float, float] | None:
        """The foot's world target at phase ``s`` (past 1: still reaching down for ground).

        Returns None once it has reached down too far: it lands where it is.
        """
        (x0, y0, _), (gx, gy, gz) = self.start, self.goal
        h = swing_along(s, g)
        z = swing_height(self.zs, s)
        if s >= 1.0:  # no ground yet: keep reaching down
            self.goal = (gx, gy, gz - 0.3 * dt)
            z = self.goal[2]
            if z < self.start[2] - 0.35:
                return None
        return (x0 + (gx - x0) * h, y0 + (gy - y0) * h, z)


def raibert_point(
    est, leg: int, t_left: float, twist, pitch: float, half_stance: float, g: TerrainGains
) -> tuple[float, float]:
    """The Raibert foothold (world xy) of a swing ending in ``t_left`` seconds.

    The hip where the trunk will be at touch-down, then half a stance (``half_stance``
    seconds) of the ground's motion ahead, plus a balance term on the velocity error.

    Args:
        est: The trunk state estimate (``x, y, yaw``).
        leg: The leg (0 FR, 1 FL, 2 RR, 3 RL).
        t_left: Seconds to touch-down.
        twist: ``(vx, vy, wz, ex, ey)``: the commanded twist and the velocity error.
        pitch: The trunk's reference pitch (rad).
        half_stance: Half the stance time (s).
        g: The terrain gait's gains.
    """
    vx, vy, wz, ex, ey = twist
    c, s = math.cos(est.yaw), math.sin(est.yaw)
    tx = est.x + (c * vx - s * vy) * t_left
    ty = est.y + (s * vx + c * vy) * t_left
    hx, hy = const.HIP_OFFSETS[leg]
    rx = hx * math.cos(pitch)
    ry = hy + const.LEG_SIDE[leg] * const.ABDUCTION
    ox = (vx - wz * ry) * half_stance + g.raibert_gain * ex
    oy = (vy + wz * rx) * half_stance + g.raibert_gain * ey
    yaw = est.yaw + wz * t_left
    ct, st = math.cos(yaw), math.sin(yaw)
    return (tx + ct * (rx + ox) - st * (ry + oy), ty + st * (rx + ox) + ct * (ry + oy))
