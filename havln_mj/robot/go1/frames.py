"""Trunk rotations in plain floats (a 3×3 matrix as 9 row-major numbers; faster than numpy).

Angles are ZYX Euler: yaw about world z, then pitch about y (positive: nose down), then roll
about x (positive: left side up).
"""

from __future__ import annotations

import math

Vec = tuple[float, float, float]


def rotation(roll: float, pitch: float, yaw: float) -> tuple[float, ...]:
    """Row-major R = Rz(yaw) Ry(pitch) Rx(roll)."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return (
        cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,
        sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,
        -sp, cp * sr, cp * cr,
    )  # fmt: skip


def to_body(r: tuple[float, ...], v: Vec) -> Vec:
    """Rᵀ v: a world vector in the rotated frame."""
    x, y, z = v
    return (
        r[0] * x + r[3] * y + r[6] * z,
        r[1] * x + r[4] * y + r[7] * z,
        r[2] * x + r[5] * y + r[8] * z,
    )


def to_world(r: tuple[float, ...], v: Vec) -> Vec:
    """R v: a vector of the rotated frame in the world."""
    x, y, z = v
    return (
        r[0] * x + r[1] * y + r[2] * z,
        r[3] * x + r[4] * y + r[5] * z,
        r[6] * x + r[7] * y + r[8] * z,
    )


def roll_pitch(quat: tuple[float, float, float, float]) -> tuple[float, float]:
    """Roll and pitch of a (w, x, y, z) quaternion."""
    w, x, y, z = quat
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x))))
    return roll, pitch
