"""SMPL model files and numpy skinning, on a tiny synthetic model in SMPL's array conventions."""

from __future__ import annotations

import pickle
import sys
import types
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse
from scipy.spatial.transform import Rotation

from havln_mj.errors import MalformedDataError, MissingDataError
from havln_mj.humans import rotations as rot
from havln_mj.humans import skeleton
from havln_mj.humans.smpl_model import SmplModel, load_smpl_model

C = skeleton.SMPL_TO_BODY
PER_JOINT = 2  # vertices per joint; 24·2 + 2 = 50 vertices


def synthetic_model(seed: int = 0, posedirs: bool = True) -> dict[str, np.ndarray]:
    """Arrays named and shaped as in an SMPL file, but with 50 made-up vertices."""
    rng = np.random.default_rng(seed)
    # A human-like rest skeleton in SMPL's frame (y up, facing +z, +x left), origin near the
    # navel as in SMPL.
    joints = skeleton.rest_positions(1.7) @ C + (0.0, -1.2, 0.03)
    verts = np.repeat(joints, PER_JOINT, axis=0) + rng.normal(0, 0.03, (24 * PER_JOINT, 3))
    verts = np.vstack([verts, joints[[10, 11]] - (0.0, 0.06, 0.0)])  # two soles
    v = len(verts)
    regressor = np.zeros((24, v))
    for j in range(24):
        regressor[j, PER_JOINT * j : PER_JOINT * (j + 1)] = rng.uniform(0.2, 1.0, PER_JOINT)
        regressor[j] /= regressor[j].sum()
    weights = np.zeros((v, 24))
    owner = np.append(np.repeat(np.arange(24), PER_JOINT), [10, 11])
    for i, j in enumerate(owner):
        if i % PER_JOINT == 0 or j == 0:  # half the vertices follow one joint only
            weights[i, j] = 1.0
        else:
            weights[i, j], weights[i, skeleton.PARENTS[j]] = 0.7, 0.3
    kintree = np.vstack([np.append(4294967295, skeleton.PARENTS[1:]), np.arange(24)])
    model = {
        "v_template": verts,
        "shapedirs": rng.normal(0, 0.01, (v, 3, 10)),
        "J_regressor": regressor,
        "weights": weights,
        "kintree_table": kintree.astype(np.uint32),
        "f": rng.integers(0, v, (30, 3)),
    }
    if posedirs:
        model["posedirs"] = rng.normal(0, 0.002, (v, 3, 207))
    return model


def write_model(tmp_path: Path, **kwargs) -> Path:
    path = tmp_path / "SMPL_TEST.npz"
    np.savez(path, **synthetic_model(**kwargs))
    return path


def smpl_lbs(arrays: dict, betas: np.ndarray, rotvecs: np.ndarray, pelvis: np.ndarray):
    """Reference SMPL skinning in SMPL's own frame, with matrices (one pose)."""
    shaped = arrays["v_template"] + arrays["shapedirs"] @ betas[:10]
    joints = arrays["J_regressor"] @ shaped
    r = Rotation.from_rotvec(rotvecs).as_matrix()  # (24, 3, 3)
    if "posedirs" in arrays:
        shaped = shaped + arrays["posedirs"] @ (r[1:] - np.eye(3)).ravel()
    g, p = np.empty((24, 3, 3)), np.empty((24, 3))
    g[0], p[0] = r[0], pelvis
    for j in range(1, 24):
        par = skeleton.PARENTS[j]
        g[j] = g[par] @ r[j]
        p[j] = p[par] + g[par] @ (joints[j] - joints[par])
    out = np.zeros_like(shaped)
    for j in range(24):
        out += arrays["weights"][:, j : j + 1] * ((shaped - joints[j]) @ g[j].T + p[j])
    return out, p


def body_local(rotvecs: np.ndarray) -> np.ndarray:
    """Our-frame local quaternions of SMPL axis-angles (conjugated by C)."""
    m = C @ Rotation.from_rotvec(rotvecs).as_matrix() @ C.T
    return rot.from_matrix(m)


