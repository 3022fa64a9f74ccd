"""Shared test data for the humans package: a made-up SMPL model."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from havln_mj.humans.skeleton import NUM_JOINTS, SMPL_TO_BODY, rest_positions
from havln_mj.humans.smpl_model import SmplModel


@pytest.fixture(scope="session")
def blob_smpl() -> SmplModel:
    """A made-up SMPL model: a small sphere bound rigidly to each joint (SMPL frame, layout)."""
    ball = trimesh.creation.icosphere(subdivisions=1, radius=0.06)
    joints = rest_positions(1.7) @ SMPL_TO_BODY  # body → SMPL frame (the matrix is orthogonal)
    verts, faces, weights = [], [], []
    for j, centre in enumerate(joints):
        faces.append(ball.faces + len(verts) * len(ball.vertices))
        verts.append(ball.vertices + centre)
        w = np.zeros((len(ball.vertices), NUM_JOINTS))
        w[:, j] = 1.0
        weights.append(w)
    verts = np.vstack(verts)
    regressor = np.zeros((NUM_JOINTS, len(verts)))
    n = len(ball.vertices)
    for j in range(NUM_JOINTS):
        regressor[j, j * n : (j + 1) * n] = 1.0 / n
    return SmplModel(
        v_template=verts,
        shapedirs=np.zeros((len(verts), 3, 10)),
        j_regressor=regressor,
        weights=np.vstack(weights),
        faces=np.vstack(faces),
    )
