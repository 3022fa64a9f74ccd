"""Matterport frame conventions: z up, metres, heading from +y turning right, elevation up.

Heading 0 faces +y and grows turning right (toward +x), kept in [0, 2π). Elevation is the angle
above the horizontal plane. MuJoCo cameras look along their local -z with +y up, so a camera
frame here has columns (right, up, -forward).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

TWO_PI = 2.0 * math.pi


def wrap_heading(heading: float) -> float:
    """Returns ``heading`` wrapped into [0, 2π)."""
    h = math.fmod(heading, TWO_PI)
    if h < 0.0:
        h += TWO_PI
    return 0.0 if h >= TWO_PI else h


def wrap_angle(angle: float) -> float:
    """Returns ``angle`` wrapped into (-π, π]."""
    a = math.fmod(angle + math.pi, TWO_PI)
    if a <= 0.0:
        a += TWO_PI
    return a - math.pi


def forward(heading: float, elevation: float = 0.0) -> np.ndarray:
    """Returns the unit view direction for a heading and elevation (radians)."""
    ce = math.cos(elevation)
    return np.array([math.sin(heading) * ce, math.cos(heading) * ce, math.sin(elevation)])


def heading_to(src: np.ndarray, dst: np.ndarray) -> float:
    """Returns the heading in [0, 2π) that faces from ``src`` toward ``dst`` horizontally."""
    return wrap_heading(math.atan2(dst[0] - src[0], dst[1] - src[1]))


def camera_xmat(heading: float, elevation: float = 0.0) -> np.ndarray:
    """Returns the 3×3 world rotation of a MuJoCo camera (columns: right, up, -forward)."""
    f = forward(heading, elevation)
    right = np.array([math.cos(heading), -math.sin(heading), 0.0])
    up = np.cross(right, f)
    return np.column_stack([right, up, -f])


def camera_quat(heading: float, elevation: float = 0.0) -> np.ndarray:
    """Returns the MuJoCo quaternion (w, x, y, z) of ``camera_xmat(heading, elevation)``."""
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, camera_xmat(heading, elevation).ravel())
    return quat
