"""Anatomical joint angles as local rotations in the body frame, and two-bone leg IK.

The body frame is z up, facing +y, +x to the person's right (see
:mod:`havln_mj.humans.skeleton`). With the rest (T-)pose's joint frames parallel to it, the
anatomical motions are these rotations (all checked against forward kinematics in the tests):

- hip flexion (knee forward): +x; knee flexion (ankle back): −x; ankle dorsiflexion (toes
  up): +x; trunk and head flexion (bending forward): −x;
- twist to the left (counter-clockwise seen from above): +z; bending to the right: +y;
- arms: from the T-pose, the right arm hangs down after +90° about y, the left after −90°;
  shoulder flexion (arm forward) is then +x, elbow flexion about the arm's own z axis.

Every function is vectorised over leading dimensions; angles are radians.
"""

from __future__ import annotations

import numpy as np

from havln_mj.humans import rotations as rot
from havln_mj.humans.skeleton import JOINT

X_AXIS, Y_AXIS, Z_AXIS = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)
RIGHT, LEFT = 1.0, -1.0  # the side's sign along +x

# Sole contact points relative to the ankle joint, as fractions of height (the ankle is
# 0.039 h above the floor; the foot joint sits over the ball of the foot).
HEEL_FRACTION = np.array([0.0, -0.025, -0.039])
BALL_FRACTION = np.array([0.005, 0.094, -0.039])


def rx(angle: np.ndarray | float) -> np.ndarray:
    """Rotation by ``angle`` about the body x axis (lateral, pointing right)."""
    return rot.from_axis(X_AXIS, angle)


def ry(angle: np.ndarray | float) -> np.ndarray:
    """Rotation by ``angle`` about the body y axis (forward)."""
    return rot.from_axis(Y_AXIS, angle)


def rz(angle: np.ndarray | float) -> np.ndarray:
    """Rotation by ``angle`` about the body z axis (up)."""
    return rot.from_axis(Z_AXIS, angle)


def trunk(flex: np.ndarray | float = 0.0, bend: np.ndarray | float = 0.0, twist=0.0):
    """A trunk or neck rotation: forward flexion, bend to the right, twist to the left."""
    return rot.mul(rz(twist), rot.mul(ry(bend), rx(-np.asarray(flex, float))))


