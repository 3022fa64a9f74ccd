"""Where a swing foot lands on scanned ground and how high it flies on the way.

Both read the ground through ``ground(x, y)``: the height of the terrain at a world point
(:class:`~havln_mj.robot.go1.height_scan.HeightScan`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable

from havln_mj.robot.go1 import constants as const
from havln_mj.robot.go1.actuation import clip_joints
from havln_mj.robot.go1.frames import rotation, to_body
from havln_mj.robot.go1.gains import TerrainGains
from havln_mj.robot.go1.gait import smoothstep
from havln_mj.robot.go1.kinematics import leg_ik

Ground = Callable[[float, float], float]
SAMPLE = 0.02  # metres between ground samples along a line
PROFILE = 20  # a swing's height profile has PROFILE + 1 samples
NEAR = tuple(-0.3 + 0.04 * k for k in range(24))  # ground that makes the trunk's rough (m)


def is_rough(ground: Ground, x: float, y: float, c: float, s: float, ahead, jump: float) -> bool:
    """Whether the ground along (c, s) at distances ``ahead`` has an edge or climbs 0.1 m.

    Obstacles (``inf`` ground) are no terrain: they are left out.
    """
    hs = [h for h in (ground(x + c * d, y + s * d) for d in ahead) if h < math.inf]
    if not hs:
        return False
    if any(abs(b - a) > jump for a, b in itertools.pairwise(hs)):
        return True
    return max(hs) - min(hs) > 0.1


def foothold(
    ground: Ground, x: float, y: float, ux: float, uy: float, g: TerrainGains
) -> tuple[float, float]:
    """A foothold near (x, y) along the unit direction (ux, uy), clear of edges.

    The ground along the line is cut into flat pieces at its edges. A foothold keeps
    ``edge_margin`` from a riser rising beside it (the toe clears it) and ``drop_margin``
    from a drop (the foot stays on its tread, the shin above the nosing). On a piece shorter
    than ``tread_max`` (a stair's tread) the foot lands in its middle, on a longer one at the
    point nearest (x, y) with those margins; of all pieces, the foothold nearest (x, y). Where
    none lies within ``foothold_shift``, (x, y) itself.
    """
    n = round((g.foothold_shift + g.tread_max) / SAMPLE)
    hs = [ground(x + ux * k * SAMPLE, y + uy * k * SAMPLE) for k in range(-n, n + 1)]
    if max(hs) - min(hs) <= g.edge_jump:  # flat (an obstacle makes this inf)
        return x, y
    cuts = [k for k in range(2 * n) if abs(hs[k + 1] - hs[k]) > g.edge_jump]
    best, best_d = None, math.inf
    lo = 0
    for hi in [*cuts, 2 * n]:  # samples lo..hi are one flat piece
        start = (lo - n - 0.5) * SAMPLE if lo > 0 else -math.inf
        end = (hi - n + 0.5) * SAMPLE if hi < 2 * n else math.inf
        if lo > 0:
            start += g.edge_margin if hs[lo - 1] > hs[lo] else g.drop_margin
        if hi < 2 * n:
            end -= g.edge_margin if hs[hi + 1] > hs[hi] else g.drop_margin
        if start <= end and hs[lo] < math.inf:  # no foothold on an obstacle
            short = end - start < g.tread_max - g.edge_margin - g.drop_margin
            at = 0.5 * (start + end) if short else min(max(0.0, start), end)
            if abs(at) < best_d:
                best, best_d = at, abs(at)
        lo = hi + 1
    if best is None or best_d > g.foothold_shift:
        return x, y
    return x + ux * best, y + uy * best


def swing_heights(
    ground: Ground,
    start: tuple[float, float, float],
    goal: tuple[float, float, float],
    g: TerrainGains,
) -> list[float]:
    """Foot-centre heights at ``PROFILE + 1`` even swing phases from ``start`` to ``goal``.

    The foot lifts ``min_lift`` while it leaves, keeps ``clearance`` above the highest ground
    (obstacles aside) within ``edge_margin`` of where it is while it travels (``swing_start``
    to ``swing_end`` of the swing, see :func:`swing_along`), then comes down on the goal. It
    climbs or drops no faster than ``swing_rate`` per unit of phase, rising early enough for
    what lies ahead.
    """
    (x0, y0, z0), (gx, gy, gz) = start, goal
    dx, dy = gx - x0, gy - y0
    length = math.hypot(dx, dy)
    ux, uy = (dx / length, dy / length) if length > 1e-6 else (0.0, 0.0)
    step = 0.01
    a = round(g.edge_margin / step)
    n = int(length / step) + 1
    tops = [
        ground(x0 + ux * k * step, y0 + uy * k * step) + const.FOOT_RADIUS
        for k in range(-a, n + a + 1)
    ]
    m0, m1 = g.swing_start, g.swing_end
    zs = []
    for i in range(PROFILE + 1):
        si = i / PROFILE
        if si <= m0:
            zs.append(z0 + g.min_lift * smoothstep(si / m0))
        elif si >= m1:
            zs.append(gz + g.min_lift * (1.0 - smoothstep((si - m1) / (1.0 - m1))))
        else:
            k = round(length * swing_along(si, g) / step) + a
            near = [t for t in tops[max(0, k - a) : k + a + 1] if t < math.inf]
            zs.append(max(near, default=max(z0, gz)) + g.clearance)
    rate = g.swing_rate / PROFILE
    for i in range(PROFILE - 1, 0, -1):  # rise early enough
        zs[i] = max(zs[i], zs[i + 1] - rate)
    for i in range(1, PROFILE):  # drop no faster
        zs[i] = max(zs[i], zs[i - 1] - rate)
    zs[0], zs[PROFILE] = z0, gz
    return zs


def swing_along(s: float, g: TerrainGains) -> float:
    """Fraction of the way from lift-off to foothold a swing foot is at phase ``s``."""
    return smoothstep((s - g.swing_start) / (g.swing_end - g.swing_start))


def swing_height(zs: list[float], s: float) -> float:
    """The profile ``zs`` of :func:`swing_heights` at phase ``s`` (linear between samples)."""
    f = min(max(s, 0.0), 1.0) * PROFILE
    i = min(int(f), PROFILE - 1)
    return zs[i] + (zs[i + 1] - zs[i]) * (f - i)


def standing_pose(
    ground: Ground, x: float, y: float, yaw: float, top: float, g: TerrainGains
) -> tuple[float, float, list[float]]:
    """Trunk height, pitch and 12 joint angles standing at (x, y) with feet on the ground.

    Each foot stands on a foothold under its hip, the trunk level with the line through them
    at the standing height, so the robot can be placed on a stair or a ramp. ``top`` is the
    trunk's height, used where the ground is unknown.
    """
    c, s = math.cos(yaw), math.sin(yaw)
    feet = []
    for leg in range(4):
        hx, hy = const.HIP_OFFSETS[leg]
        ry = hy + const.LEG_SIDE[leg] * const.ABDUCTION
        fx, fy = foothold(ground, x + c * hx - s * ry, y + s * hx + c * ry, c, s, g)
        fz = ground(fx, fy)
        fz = fz if math.isfinite(fz) else top - g.flat_height
        feet.append((fx, fy, fz + const.FOOT_RADIUS - g.touchdown_depth))
    front = 0.5 * (feet[0][2] + feet[1][2])
    rear = 0.5 * (feet[2][2] + feet[3][2])
    pitch = -math.atan2(front - rear, 2.0 * const.HIP_X)
    stand = g.rough_height if is_rough(ground, x, y, c, s, NEAR, g.edge_jump) else g.flat_height
    z = 0.5 * (front + rear) - const.FOOT_RADIUS + g.touchdown_depth + stand
    rot = rotation(0.0, pitch, yaw)
    q: list[float] = []
    for leg, f in enumerate(feet):
        hx, hy = const.HIP_OFFSETS[leg]
        b = to_body(rot, (f[0] - x, f[1] - y, f[2] - z))
        q.extend(clip_joints(leg_ik(leg, b[0] - hx, b[1] - hy, b[2])))
    return z, pitch, q
