"""The shipped catalog of Anny bodies: how Anny's rig maps onto our skeleton, and the loader.

The catalog (``humans/anny/bodies.npz``, built by :mod:`havln_mj.humans.anny_build` from
Anny, NAVER LABS: code Apache-2.0, MakeHuman body assets CC0) holds one decimated mesh
topology shared by every body, and per body its rest vertices and the rest positions of our
24 skeleton joints, all in our body frame (z up, facing +y, +x to the right, soles on
z = 0). Anny's rest pose is an A-pose; :mod:`havln_mj.humans.anny_rig` turns it into our
T-pose convention. Skinning weights are Anny's, summed onto our 24 joints (each Anny bone
follows the joint it maps to, or its nearest mapped parent).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from havln_mj.errors import InvalidArgumentError, MalformedDataError
from havln_mj.humans.skeleton import JOINT, NUM_JOINTS
from havln_mj.paths import asset_path

POSITION_SCALE = 1.0 / 15000.0  # metres per unit of the stored int16 vertices (±2.18 m)
TEXTURE_SIZE = 512  # texels per side of a person's clothes texture

# Anny bone → our joint. Bones not listed follow their nearest listed parent.
ANNY_TO_JOINT = {
    "root": JOINT["pelvis"],
    "spine04": JOINT["spine1"],
    "spine02": JOINT["spine2"],
    "spine01": JOINT["spine3"],
    "neck01": JOINT["neck"],
    "head": JOINT["head"],
}
for _side, _s in (("left", "L"), ("right", "R")):
    ANNY_TO_JOINT.update(
        {
            f"upperleg01.{_s}": JOINT[f"{_side}_hip"],
            f"lowerleg01.{_s}": JOINT[f"{_side}_knee"],
            f"foot.{_s}": JOINT[f"{_side}_ankle"],
            f"clavicle.{_s}": JOINT[f"{_side}_collar"],
            f"upperarm01.{_s}": JOINT[f"{_side}_shoulder"],
            f"lowerarm01.{_s}": JOINT[f"{_side}_elbow"],
            f"wrist.{_s}": JOINT[f"{_side}_wrist"],
        }
    )
    for _k in range(1, 6):
        ANNY_TO_JOINT[f"toe{_k}-1.{_s}"] = JOINT[f"{_side}_foot"]
        ANNY_TO_JOINT[f"finger{_k}-1.{_s}"] = JOINT[f"{_side}_hand"]
        if _k > 1:
            ANNY_TO_JOINT[f"metacarpal{_k - 1}.{_s}"] = JOINT[f"{_side}_hand"]

# The Anny bone whose head is each joint's rest position (our joint order).
JOINT_ANCHOR_BONES = (
    "root",
    "upperleg01.L",
    "upperleg01.R",
    "spine04",
    "lowerleg01.L",
    "lowerleg01.R",
    "spine02",
    "foot.L",
    "foot.R",
    "spine01",
    "toe3-1.L",
    "toe3-1.R",
    "neck01",
    "clavicle.L",
    "clavicle.R",
    "head",
    "upperarm01.L",
    "upperarm01.R",
    "lowerarm01.L",
    "lowerarm01.R",
    "wrist.L",
    "wrist.R",
    "finger3-1.L",
    "finger3-1.R",
)


@dataclass(frozen=True)
class AnnyTopology:
    """What every catalog body shares.

    Attributes:
        faces: Triangles ``(F, 3)`` on the geometric vertices.
        joint_index: The 4 joints weighing on each vertex ``(V, 4)``.
        joint_weight: Their weights ``(V, 4)`` (rows sum to 1).
        uv: Texture coordinates ``(R, 2)`` of the render vertices (OBJ convention, v up).
        uv_vertex: The geometric vertex of each render vertex ``(R,)`` (split on UV seams).
        uv_faces: Triangles ``(F, 3)`` on the render vertices.
        texel_face: Face shown by each texel ``(S, S)`` (``int16``, −1 none), image rows top
            first.
        texel_bary: Barycentric ``(u, v)`` of each texel in that face ``(S, S, 2)``
            (``float16``).
    """

    faces: np.ndarray
    joint_index: np.ndarray
    joint_weight: np.ndarray
    uv: np.ndarray
    uv_vertex: np.ndarray
    uv_faces: np.ndarray
    texel_face: np.ndarray
    texel_bary: np.ndarray

    @property
    def num_vertices(self) -> int:
        """Geometric vertices per body."""
        return len(self.joint_index)

    def dense_weights(self) -> np.ndarray:
        """Skinning weights as a dense ``(V, 24)`` array."""
        out = np.zeros((self.num_vertices, NUM_JOINTS))
        np.put_along_axis(out, self.joint_index.astype(int), self.joint_weight, axis=1)
        return out


@dataclass(frozen=True)
class AnnyBody:
    """One catalog body at rest (A-pose), in our body frame.

    Attributes:
        id: Catalog id, e.g. ``"woman-average"``.
        vertices: Rest vertices ``(V, 3)``.
        joints: Rest positions ``(24, 3)`` of our joints.
        eyes: Rest positions ``(2, 3)`` of the left and right eye centres.
        height: Standing height (m).
        age: Anny's age parameter (0 baby, 1/3 child, 2/3 young adult, 1 old).
        female: Anny's gender parameter (0 male … 1 female).
        topology: The shared topology.
    """

    id: str
    vertices: np.ndarray
    joints: np.ndarray
    eyes: np.ndarray
    height: float
    age: float
    female: float
    topology: AnnyTopology


@dataclass(frozen=True)
class AnnyCatalog:
    """Every shipped body on its shared topology."""

    topology: AnnyTopology
    bodies: tuple[AnnyBody, ...]

    def __len__(self) -> int:
        return len(self.bodies)

    @property
    def ids(self) -> list[str]:
        """Body ids in catalog order."""
        return [b.id for b in self.bodies]

    def get(self, body_id: str) -> AnnyBody:
        """The body called ``body_id``.

        Raises:
            InvalidArgumentError: No such body (the message lists them).
        """
        for body in self.bodies:
            if body.id == body_id:
                return body
        raise InvalidArgumentError(f"unknown Anny body {body_id!r}; valid: {', '.join(self.ids)}")


@lru_cache(maxsize=1)
def load_anny_catalog() -> AnnyCatalog:
    """The shipped catalog (read once per process; arrays are read-only).

    Raises:
        MissingDataError: ``humans/anny/bodies.npz`` is absent.
        MalformedDataError: It lacks an array or its arrays do not fit together.
    """
    path = asset_path("humans", "anny", "bodies.npz")
    meta = json.loads(asset_path("humans", "anny", "bodies.json").read_text())
    try:
        with np.load(path) as npz:
            a = {k: npz[k] for k in npz.files}
        topology = AnnyTopology(
            faces=a["faces"].astype(np.int32),
            joint_index=a["joint_index"].astype(np.intp),
            joint_weight=a["joint_weight"].astype(float),
            uv=a["uv"].astype(float),
            uv_vertex=a["uv_vertex"].astype(np.intp),
            uv_faces=a["uv_faces"].astype(np.int32),
            # Kept as stored (int16, float16: 1.5 MB less for the life of the process); the
            # painter reads them as indices and float64 weights, exactly as wider copies.
            texel_face=a["texel_face"],
            texel_bary=a["texel_bary"],
        )
        rest = a["rest"].astype(float) * POSITION_SCALE
        entries = meta["bodies"]
        if len(entries) != len(rest) or rest.shape[1] != topology.num_vertices:
            raise MalformedDataError(
                f"{path}: {len(rest)} bodies of {rest.shape[1]} vertices, but bodies.json "
                f"lists {len(entries)} and the topology has {topology.num_vertices}"
            )
        bodies = tuple(
            AnnyBody(
                id=e["id"],
                vertices=_frozen(rest[k]),
                joints=_frozen(a["joints"][k].astype(float)),
                eyes=_frozen(a["eyes"][k].astype(float)),
                height=float(e["height_m"]),
                age=float(e["age"]),
                female=float(e["gender"]),
                topology=topology,
            )
            for k, e in enumerate(entries)
        )
    except KeyError as exc:
        raise MalformedDataError(f"{path}: missing {exc} (rebuild with anny_build)") from None
    return AnnyCatalog(topology, bodies)


def _frozen(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a
