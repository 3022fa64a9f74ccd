"""The ground forces a statically walking GO1 asks of its stance feet.

:func:`distribute` shares a wanted force and moment on the trunk among the feet on the
ground (least squares, each foot pushing at least ``F_MIN`` and within its friction cone);
:func:`support_margin` and :func:`support_target` place the centre of mass inside the
triangle of three stance feet, as a statically stable crawl must before it lifts the fourth.
"""

from __future__ import annotations

import math

import numpy as np

F_MIN = 5.0  # N: the least push of a stance foot (it stays on the ground)
_MOMENT_WEIGHT = 5.0  # the moment rows weigh this much more than the force rows


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def distribute(
    force: np.ndarray, moment: np.ndarray, com: np.ndarray, feet: dict[int, np.ndarray], mu: float
) -> dict[int, np.ndarray]:
    """World forces of the ground on the stance feet that best give ``force`` and ``moment``.

    A foot asked to pull (less than ``F_MIN`` up) is set to ``F_MIN`` straight up and the
    others share the rest; horizontal parts are cut to ``mu`` times the vertical one.

    Args:
        force: Wanted net force on the robot (N, world frame), weight included.
        moment: Wanted net moment about the centre of mass (N·m, world frame).
        com: The centre of mass (world).
        feet: Stance feet: leg index to foot position (world).
        mu: Friction coefficient the forces keep within.
    """
    weights = np.array([1.0, 1.0, 1.0, _MOMENT_WEIGHT, _MOMENT_WEIGHT, _MOMENT_WEIGHT])
    want = np.concatenate([force, moment])
    active = list(feet)
    out: dict[int, np.ndarray] = {}
    while active:
        a = np.zeros((6, 3 * len(active)))
        for j, leg in enumerate(active):
            a[0:3, 3 * j : 3 * j + 3] = np.eye(3)
            a[3:6, 3 * j : 3 * j + 3] = _skew(feet[leg] - com)
        aw = a * weights[:, None]
        f = np.linalg.solve(aw.T @ aw + 1e-3 * np.eye(a.shape[1]), aw.T @ (want * weights))
        low = [leg for j, leg in enumerate(active) if f[3 * j + 2] < F_MIN]
        if not low or len(active) == 1:
            out.update({leg: f[3 * j : 3 * j + 3].copy() for j, leg in enumerate(active)})
            break
        for leg in low:
            out[leg] = np.array([0.0, 0.0, F_MIN])
            want = want - np.concatenate([out[leg], np.cross(feet[leg] - com, out[leg])])
            active.remove(leg)
    for f in out.values():
        f[2] = max(f[2], F_MIN)
        side = math.hypot(f[0], f[1])
        if side > mu * f[2]:
            f[:2] *= mu * f[2] / side
    return out


def support_margin(point: np.ndarray, triangle: np.ndarray) -> float:
    """Distance (m) of ``point`` inside the triangle's edges (negative outside); xy only."""
    a, b, c = triangle[:, :2]
    area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    sign = 1.0 if area > 0 else -1.0
    out = math.inf
    for u, v in ((a, b), (b, c), (c, a)):
        e = v - u
        cross = e[0] * (point[1] - u[1]) - e[1] * (point[0] - u[0])
        out = min(out, sign * cross / max(math.hypot(e[0], e[1]), 1e-9))
    return out


def support_target(triangle: np.ndarray, ahead: np.ndarray, margin: float) -> np.ndarray:
    """A centre-of-mass goal in a support triangle: its centroid moved by ``ahead``.

    The move is halved until the goal lies ``margin`` inside the triangle's edges.
    """
    c = triangle.mean(axis=0)
    p = c + ahead
    for _ in range(12):
        if support_margin(p, triangle) >= margin:
            break
        p = 0.5 * (p + c)
    return p
