"""The canonical human skeleton: SMPL's 24-joint tree in our z-up frame, and its kinematics.

**Frame.** A person's body frame is z up, facing +y, with +x to their right, so a person
with heading 0 faces the world's +y like the agent. SMPL's frame (y up, facing +z, +x to the
body's left) maps to it by ``p_body = (−x, z, y)_smpl`` (:data:`SMPL_TO_BODY`, a proper
rotation).

**Pose.** As in SMPL, every joint frame is parallel to the body frame in the rest (T-)pose,
and a pose is one local rotation per joint (a unit quaternion ``w, x, y, z``) relative to
its parent, plus the pelvis position. Joint 0's rotation is the whole body's orientation.

**Proportions.** :func:`rest_offsets` places the joints from a person's height with
segment-length ratios of the public anthropometric tables (Drillis and Contini, as tabulated
by Winter, *Biomechanics and Motor Control of Human Movement*): our numbers, not SMPL's
template. Motions stay valid across heights because they are rotations.
"""

from __future__ import annotations

import numpy as np

from havln_mj.humans import rotations as rot

JOINT_NAMES = (
    "pelvis",
    "left_hip",
    "right_hip",
    "spine1",
    "left_knee",
    "right_knee",
    "spine2",
    "left_ankle",
    "right_ankle",
    "spine3",
    "left_foot",
    "right_foot",
    "neck",
    "left_collar",
    "right_collar",
    "head",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "left_hand",
    "right_hand",
)
NUM_JOINTS = len(JOINT_NAMES)
PARENTS = np.array(
    [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21]
)
JOINT = {name: k for k, name in enumerate(JOINT_NAMES)}

SMPL_TO_BODY = np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])
"""Maps SMPL-frame vectors (y up, facing +z, +x = left) to the body frame (z up, facing +y)."""
SMPL_TO_BODY_QUAT = rot.from_matrix(SMPL_TO_BODY)

MIN_HEIGHT, MAX_HEIGHT = 1.0, 1.95  # children of about 6 years up to tall adults

# Rest (T-pose) joint positions as fractions of height: (x to the right, y forward, z up),
# feet on z = 0. Heights of hip, knee, ankle, shoulder and the arm segment lengths follow the
# anthropometric ratios (hip 0.530, knee 0.285, ankle 0.039, shoulder 0.818, biacromial
# width 0.259, upper arm 0.186, forearm 0.146, hand 0.108, foot length 0.152 of height).
_REST_FRACTIONS = {
    "pelvis": (0.0, 0.0, 0.575),
    "left_hip": (-0.052, 0.0, 0.530),
    "right_hip": (0.052, 0.0, 0.530),
    "spine1": (0.0, -0.010, 0.640),
    "left_knee": (-0.055, 0.0, 0.285),
    "right_knee": (0.055, 0.0, 0.285),
    "spine2": (0.0, -0.012, 0.715),
    "left_ankle": (-0.055, -0.012, 0.039),
    "right_ankle": (0.055, -0.012, 0.039),
    "spine3": (0.0, -0.008, 0.755),
    "left_foot": (-0.060, 0.082, 0.010),
    "right_foot": (0.060, 0.082, 0.010),
    "neck": (0.0, -0.012, 0.845),
    "left_collar": (-0.045, -0.010, 0.815),
    "right_collar": (0.045, -0.010, 0.815),
    "head": (0.0, 0.0, 0.895),
    "left_shoulder": (-0.130, -0.015, 0.818),
    "right_shoulder": (0.130, -0.015, 0.818),
    "left_elbow": (-0.316, -0.015, 0.818),
    "right_elbow": (0.316, -0.015, 0.818),
    "left_wrist": (-0.462, -0.015, 0.818),
    "right_wrist": (0.462, -0.015, 0.818),
    "left_hand": (-0.516, -0.015, 0.818),
    "right_hand": (0.516, -0.015, 0.818),
}
SOLE_FRACTION = 0.0  # soles touch z = 0 in the rest pose
FOOT_HEIGHT_FRACTION = 0.039  # ankle height: the sole is this far below the ankle joint


def rest_positions(height: float) -> np.ndarray:
    """Rest-pose joint positions ``(24, 3)`` of a person ``height`` metres tall, feet at z=0."""
    return height * np.array([_REST_FRACTIONS[name] for name in JOINT_NAMES])


def rest_offsets(height: float) -> np.ndarray:
    """Each joint's rest position relative to its parent ``(24, 3)``.

    Row 0 is the pelvis's position above the point between the feet.
    """
    pos = rest_positions(height)
    off = pos.copy()
    off[1:] -= pos[PARENTS[1:]]
    return off


def offsets_from_positions(positions: np.ndarray) -> np.ndarray:
    """Parent-relative offsets ``(24, 3)`` from rest joint positions ``(24, 3)``."""
    positions = np.asarray(positions, float)
    off = positions.copy()
    off[1:] -= positions[PARENTS[1:]]
    return off


def _depth_levels() -> list[tuple[np.ndarray, np.ndarray]]:
    """``(joints, their parents)`` by depth in the tree (pelvis excluded), shallowest first."""
    depth = np.zeros(NUM_JOINTS, dtype=int)
    for j in range(1, NUM_JOINTS):
        depth[j] = depth[PARENTS[j]] + 1
    levels = [np.flatnonzero(depth == d) for d in range(1, depth.max() + 1)]
    return [(level, PARENTS[level]) for level in levels]


_LEVELS = _depth_levels()


def forward_kinematics(
    offsets: np.ndarray, local: np.ndarray, root: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """World joint positions and orientations from local rotations.

    Joints of one tree depth are computed together (8 levels for 23 joints), vectorised over
    the leading dimensions.

    Args:
        offsets: Rest offsets ``(24, 3)`` (or ``(..., 24, 3)`` per person); row 0 is ignored.
        local: Local joint rotations ``(..., 24, 4)``.
        root: Pelvis positions ``(..., 3)``.

    Returns:
        ``(positions (..., 24, 3), orientations (..., 24, 4))`` in the world frame.
    """
    local = np.asarray(local, float)
    # Homogeneous transforms: one matmul per level gives each joint's rotation and position.
    tf = np.zeros((*local.shape[:-1], 4, 4))
    tf[..., :3, :3] = rot.to_matrix(local)
    tf[..., :3, 3] = offsets
    tf[..., 3, 3] = 1.0
    tf[..., 0, :3, 3] = root
    quat = np.empty_like(local)
    quat[..., 0, :] = local[..., 0, :]
    for level, parent in _LEVELS:
        tf[..., level, :, :] = tf[..., parent, :, :] @ tf[..., level, :, :]
        quat[..., level, :] = rot.mul(quat[..., parent, :], local[..., level, :])
    return tf[..., :3, 3], quat


def smpl_to_body_rotations(local_smpl: np.ndarray) -> np.ndarray:
    """Re-expresses SMPL local rotations ``(..., 24, 4)`` in the body frame.

    SMPL's local rotations are about SMPL-frame axes (every rest frame is parallel to the
    model frame), so each is conjugated by the frame change: ``q_body = c ⊗ q ⊗ c⁻¹``.
    """
    c = SMPL_TO_BODY_QUAT
    return rot.mul(rot.mul(c, local_smpl), rot.conj(c))
