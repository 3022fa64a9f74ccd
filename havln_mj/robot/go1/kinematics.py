"""Analytic GO1 leg kinematics (scalar math: 4 legs are faster in plain Python than numpy).

A leg's frame is its hip body: at the abduction joint, axes parallel to the trunk's. The
abduction joint turns about x; the thigh joint sits ``side * ABDUCTION`` along y and turns about
y like the knee; thigh and calf are ``THIGH`` and ``CALF`` long, the foot centre at the end.
"""

from __future__ import annotations

import math

from havln_mj.robot.go1.constants import ABDUCTION, CALF, HIP_OFFSETS, LEG_SIDE, THIGH

_L = THIGH  # the IK below uses equal thigh and calf lengths, true of the GO1
assert abs(THIGH - CALF) < 1e-9
_REACH = 2 * _L - 1e-4


def leg_ik(leg: int, x: float, y: float, z: float) -> tuple[float, float, float]:
    """Joint angles (abduction, thigh, knee) that put leg ``leg``'s foot at (x, y, z).

    The point is in the hip frame; out-of-reach points are pulled onto the workspace.
    """
    side_l1 = LEG_SIDE[leg] * ABDUCTION
    r2 = y * y + z * z - ABDUCTION * ABDUCTION
    zl = -math.sqrt(r2) if r2 > 1e-6 else -1e-3
    q1 = math.atan2(z, y) - math.atan2(zl, side_l1)
    if q1 > math.pi:
        q1 -= 2 * math.pi
    elif q1 < -math.pi:
        q1 += 2 * math.pi
    d = math.sqrt(x * x + zl * zl)
    if d > _REACH:
        d = _REACH
    c = (d * d - 2 * _L * _L) / (2 * _L * _L)
    q3 = -math.acos(max(-1.0, min(1.0, c)))
    q2 = math.atan2(-x, -zl) - 0.5 * q3
    return q1, q2, q3


def leg_fk(leg: int, q1: float, q2: float, q3: float) -> tuple[float, float, float]:
    """Foot centre of leg ``leg`` in the trunk frame for joint angles (abduction, thigh, knee)."""
    x = -_L * (math.sin(q2) + math.sin(q2 + q3))
    zl = -_L * (math.cos(q2) + math.cos(q2 + q3))
    y0 = LEG_SIDE[leg] * ABDUCTION
    c, s = math.cos(q1), math.sin(q1)
    hx, hy = HIP_OFFSETS[leg]
    return hx + x, hy + c * y0 - s * zl, s * y0 + c * zl


def leg_jacobian_t(
    leg: int, q1: float, q2: float, q3: float, f: tuple[float, float, float]
) -> tuple[float, float, float]:
    """``Jᵀ f``: the joint torques whose work matches force ``f`` (trunk frame) at the foot."""
    s2, c2 = math.sin(q2), math.cos(q2)
    s23, c23 = math.sin(q2 + q3), math.cos(q2 + q3)
    x = -_L * (s2 + s23)
    zl = -_L * (c2 + c23)
    y0 = LEG_SIDE[leg] * ABDUCTION
    c, s = math.cos(q1), math.sin(q1)
    y = c * y0 - s * zl
    z = s * y0 + c * zl
    dzl2, dzl3 = -x, _L * s23
    fx, fy, fz = f
    t1 = -z * fy + y * fz
    t2 = zl * fx - s * dzl2 * fy + c * dzl2 * fz
    t3 = -_L * c23 * fx - s * dzl3 * fy + c * dzl3 * fz
    return t1, t2, t3