def test_joints_are_the_regressed_shaped_template(tmp_path: Path) -> None:
    arrays = synthetic_model()
    model = load_smpl_model(write_model(tmp_path))
    assert model.num_vertices == 50 and model.num_betas == 10
    betas = np.random.default_rng(1).normal(0, 1, 16)  # AMASS-style: 16, the model has 10
    want = arrays["J_regressor"] @ (arrays["v_template"] + arrays["shapedirs"] @ betas[:10])
    np.testing.assert_allclose(model.joints(betas), want, atol=1e-12)
    np.testing.assert_allclose(
        model.joints(), arrays["J_regressor"] @ arrays["v_template"], atol=1e-12
    )


def test_rest_offsets_rebuild_the_joints_in_our_frame(tmp_path: Path) -> None:
    arrays = synthetic_model()
    model = load_smpl_model(write_model(tmp_path))
    betas = np.linspace(-1, 1, 10)
    joints = model.joints(betas) @ C.T
    pos, _ = skeleton.forward_kinematics(model.rest_offsets(betas), rot.identity((24,)), joints[0])
    np.testing.assert_allclose(pos, joints, atol=1e-12)
    shaped = (arrays["v_template"] + arrays["shapedirs"] @ betas) @ C.T
    assert model.rest_offsets(betas)[0] == pytest.approx([0, 0, joints[0, 2] - shaped[:, 2].min()])
    # Our frame is z up: the head is above the pelvis, the pelvis above the ankles.
    assert joints[15, 2] > joints[0, 2] + 0.5 > joints[7, 2] + 0.5


def test_zero_pose_gives_the_shaped_template(tmp_path: Path) -> None:
    arrays = synthetic_model()
    model = load_smpl_model(write_model(tmp_path))
    betas = np.random.default_rng(2).normal(0, 1, 10)
    shaped = arrays["v_template"] + arrays["shapedirs"] @ betas
    pelvis = model.joints(betas)[0] @ C.T
    verts = model.skin(betas, rot.identity((24,)), pelvis)
    np.testing.assert_allclose(verts, shaped @ C.T, atol=1e-12)
    # Moving the root translates every vertex rigidly.
    moved = model.skin(betas, rot.identity((24,)), pelvis + np.array([1.0, 2.0, 3.0]))
    np.testing.assert_allclose(moved - verts, np.broadcast_to((1.0, 2.0, 3.0), verts.shape))


def test_a_rotated_joint_moves_only_the_vertices_it_weighs(tmp_path: Path) -> None:
    model = load_smpl_model(write_model(tmp_path, posedirs=False))
    elbow = skeleton.JOINT["left_elbow"]
    chain = [elbow, skeleton.JOINT["left_wrist"], skeleton.JOINT["left_hand"]]
    local = rot.identity((24,))
    turn = rot.from_axis_angle(np.array([0.3, 1.0, -0.4]))
    local[elbow] = turn
    pelvis = model.joints()[0] @ C.T
    rest = model.skin(None, rot.identity((24,)), pelvis)
    posed = model.skin(None, local, pelvis)
    moved = np.linalg.norm(posed - rest, axis=1) > 1e-9
    weighs = model.weights[:, chain].sum(axis=1) > 0
    assert moved.any()
    np.testing.assert_array_equal(moved, weighs)
    # A vertex skinned to the elbow alone turns rigidly about the elbow joint.
    only = np.flatnonzero(model.weights[:, elbow] == 1.0)
    centre = model.joints()[elbow] @ C.T
    np.testing.assert_allclose(
        posed[only] - centre, rot.rotate(turn, rest[only] - centre), atol=1e-12
    )


