"""Semantic and instance segmentation: per-geom labels and a camera's segmentation pass.

Labels are set when a world is built; the pass renders them for any camera.

**Classes** are Matterport's mpcat40 indices 0..41 (0 ``void``: nothing labelled there) plus
:data:`~havln_mj.scene.matterport.categories.PERSON` = 42 for people
(:data:`~havln_mj.scene.matterport.categories.CLASS_NAMES` names them all).

**Instances** are ids stable for the life of a model: a building's objects are 1..N (their
ids in the scan's labels), person ``k`` is :data:`PERSON_INSTANCE_BASE` + k, and 0 means
none (nothing, or an unlabelled surface).

**Where labels live.** Each geom's (class, instance) is its user data
(``model.geom_user[:, 0:2]``). A building's labels are drawn by *label geoms*: one untextured
mesh per object instance in geom group :data:`LABELS`, which RGB cameras leave out (the
visual mesh is drawn merged per material, few geoms being fastest to render). People's geoms
(group ``HUMANS``) are labelled in place. The segmentation pass draws the label geoms, the
people and the robot; a model without label geoms (a scan with no labels) draws its visual
geoms instead, all class 0, so people are still cut out by the walls in front of them.

Build: :func:`add_label_meshes` then :func:`label_people` on the ``MjSpec`` before compiling
(``havln_mj.sim.world.build_world`` does both). Render: :func:`render_labels` after the
frame's kinematics, like ``Camera.render``.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass

import mujoco
import numpy as np

from havln_mj import groups
from havln_mj.render.camera import Camera
from havln_mj.scene.matterport.categories import MPCAT40_COLOURS, PERSON, LabelMesh

LABELS = groups.LABELS
"""Geom group of the label geoms (hidden from RGB cameras, drawn by the segmentation pass)."""

PERSON_INSTANCE_BASE = 1 << 16
"""Instance id of person 0; person ``k`` is this plus ``k``."""

_PERSON_BODY = re.compile(r"human(\d+)/")


@dataclass(frozen=True)
class Segmentation:
    """Per-pixel labels of one view (top row first).

    Attributes:
        semantic: H×W ``uint8`` class (mpcat40 index, 42 person, 0 where nothing is labelled).
        instance: H×W ``int32`` instance id (0 where none).
    """

    semantic: np.ndarray
    instance: np.ndarray


def add_label_meshes(spec: mujoco.MjSpec, meshes: Iterable[LabelMesh]) -> int:
    """Adds one label geom per mesh (group :data:`LABELS`, no contacts); returns how many."""
    spec.nuser_geom = 2
    added = 0
    for k, mesh in enumerate(meshes):
        if len(mesh.faces) == 0:
            continue
        vertices = np.asarray(mesh.vertices, np.float32)
        if len(vertices) < 4:  # MuJoCo's minimum; the extra vertex is used by no face
            vertices = np.concatenate([vertices, vertices[:1]])
        name = f"label/{k}_{mesh.name}"
        spec.add_mesh(
            name=name,
            uservert=vertices.ravel(),
            userface=np.asarray(mesh.faces, np.int32).ravel(),
            inertia=mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL,
        )
        spec.worldbody.add_geom(
            name=name,
            type=mujoco.mjtGeom.mjGEOM_MESH,
            meshname=name,
            group=LABELS,
            contype=0,
            conaffinity=0,
            rgba=(0.5, 0.5, 0.5, 1.0),
            userdata=[float(mesh.semantic), float(mesh.instance)],
        )
        added += 1
    return added


def label_people(spec: mujoco.MjSpec) -> int:
    """Labels every geom of group ``HUMANS`` on a body ``human<k>/...`` as person ``k``.

    Returns:
        The number of geoms labelled.
    """
    spec.nuser_geom = 2
    count = 0
    for body in spec.bodies:
        match = _PERSON_BODY.match(body.name)
        if match is None:
            continue
        for geom in body.geoms:
            if geom.group == groups.HUMANS:
                geom.userdata = [float(PERSON), float(PERSON_INSTANCE_BASE + int(match[1]))]
                count += 1
    return count


def geom_labels(model: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray]:
    """Per model geom, its (class, instance), as two ``(ngeom,)`` ``int64`` arrays."""
    if model.nuser_geom >= 2:
        user = np.rint(model.geom_user[:, :2]).astype(np.int64)
        return user[:, 0], user[:, 1]
    return np.zeros(model.ngeom, np.int64), np.zeros(model.ngeom, np.int64)


def segmentation_groups(model: mujoco.MjModel) -> tuple[int, ...]:
    """The geom groups the segmentation pass draws (see the module docstring)."""
    building = LABELS if np.any(model.geom_group == LABELS) else groups.VISUAL
    return (building, groups.ROBOT, groups.HUMANS)


def render_labels(model: mujoco.MjModel, data: mujoco.MjData, camera: Camera) -> Segmentation:
    """Renders the semantic and instance labels of ``camera``'s view of ``data``.

    Same preconditions as ``Camera.render`` (kinematics done); the view is the camera's own
    (pose, field of view, size). One extra render pass.
    """
    ids = camera.render_geom_ids(data, geom_groups=segmentation_groups(model))
    semantic, instance = geom_labels(model)
    hit = ids >= 0
    safe = np.where(hit, ids, 0)
    return Segmentation(
        np.where(hit, semantic[safe], 0).astype(np.uint8),
        np.where(hit, instance[safe], 0).astype(np.int32),
    )


def colorize(semantic: np.ndarray) -> np.ndarray:
    """An H×W×3 ``uint8`` picture of a semantic map in mpcat40's colours (people in red)."""
    table = np.array(
        [[int(h[i : i + 2], 16) for i in (0, 2, 4)] for h in (*MPCAT40_COLOURS, "e8282b")],
        np.uint8,
    )
    return table[np.minimum(semantic, len(table) - 1)]
