"""People drawn as skinned meshes from a (made-up) SMPL model: posed, uploaded and seen."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
import trimesh

from havln_mj import groups
from havln_mj.humans import rotations as rot
from havln_mj.humans.body import BodyShape
from havln_mj.humans.clip import Clip
from havln_mj.humans.crowd import Crowd, Person
from havln_mj.humans.mujoco_people import PeopleWriter, add_people
from havln_mj.humans.skeleton import JOINT, NUM_JOINTS, rest_positions
from havln_mj.humans.skinned import Skin, SkinWriter, vertex_normals
from havln_mj.render.camera import Camera


def _scene(crowd: Crowd) -> tuple[mujoco.MjModel, mujoco.MjData]:
    spec = mujoco.MjSpec()
    spec.visual.global_.offwidth, spec.visual.global_.offheight = 96, 96
    eye = spec.worldbody.add_body(name="eye", pos=(0.0, -4.0, 1.0))
    # Looking along +y: camera -z = world +y, camera +y = world +z.
    eye.add_camera(name="cam", quat=tuple(rot.from_axis((1, 0, 0), math.pi / 2)), fovy=60.0)
    add_people(spec, crowd.shapes, crowd.skins)
    return spec.compile(), None


def _crowd(x: float, wave: float, model) -> Crowd:
    local = rot.identity((2, NUM_JOINTS))
    local[:, JOINT["right_shoulder"]] = rot.from_axis((0, 1, 0), [0.0, wave])
    root = np.tile(rest_positions(1.7)[0], (2, 1))
    clip = Clip(root, 1.0, local=local)
    skin = Skin(model)
    return Crowd([Person(BodyShape(1.7), clip, np.array([x, 0.0, 0.0]), 0.0, "wave", skin=skin)])


def test_skinned_person_replaces_the_capsules_and_follows_the_pose(blob_smpl):
    crowd = _crowd(0.0, -1.2, blob_smpl)  # about +y (forward): negative lifts the right arm
    model, _ = _scene(crowd)
    human = np.flatnonzero(model.geom_group == groups.HUMANS)
    assert len(human) == 1 and model.geom_type[human[0]] == mujoco.mjtGeom.mjGEOM_MESH
    data = mujoco.MjData(model)
    writer, skins = PeopleWriter(model, 1), SkinWriter(model, [0])
    masks = []
    with Camera(model, "cam", 96, 96, 60.0) as cam:
        for t in (0.0, 1.0):  # rest, then the right arm raised
            writer.write(data, *crowd.pose(t))
            verts = crowd.skin_vertices(t)
            for mesh in skins.write(model, data, verts):
                cam.upload_mesh(mesh)
            mujoco.mj_kinematics(model, data)
            mujoco.mj_camlight(model, data)
            # The model's mesh, placed by its geom, is the skinned surface.
            g = human[0]
            placed = model.mesh_vert @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g]
            np.testing.assert_allclose(placed, verts[0], atol=1e-5)
            masks.append(np.isin(cam.render_geom_ids(data), human))
    assert masks[0].sum() > 30 and masks[1].sum() > 30
    # The raised right arm (the person's right is +x, image right) moves pixels up there.
    rows = np.nonzero(masks[1] & ~masks[0])[0]
    assert len(rows) > 0 and rows.mean() < np.nonzero(masks[0])[0].mean()


def test_vertex_normals_point_out_of_a_sphere():
    ball = trimesh.creation.icosphere(subdivisions=2)
    n = vertex_normals(np.asarray(ball.vertices), np.asarray(ball.faces))
    np.testing.assert_allclose(np.sum(n * ball.vertices, axis=1), 1.0, atol=0.02)


def test_a_skin_needs_rotations(blob_smpl):
    joints = np.tile(rest_positions(1.7), (2, 1, 1))
    clip = Clip(joints[:, 0], 10.0, positions=joints)
    with pytest.raises(ValueError, match="rotations"):
        Person(BodyShape(1.7), clip, np.zeros(3), 0.0, "mdm", skin=Skin(blob_smpl))
