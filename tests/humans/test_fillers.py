"""Fillers inside rigid Anny pieces: low-poly closed capsules, drawn where creases open."""

from __future__ import annotations

from collections import Counter

import mujoco
import numpy as np
import pytest

from havln_mj.humans.mujoco_people import FILLER_SHRINK, add_people, capsule_mesh
from havln_mj.humans.population import anny_shape


@pytest.mark.parametrize("b", [(0.0, 0.0, 0.4), (0.3, -0.2, 0.1), (0.0, 0.0, 0.0)])
def test_capsule_mesh_is_a_closed_outward_capsule(b):
    a = np.array([0.1, 0.2, -0.1])
    b, r = a + np.array(b), 0.05
    verts, normals, faces = capsule_mesh(a, b, r)
    sides = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    edges = Counter(map(tuple, np.sort(sides, axis=1).tolist()))
    assert set(edges.values()) == {2}  # closed: every edge between two triangles
    axis = b - a
    t = np.clip((verts - a) @ axis / max(axis @ axis, 1e-12), 0.0, 1.0)
    gap = np.linalg.norm(verts - (a + t[:, None] * axis), axis=1)
    np.testing.assert_allclose(gap, r, atol=1e-12)  # on the capsule's surface
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0)
    tri = verts[faces]
    outward = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    centre = tri.mean(axis=1)
    t = np.clip((centre - a) @ axis / max(axis @ axis, 1e-12), 0.0, 1.0)
    assert np.all(np.einsum("ij,ij->i", outward, centre - (a + t[:, None] * axis)) > 0)
    assert len(faces) <= 64


def test_pieces_carry_mesh_fillers_and_solid_people_keep_colliding_capsules():
    shape = anny_shape(np.random.default_rng(0))
    for solid in (False, True):
        spec = mujoco.MjSpec()
        add_people(spec, [shape], solid=solid, style="pieces")
        model = spec.compile()
        fillers = [
            g
            for g in range(model.ngeom)
            if model.geom(g).name.count("/") == 2 and not model.geom(g).name.endswith("/anny")
        ]
        kinds = {int(model.geom_type[g]) for g in fillers}
        if solid:  # the capsules are the contact shapes: primitives that collide
            assert int(mujoco.mjtGeom.mjGEOM_MESH) not in kinds
            assert all(model.geom_contype[g] == 1 for g in fillers)
        else:
            assert int(mujoco.mjtGeom.mjGEOM_MESH) in kinds
            assert all(model.geom_contype[g] == 0 for g in fillers)
            assert all(model.geom_rgba[g, 3] == 1.0 for g in fillers)  # drawn, in creases
    assert 0 < FILLER_SHRINK < 1