@pytest.mark.parametrize("posedirs", [False, True])
def test_skinning_matches_smpl_lbs_in_the_smpl_frame(tmp_path: Path, posedirs: bool) -> None:
    arrays = synthetic_model(posedirs=posedirs)
    model = load_smpl_model(write_model(tmp_path, posedirs=posedirs))
    rng = np.random.default_rng(3)
    betas = rng.normal(0, 1, 10)
    rotvecs = rng.normal(0, 0.5, (24, 3))
    pelvis = np.array([0.3, 0.9, -1.0])  # SMPL frame
    want, _ = smpl_lbs(arrays, betas, rotvecs, pelvis)
    got = model.skin(betas, body_local(rotvecs), C @ pelvis)
    np.testing.assert_allclose(got, want @ C.T, atol=1e-9)
    # Batched poses give the same per frame.
    batch = model.skin(betas, np.stack([body_local(rotvecs)] * 3), np.stack([C @ pelvis] * 3))
    np.testing.assert_allclose(batch[2], got, atol=1e-12)
    if posedirs:
        plain = SmplModel(**{**vars(model), "posedirs": None})
        assert np.abs(plain.skin(betas, body_local(rotvecs), C @ pelvis) - got).max() > 1e-4


def test_pickle_without_chumpy_and_sparse_regressor(tmp_path: Path) -> None:
    arrays = synthetic_model()
    sparse = {**arrays, "J_regressor": scipy.sparse.csc_matrix(arrays["J_regressor"])}
    pkl = tmp_path / "basicModel.pkl"
    pkl.write_bytes(pickle.dumps(sparse, protocol=2))
    npz = tmp_path / "sparse.npz"
    np.savez(npz, **sparse)  # np.savez stores the sparse matrix as a pickled object
    for path in (pkl, npz):
        model = load_smpl_model(path)
        np.testing.assert_allclose(model.j_regressor, arrays["J_regressor"])
        np.testing.assert_allclose(model.posedirs, arrays["posedirs"])


def test_chumpy_pickle_asks_for_conversion(tmp_path: Path, monkeypatch) -> None:
    chumpy, ch = types.ModuleType("chumpy"), types.ModuleType("chumpy.ch")

    class Ch:  # stands in for chumpy's array class while pickling
        pass

    Ch.__module__, Ch.__qualname__ = "chumpy.ch", "Ch"
    ch.Ch = Ch
    monkeypatch.setitem(sys.modules, "chumpy", chumpy)
    monkeypatch.setitem(sys.modules, "chumpy.ch", ch)
    blob = pickle.dumps({**synthetic_model(), "shapedirs": Ch()}, protocol=2)
    monkeypatch.delitem(sys.modules, "chumpy")
    monkeypatch.delitem(sys.modules, "chumpy.ch")
    path = tmp_path / "SMPL_NEUTRAL.pkl"
    path.write_bytes(blob)
    with pytest.raises(MalformedDataError, match=r"chumpy.*npz") as err:
        load_smpl_model(path)
    assert str(path) in str(err.value) and "np.savez" in str(err.value)


def test_model_file_errors_name_file_and_key(tmp_path: Path) -> None:
    with pytest.raises(MissingDataError, match=r"nowhere\.npz"):
        load_smpl_model(tmp_path / "nowhere.npz")
    arrays = synthetic_model()
    cases = {
        "no_weights": ({k: v for k, v in arrays.items() if k != "weights"}, "weights"),
        "bad_regressor": ({**arrays, "J_regressor": arrays["J_regressor"][:22]}, "J_regressor"),
        "bad_shapedirs": ({**arrays, "shapedirs": arrays["shapedirs"][:, :2]}, "shapedirs"),
        "bad_posedirs": ({**arrays, "posedirs": arrays["posedirs"][..., :100]}, "posedirs"),
        "bad_tree": ({**arrays, "kintree_table": arrays["kintree_table"].copy()}, "kintree"),
    }
    cases["bad_tree"][0]["kintree_table"][0, 5] = 1  # right knee hung on the left hip
    for name, (content, key) in cases.items():
        path = tmp_path / f"{name}.npz"
        np.savez(path, **content)
        with pytest.raises(MalformedDataError, match=key) as err:
            load_smpl_model(path)
        assert name in str(err.value)
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"not a zip")
    with pytest.raises(MalformedDataError, match=r"junk\.npz"):
        load_smpl_model(junk)