def arm(
    side: float,
    flex: np.ndarray | float,
    elbow: np.ndarray | float,
    abduct: np.ndarray | float = 0.14,
    across: np.ndarray | float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Shoulder and elbow local rotations of one arm.

    Args:
        side: ``RIGHT`` or ``LEFT``.
        flex: Shoulder flexion (arm forward; π/2 points it ahead, π overhead).
        elbow: Elbow flexion (0 straight).
        abduct: Angle of the hanging arm away from the body's side.
        across: Horizontal adduction (the arm swung toward the midline).

    Returns:
        ``(shoulder, elbow)`` quaternions.
    """
    hang = ry(side * (np.pi / 2 - np.asarray(abduct, float)))
    shoulder = rot.mul(rz(side * np.asarray(across, float)), rot.mul(rx(flex), hang))
    return shoulder, rz(side * np.asarray(elbow, float))


def set_arm(local: np.ndarray, side: float, *args, **kwargs) -> None:
    """Writes :func:`arm`'s shoulder and elbow rotations into ``local (..., 24, 4)``."""
    name = "right" if side > 0 else "left"
    sh, el = arm(side, *args, **kwargs)
    local[..., JOINT[f"{name}_shoulder"], :] = sh
    local[..., JOINT[f"{name}_elbow"], :] = el


def set_spine(local: np.ndarray, total: np.ndarray) -> None:
    """Spreads one trunk rotation ``total (..., 4)`` evenly over the three spine joints."""
    part = rot.slerp(rot.identity(total.shape[:-1]), total, 1.0 / 3.0)
    for name in ("spine1", "spine2", "spine3"):
        local[..., JOINT[name], :] = part


def set_neck(local: np.ndarray, total: np.ndarray) -> None:
    """Spreads one head rotation ``total (..., 4)`` over the neck and head joints."""
    part = rot.slerp(rot.identity(total.shape[:-1]), total, 0.5)
    local[..., JOINT["neck"], :] = part
    local[..., JOINT["head"], :] = part


def foot_orientation(yaw: np.ndarray | float, pitch: np.ndarray | float) -> np.ndarray:
    """World orientation of a foot turned by ``yaw`` (about +z) and pitched toes-up by ``pitch``."""
    return rot.mul(rz(yaw), rx(pitch))


def ankle_from_contact(
    height: float,
    ground: np.ndarray,
    yaw: np.ndarray,
    pitch: np.ndarray,
    lift: np.ndarray | float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Ankle position and foot orientation for a foot rolling on its heel or ball.

    The foot is described by where its ankle would be with the sole flat on the floor
    (``ground`` (..., 2)), its yaw and its pitch. A toes-up foot pivots about its heel, a
    toes-down one about its ball, so the lowest sole point stays where it is for any pitch
    and sits ``lift`` above the floor: a planted foot rolls without sliding.

    Returns:
        ``(ankle (..., 3), orientation (..., 4))``.
    """
    ground = np.asarray(ground, float)
    pitch = np.asarray(pitch, float)
    pivot_local = np.where(
        (pitch > 0)[..., None], HEEL_FRACTION * height, BALL_FRACTION * height
    )  # (..., 3) from the ankle
    flat = rz(yaw)
    q = foot_orientation(yaw, pitch)
    pivot = np.concatenate([ground, np.zeros((*ground.shape[:-1], 1))], axis=-1)
    pivot = pivot + rot.rotate(flat, pivot_local) * np.array([1.0, 1.0, 0.0])
    pivot[..., 2] = lift
    return pivot - rot.rotate(q, pivot_local), q


def sole_points(height: float, ankle: np.ndarray, foot_quat: np.ndarray) -> np.ndarray:
    """World heel and ball points ``(..., 2, 3)`` of feet with the given ankle poses."""
    pts = np.stack([HEEL_FRACTION, BALL_FRACTION]) * height
    return ankle[..., None, :] + rot.rotate(foot_quat[..., None, :], pts)


def leg_reach(offsets: np.ndarray) -> float:
    """Longest hip-to-ankle distance the leg can span (knee straight)."""
    u1, u2 = offsets[JOINT["left_knee"]], offsets[JOINT["left_ankle"]]
    return float(np.linalg.norm(u1 + u2))


def leg_ik(
    offsets: np.ndarray,
    side: float,
    hip: np.ndarray,
    parent: np.ndarray,
    ankle: np.ndarray,
    foot: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hip, knee and ankle local rotations that put the ankle at a target.

    The knee is a hinge about the thigh's x axis; the leg's swivel keeps that axis along the
    foot's lateral axis, so the knee points where the foot does.

    Args:
        offsets: Rest offsets ``(24, 3)``.
        side: ``RIGHT`` or ``LEFT``.
        hip: World hip positions ``(..., 3)``.
        parent: World orientations of the pelvis ``(..., 4)``.
        ankle: Target ankle positions ``(..., 3)`` (clamped to the leg's reach).
        foot: Target world foot orientations ``(..., 4)``.

    Returns:
        ``(hip, knee, ankle)`` local quaternions ``(..., 4)``.
    """
    name = "right" if side > 0 else "left"
    u1 = offsets[JOINT[f"{name}_knee"]]
    u2 = offsets[JOINT[f"{name}_ankle"]]
    target = np.asarray(ankle, float) - hip
    d = np.linalg.norm(target, axis=-1)
    # |u1 + Rx(θ) u2|² = l1² + l2² + 2 (c0 + A cos θ + B sin θ); solve for the knee angle θ.
    c0 = u1[0] * u2[0]
    a = u1[1] * u2[1] + u1[2] * u2[2]
    b = u1[2] * u2[1] - u1[1] * u2[2]
    r, delta = np.hypot(a, b), np.arctan2(b, a)
    cos_term = ((d**2 - u1 @ u1 - u2 @ u2) / 2 - c0) / r
    theta = delta - np.arccos(np.clip(cos_term, -1.0, 1.0))  # θ ≤ δ: the knee bends forward
    knee = rx(theta)
    leg = u1 + rot.rotate(knee, u2)  # hip-to-ankle in the thigh's rest frame
    lateral = rot.rotate(foot, np.array(X_AXIS))
    world = _align(leg, np.array(X_AXIS), target, lateral)
    hip_local = rot.mul(rot.conj(parent), world)
    ankle_local = rot.mul(rot.conj(rot.mul(world, knee)), foot)
    return hip_local, knee, ankle_local


def _frame(primary: np.ndarray, secondary: np.ndarray) -> np.ndarray:
    """Orthonormal frames ``(..., 3, 3)`` (columns) from a primary and a secondary direction."""
    a = primary / np.linalg.norm(primary, axis=-1, keepdims=True)
    b = secondary - np.sum(secondary * a, axis=-1, keepdims=True) * a
    b = b / np.linalg.norm(b, axis=-1, keepdims=True)
    return np.stack([a, b, np.cross(a, b)], axis=-1)


def _align(v_from: np.ndarray, s_from: np.ndarray, v_to: np.ndarray, s_to: np.ndarray):
    """The rotation taking ``v_from`` onto ``v_to``, ``s_from`` as near as can be to ``s_to``."""
    f0 = _frame(np.broadcast_to(v_from, np.shape(v_to)), np.broadcast_to(s_from, np.shape(v_to)))
    f1 = _frame(v_to, s_to)
    return rot.from_matrix(f1 @ np.swapaxes(f0, -1, -2))
