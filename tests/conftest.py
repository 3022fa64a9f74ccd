"""Shared fixtures: an isolated cache per test session and the shared real-data folder."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("MUJOCO_GL", "egl")

_REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session", autouse=True)
def _isolated_cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Points HAVLN_CACHE at a per-session temp folder so tests never touch the user's cache."""
    path = tmp_path_factory.mktemp("havln_cache")
    old = os.environ.get("HAVLN_CACHE")
    os.environ["HAVLN_CACHE"] = str(path)
    yield path
    if old is None:
        os.environ.pop("HAVLN_CACHE", None)
    else:
        os.environ["HAVLN_CACHE"] = old


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The real public test data (``$HAVLN_SHARED_DATA`` or ``../shared/data``); skips if absent."""
    path = Path(os.environ.get("HAVLN_SHARED_DATA", _REPO.parent / "shared" / "data"))
    if not (path / "mp3d_connectivity").is_dir():
        pytest.skip(f"shared real data not found at {path} (set HAVLN_SHARED_DATA)")
    return path


@pytest.fixture(scope="session")
def blob_smpl():
    """A made-up SMPL model: a small sphere bound rigidly to each joint (SMPL frame, layout)."""
    import numpy as np
    import trimesh

    from havln_mj.humans.skeleton import NUM_JOINTS, SMPL_TO_BODY, rest_positions
    from havln_mj.humans.smpl_model import SmplModel

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


class StandingPeople:
    """People standing still at fixed pelvis points: the Crowd protocol, nothing drawn."""

    def __init__(self, points):
        import numpy as np

        self.points = np.asarray(points, float).reshape(-1, 3)
        self.shapes, self.skins = [], []

    def __len__(self):
        return len(self.points)

    def positions(self, times, people=None):
        import numpy as np

        points = self.points if people is None else self.points[people]
        return np.broadcast_to(points, (len(np.atleast_1d(times)), *points.shape)).copy()

    def footprint(self):
        import numpy as np

        return self.points[:, :2], np.zeros(len(self.points))

    def states(self, t):
        return [tuple(p) for p in self.points]


@pytest.fixture(scope="session")
def standing():
    """Makes people standing still at given pelvis points (see :class:`StandingPeople`)."""
    return StandingPeople
