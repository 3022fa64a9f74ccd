"""Quaternion and rotation helpers, vectorised over any leading dimensions.

Quaternions are ``(..., 4)`` arrays ``(w, x, y, z)`` (MuJoCo's order), unit length; rotation
matrices are ``(..., 3, 3)`` acting on column vectors.
"""

from __future__ import annotations

import numpy as np

_EPS = 1e-12


def normalize(q: np.ndarray) -> np.ndarray:
    """Unit quaternions (the zero quaternion becomes the identity)."""
    q = np.asarray(q, dtype=float)
    n = np.linalg.norm(q, axis=-1, keepdims=True)
    ident = np.zeros_like(q)
    ident[..., 0] = 1.0
    return np.where(n > _EPS, q / np.maximum(n, _EPS), ident)


def identity(shape: tuple[int, ...] = ()) -> np.ndarray:
    """Identity quaternions of the given leading shape."""
    q = np.zeros((*shape, 4))
    q[..., 0] = 1.0
    return q


def _hamilton_table() -> np.ndarray:
    """``T`` with ``(a ⊗ b)_i = Σ_jk T[i, j, k] a_j b_k``."""
    t = np.zeros((4, 4, 4))
    for (j, k), (i, sign) in {
        (0, 0): (0, 1), (0, 1): (1, 1), (0, 2): (2, 1), (0, 3): (3, 1),
        (1, 0): (1, 1), (1, 1): (0, -1), (1, 2): (3, 1), (1, 3): (2, -1),
        (2, 0): (2, 1), (2, 1): (3, -1), (2, 2): (0, -1), (2, 3): (1, 1),
        (3, 0): (3, 1), (3, 1): (2, 1), (3, 2): (1, -1), (3, 3): (0, -1),
    }.items():  # fmt: skip
        t[i, j, k] = sign
    return t


_HAMILTON = _hamilton_table()
_HAMILTON_FLAT = _HAMILTON.reshape(4, 16).T.copy()
_LEVI_CIVITA = np.zeros((3, 3, 3))
for _i, _j, _k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
    _LEVI_CIVITA[_i, _j, _k], _LEVI_CIVITA[_i, _k, _j] = 1.0, -1.0


def mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product ``a ⊗ b`` (rotate by ``b``, then by ``a``)."""
    # An outer product and one matmul beat sixteen small array products by far.
    a, b = np.asarray(a, float), np.asarray(b, float)
    outer = (a[..., :, None] * b[..., None, :]).reshape(
        *np.broadcast_shapes(a.shape, b.shape)[:-1], 16
    )
    return outer @ _HAMILTON_FLAT


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ijk,...j,...k->...i", _LEVI_CIVITA, a, b)


def conj(q: np.ndarray) -> np.ndarray:
    """The inverse of unit quaternions."""
    return np.asarray(q, float) * np.array([1.0, -1.0, -1.0, -1.0])


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotates vectors ``v (..., 3)`` by quaternions ``q (..., 4)``."""
    q = np.asarray(q, float)
    v = np.asarray(v, float)
    w, u = q[..., :1], q[..., 1:]
    t = 2.0 * _cross(u, v)
    return v + w * t + _cross(u, t)


def from_axis_angle(aa: np.ndarray) -> np.ndarray:
    """Quaternions from axis-angle (Rodrigues) vectors ``(..., 3)``."""
    aa = np.asarray(aa, float)
    angle = np.linalg.norm(aa, axis=-1, keepdims=True)
    half = 0.5 * angle
    # sin(θ/2)/θ → 1/2 as θ → 0.
    k = np.where(angle > 1e-8, np.sin(half) / np.maximum(angle, 1e-8), 0.5 - angle**2 / 48.0)
    return np.concatenate([np.cos(half), aa * k], axis=-1)


