"""Driving an Anny body with our skeleton's poses: rest correction, skinning, rigid pieces.

Motions are joint rotations relative to our rest T-pose (every joint frame parallel to the
body frame). Anny's rest is an A-pose, so each limb joint ``j`` gets a fixed **rest
correction** ``C_j``: the smallest world rotation turning its Anny bone (its rest position
to its main child's) onto our rest bone direction. Trunk, neck and head keep Anny's natural
posture (``C = I``); hands and feet follow their wrist and ankle. The corrected joints give
the person's own rest **offsets** (Anny's bone lengths in our T-pose), which the crowd's
forward kinematics uses, so a posed joint ``j`` at world position ``X_j`` and orientation
``W_j`` moves the body's rest vertices rigidly by ``v ↦ W_j C_j (v − a_j) + X_j`` (``a_j``:
the joint's Anny rest position). Linear blend skinning mixes those 24 transforms with the
vertex weights; the rigid pieces (:func:`rigid_pieces`) carry one transform each.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from havln_mj.humans import rotations as rot
from havln_mj.humans.anny_data import AnnyBody
from havln_mj.humans.skeleton import (
    JOINT,
    MAX_HEIGHT,
    MIN_HEIGHT,
    NUM_JOINTS,
    PARENTS,
    rest_offsets,
)

PELVIS_HEIGHT_FRACTION = 0.57  # our clips stand the pelvis this high (knees soft), × height
OVERLAP_WEIGHT = 0.45
"""A rigid piece also keeps the faces bound this much (skinning weight) to its joint."""

# Limb joints corrected to our rest bone, by the child their bone points at.
_LIMB_CHILD = {}
for _side in ("left", "right"):
    _LIMB_CHILD.update(
        {
            JOINT[f"{_side}_hip"]: JOINT[f"{_side}_knee"],
            JOINT[f"{_side}_knee"]: JOINT[f"{_side}_ankle"],
            JOINT[f"{_side}_ankle"]: JOINT[f"{_side}_foot"],
            JOINT[f"{_side}_collar"]: JOINT[f"{_side}_shoulder"],
            JOINT[f"{_side}_shoulder"]: JOINT[f"{_side}_elbow"],
            JOINT[f"{_side}_elbow"]: JOINT[f"{_side}_wrist"],
            JOINT[f"{_side}_wrist"]: JOINT[f"{_side}_hand"],
        }
    )
_LEAF_FOLLOWS = {
    JOINT[f"{s}_{leaf}"]: JOINT[f"{s}_{parent}"]
    for s in ("left", "right")
    for leaf, parent in (("foot", "ankle"), ("hand", "wrist"))
}


@dataclass(frozen=True)
class AnnyRig:
    """An Anny body fitted to our skeleton.

    Attributes:
        body: The catalog body.
        correction: Rest corrections ``C_j`` ``(24, 4)`` (world quaternions).
    """

    body: AnnyBody
    correction: np.ndarray

    @property
    def anchors(self) -> np.ndarray:
        """Anny rest positions of our joints ``(24, 3)``."""
        return self.body.joints

    @cached_property
    def offsets(self) -> np.ndarray:
        """The body's rest offsets ``(24, 3)`` in our T-pose (row 0: pelvis above the soles)."""
        a, c = self.anchors, self.correction
        tpose = np.empty_like(a)
        tpose[0] = a[0]
        for j in range(1, NUM_JOINTS):
            p = PARENTS[j]
            tpose[j] = tpose[p] + rot.rotate(c[p], a[j] - a[p])
        off = tpose.copy()
        off[1:] -= tpose[PARENTS[1:]]
        off[0] = (0.0, 0.0, a[0, 2])
        return off

    @property
    def clip_height(self) -> float:
        """The height our motion recipes are given, so the clip's pelvis height fits the legs."""
        return float(np.clip(self.anchors[0, 2] / PELVIS_HEIGHT_FRACTION, MIN_HEIGHT, MAX_HEIGHT))

    def transforms(self, positions: np.ndarray, quats: np.ndarray) -> tuple[np.ndarray, ...]:
        """Per-joint rigid transforms ``(R (..., 24, 3, 3), t (..., 24, 3))`` of a pose.

        Args:
            positions: World joint positions ``(..., 24, 3)``.
            quats: World joint orientations ``(..., 24, 4)`` (relative to our T-pose).
        """
        r = rot.to_matrix(rot.mul(quats, self.correction))
        t = positions - np.einsum("...jab,jb->...ja", r, self.anchors)
        return r, t

    def skin(
        self,
        positions: np.ndarray,
        quats: np.ndarray,
        rest: np.ndarray | None = None,
        index: np.ndarray | None = None,
        weight: np.ndarray | None = None,
    ) -> np.ndarray:
        """Posed vertices ``(V, 3)`` by linear blend skinning of one pose.

        Args:
            positions: World joint positions ``(24, 3)``.
            quats: World joint orientations ``(24, 4)``.
            rest: Rest vertices (default: the body's).
            index: The 4 joints of each vertex ``(V, 4)`` (default: the topology's).
            weight: Their weights ``(V, 4)`` (default: the topology's).
        """
        topo = self.body.topology
        rest = self.body.vertices if rest is None else rest
        index = topo.joint_index if index is None else index
        weight = topo.joint_weight if weight is None else weight
        r, t = self.transforms(positions, quats)
        # Blend the four 3×4 transforms of each vertex, then apply the blend once.
        m = np.concatenate([r, t[:, :, None]], axis=2)  # (24, 3, 4)
        blend = np.einsum("vk,vkab->vab", weight, m[index])
        return np.einsum("vab,vb->va", blend[:, :, :3], rest) + blend[:, :, 3]


def fit(body: AnnyBody) -> AnnyRig:
    """Fits ``body`` to our skeleton (its rest corrections)."""
    ours = rest_offsets(1.0)
    corr = rot.identity((NUM_JOINTS,))
    a = body.joints
    for j, child in _LIMB_CHILD.items():
        corr[j] = rot.swing(a[child] - a[j], ours[child])
    for leaf, parent in _LEAF_FOLLOWS.items():
        corr[leaf] = corr[parent]
    return AnnyRig(body, corr)


@dataclass(frozen=True)
class Piece:
    """One joint's rigid piece of the mesh.

    Attributes:
        joint: The joint carrying it.
        faces: Its triangles, indices into the topology's render vertices ``(F, 3)``.
    """

    joint: int
    faces: np.ndarray


def rigid_pieces(weights: np.ndarray, faces: np.ndarray) -> list[Piece]:
    """Splits a mesh into one piece per joint, overlapping where joints blend.

    A face belongs to the joint with most weight over its corners, and also to every joint
    that binds one of its corners by at least :data:`OVERLAP_WEIGHT`: when a joint bends, the
    overlap closes the crease instead of opening a gap.

    Args:
        weights: Per geometric vertex, dense joint weights ``(V, 24)``.
        faces: Triangles on those vertices ``(F, 3)``.

    Returns:
        Pieces of joints that carry faces, with face indices into ``faces``.
    """
    corner = weights[faces]  # (F, 3, 24)
    owner = corner.sum(axis=1).argmax(axis=1)
    binds = corner.max(axis=1) >= OVERLAP_WEIGHT
    out = []
    for j in range(NUM_JOINTS):
        keep = np.flatnonzero((owner == j) | binds[:, j])
        if len(keep):
            out.append(Piece(j, keep))
    return out
