"""Orientations for bodies posed from joint positions alone ("segment mode").

Position-only motions (MDM output) have no joint rotations. Each rigid piece is then turned
so that its rest bone (joint → main child) points along the observed bone, with the smallest
rotation; the pelvis and chest also keep their left–right axis along the hips and shoulders,
so the trunk does not spin about its own axis.
"""

from __future__ import annotations

import numpy as np

from havln_mj.humans import rotations as rot
from havln_mj.humans.skeleton import JOINT, NUM_JOINTS, PARENTS

# The child each joint's piece points at (leaves keep their parent's orientation).
_MAIN_CHILD = {
    JOINT["pelvis"]: JOINT["spine1"],
    JOINT["spine3"]: JOINT["neck"],
    JOINT["left_collar"]: JOINT["left_shoulder"],
    JOINT["right_collar"]: JOINT["right_shoulder"],
}
for _j in range(1, NUM_JOINTS):
    _MAIN_CHILD.setdefault(int(PARENTS[_j]), _j)
# Trunk pieces whose sideways axis follows a pair of joints (right minus left).
_SIDEWAYS = {
    JOINT["pelvis"]: (JOINT["left_hip"], JOINT["right_hip"]),
    JOINT["spine3"]: (JOINT["left_collar"], JOINT["right_collar"]),
}


def _frame(up: np.ndarray, side: np.ndarray) -> np.ndarray:
    """Rotation matrices with z along ``up`` and x along ``side`` made orthogonal to it."""
    z = up / np.maximum(np.linalg.norm(up, axis=-1, keepdims=True), 1e-12)
    x = side - np.sum(side * z, axis=-1, keepdims=True) * z
    x = x / np.maximum(np.linalg.norm(x, axis=-1, keepdims=True), 1e-12)
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=-1)


def segment_orientations(positions: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """World orientations ``(..., 24, 4)`` of the pieces for joint positions ``(..., 24, 3)``.

    Args:
        positions: Joint positions.
        offsets: The body's rest offsets ``(24, 3)`` (bone directions at rest).
    """
    positions = np.asarray(positions, float)
    quats = rot.identity(positions.shape[:-1])
    for j in range(NUM_JOINTS):
        child = _MAIN_CHILD.get(j)
        if child is None:
            quats[..., j, :] = quats[..., PARENTS[j], :]
            continue
        bone = positions[..., child, :] - positions[..., j, :]
        if j in _SIDEWAYS:
            left, right = _SIDEWAYS[j]
            side = positions[..., right, :] - positions[..., left, :]
            rest = _frame(offsets[child], offsets[right] - offsets[left])
            now = _frame(bone, side)
            quats[..., j, :] = rot.from_matrix(now @ np.swapaxes(rest, -1, -2))
        else:
            quats[..., j, :] = rot.swing(np.broadcast_to(offsets[child], bone.shape), bone)
    return quats