def to_axis_angle(q: np.ndarray) -> np.ndarray:
    """Axis-angle vectors ``(..., 3)`` of quaternions, angles in [0, π]."""
    q = normalize(q)
    q = np.where(q[..., :1] < 0, -q, q)  # the short way round
    s = np.linalg.norm(q[..., 1:], axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(s, q[..., :1])
    k = np.where(s > 1e-8, angle / np.maximum(s, 1e-8), 2.0)
    return q[..., 1:] * k


def from_axis(axis: np.ndarray | tuple, angle: np.ndarray | float) -> np.ndarray:
    """Quaternions of rotations by ``angle`` (any shape) about one unit ``axis``."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    half = 0.5 * np.asarray(angle, float)[..., None]
    return np.concatenate([np.cos(half), np.sin(half) * axis], axis=-1)


def _matrix_table() -> np.ndarray:
    """``C`` with ``R_ij = Σ_kl C[i, j, k, l] q_k q_l`` for unit ``q`` (homogeneous form)."""
    c = np.zeros((3, 3, 4, 4))
    w, x, y, z = range(4)
    for (i, j), terms in {
        (0, 0): ((w, w, 1), (x, x, 1), (y, y, -1), (z, z, -1)),
        (1, 1): ((w, w, 1), (x, x, -1), (y, y, 1), (z, z, -1)),
        (2, 2): ((w, w, 1), (x, x, -1), (y, y, -1), (z, z, 1)),
        (0, 1): ((x, y, 2), (w, z, -2)),
        (1, 0): ((x, y, 2), (w, z, 2)),
        (0, 2): ((x, z, 2), (w, y, 2)),
        (2, 0): ((x, z, 2), (w, y, -2)),
        (1, 2): ((y, z, 2), (w, x, -2)),
        (2, 1): ((y, z, 2), (w, x, 2)),
    }.items():
        for k, m, v in terms:
            c[i, j, k, m] = v
    return c


_MATRIX_FLAT = _matrix_table().reshape(9, 16).T.copy()


def to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` of (not necessarily unit) quaternions."""
    q = np.asarray(q, float)
    # The quadratic form divided by |q|² is the rotation of q / |q|: one matmul, no stacking.
    outer = (q[..., :, None] * q[..., None, :]).reshape(*q.shape[:-1], 16)
    m = (outer @ _MATRIX_FLAT) / np.sum(q * q, axis=-1, keepdims=True)
    return m.reshape(*q.shape[:-1], 3, 3)


def from_matrix(m: np.ndarray) -> np.ndarray:
    """Quaternions (w ≥ 0) of rotation matrices ``(..., 3, 3)``."""
    m = np.asarray(m, float)
    m00, m11, m22 = m[..., 0, 0], m[..., 1, 1], m[..., 2, 2]
    # Four candidate formulas; each is stable where its diagonal term is largest.
    cands = np.stack(
        [
            np.stack(
                [
                    1 + m00 + m11 + m22,
                    m[..., 2, 1] - m[..., 1, 2],
                    m[..., 0, 2] - m[..., 2, 0],
                    m[..., 1, 0] - m[..., 0, 1],
                ],
                -1,
            ),
            np.stack(
                [
                    m[..., 2, 1] - m[..., 1, 2],
                    1 + m00 - m11 - m22,
                    m[..., 0, 1] + m[..., 1, 0],
                    m[..., 0, 2] + m[..., 2, 0],
                ],
                -1,
            ),
            np.stack(
                [
                    m[..., 0, 2] - m[..., 2, 0],
                    m[..., 0, 1] + m[..., 1, 0],
                    1 - m00 + m11 - m22,
                    m[..., 1, 2] + m[..., 2, 1],
                ],
                -1,
            ),
            np.stack(
                [
                    m[..., 1, 0] - m[..., 0, 1],
                    m[..., 0, 2] + m[..., 2, 0],
                    m[..., 1, 2] + m[..., 2, 1],
                    1 - m00 - m11 + m22,
                ],
                -1,
            ),
        ],
        axis=-2,
    )  # (..., 4, 4)
    best = np.argmax(np.stack([m00 + m11 + m22, m00, m11, m22], -1), axis=-1)
    q = np.take_along_axis(cands, best[..., None, None], axis=-2)[..., 0, :]
    q = normalize(q)
    return np.where(q[..., :1] < 0, -q, q)


def from_rot6d(r6: np.ndarray) -> np.ndarray:
    """Quaternions from the 6-D rotation representation ``(..., 6)``.

    The six numbers are the first two *rows* of the rotation matrix (the convention of
    PyTorch3D's ``matrix_to_rotation_6d``, used by MDM and HAPS); Gram–Schmidt makes them
    orthonormal and the third row is their cross product.
    """
    r6 = np.asarray(r6, float)
    a1, a2 = r6[..., :3], r6[..., 3:]
    b1 = a1 / np.maximum(np.linalg.norm(a1, axis=-1, keepdims=True), _EPS)
    a2 = a2 - np.sum(b1 * a2, axis=-1, keepdims=True) * b1
    b2 = a2 / np.maximum(np.linalg.norm(a2, axis=-1, keepdims=True), _EPS)
    b3 = np.cross(b1, b2)
    return from_matrix(np.stack([b1, b2, b3], axis=-2))


def slerp(q0: np.ndarray, q1: np.ndarray, t: np.ndarray | float) -> np.ndarray:
    """Spherical interpolation from ``q0`` to ``q1`` at fractions ``t`` (broadcast over ``...``)."""
    q0, q1 = normalize(q0), normalize(q1)
    t = np.asarray(t, float)[..., None]
    dot = np.sum(q0 * q1, axis=-1, keepdims=True)
    q1 = np.where(dot < 0, -q1, q1)  # the short way round
    dot = np.abs(dot)
    theta = np.arccos(np.clip(dot, -1.0, 1.0))
    sin = np.sin(theta)
    near = sin < 1e-6
    w0 = np.where(near, 1.0 - t, np.sin((1.0 - t) * theta) / np.where(near, 1.0, sin))
    w1 = np.where(near, t, np.sin(t * theta) / np.where(near, 1.0, sin))
    return normalize(w0 * q0 + w1 * q1)


def nlerp(q0: np.ndarray, q1: np.ndarray, t: np.ndarray | float) -> np.ndarray:
    """Normalised linear interpolation from ``q0`` to ``q1``, the short way round.

    Slerp's path at a fraction of the cost: within 0.1° of it for rotations less than 20°
    apart, as neighbouring frames of a clip are.
    """
    q0, q1 = np.asarray(q0, float), np.asarray(q1, float)
    t = np.asarray(t, float)[..., None]
    q1 = np.where(np.sum(q0 * q1, axis=-1, keepdims=True) < 0, -q1, q1)
    q = q0 + t * (q1 - q0)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def yaw(angle: np.ndarray | float) -> np.ndarray:
    """Quaternions of rotations by ``angle`` about +z (counter-clockwise seen from above)."""
    return from_axis((0.0, 0.0, 1.0), angle)


def from_heading(heading: np.ndarray | float) -> np.ndarray:
    """The body orientation of a person facing ``heading`` (from +y, turning right)."""
    return yaw(-np.asarray(heading, float))


def swing(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Smallest rotations taking directions ``a`` to ``b`` (``(..., 3)`` each)."""
    a = a / np.maximum(np.linalg.norm(a, axis=-1, keepdims=True), _EPS)
    b = b / np.maximum(np.linalg.norm(b, axis=-1, keepdims=True), _EPS)
    w = 1.0 + np.sum(a * b, axis=-1, keepdims=True)
    q = np.concatenate([w, np.cross(a, b)], axis=-1)
    # Opposite directions: turn half a circle about any axis normal to a.
    opposite = w[..., 0] < 1e-9
    if np.any(opposite):
        normal = np.cross(a, [1.0, 0.0, 0.0])
        small = np.linalg.norm(normal, axis=-1) < 1e-6
        normal[small] = np.cross(a[small], [0.0, 1.0, 0.0])
        q[opposite] = np.concatenate([np.zeros_like(w), normal], axis=-1)[opposite]
    return normalize(q)
