"""Motion loaders on files written here in the AMASS, HAPS and MDM formats (made-up content).

The reference joint positions are computed from each source's own definition: SMPL forward
kinematics with rotation matrices in the source's frame (pelvis = J0(β) + trans for AMASS,
the stored root translation for HAPS), then mapped to ours (z-up AMASS unchanged, y-up
sources by SMPL_TO_BODY).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from havln_mj.errors import InvalidArgumentError, MalformedDataError, MissingDataError
from havln_mj.humans import rotations as rot
from havln_mj.humans import skeleton
from havln_mj.humans.loaders import (
    LoadedMotion,
    haps_dir_name,
    load_amass,
    load_haps,
    load_haps_folder,
    load_mdm,
)
from havln_mj.humans.smpl_model import load_smpl_model

C = skeleton.SMPL_TO_BODY
CM = 0.01
FEET = [7, 8, 10, 11]
TEXT = "hallway:Someone talking on the phone while pacing/turning."


def synthetic_model(seed: int = 0) -> dict[str, np.ndarray]:
    """A 50-vertex model with SMPL's array names, shapes and joint tree."""
    rng = np.random.default_rng(seed)
    joints = skeleton.rest_positions(1.65) @ C + (0.01, -1.15, 0.02)  # SMPL frame
    verts = np.vstack([np.repeat(joints, 2, axis=0) + rng.normal(0, 0.03, (48, 3)), joints[:2]])
    regressor = np.zeros((24, 50))
    for j in range(24):
        regressor[j, 2 * j : 2 * j + 2] = 0.5
    weights = np.zeros((50, 24))
    weights[np.arange(50), np.append(np.repeat(np.arange(24), 2), [0, 1])] = 1.0
    kintree = np.vstack([np.append(-1, skeleton.PARENTS[1:]), np.arange(24)])
    return {
        "v_template": verts,
        "shapedirs": rng.normal(0, 0.01, (50, 3, 10)),
        "posedirs": rng.normal(0, 0.001, (50, 3, 207)),
        "J_regressor": regressor,
        "weights": weights,
        "kintree_table": kintree,
        "f": rng.integers(0, 50, (20, 3)),
    }


@pytest.fixture
def model_arrays() -> dict[str, np.ndarray]:
    return synthetic_model()


@pytest.fixture
def model(tmp_path: Path, model_arrays):
    path = tmp_path / "model.npz"
    np.savez(path, **model_arrays)
    return load_smpl_model(path)


def rest_joints(arrays: dict, betas: np.ndarray | None) -> np.ndarray:
    """J(β) = J_regressor · (v_template + shapedirs · β), SMPL frame."""
    b = np.zeros(10) if betas is None else betas[:10]
    return arrays["J_regressor"] @ (arrays["v_template"] + arrays["shapedirs"] @ b)


def smpl_fk(mats: np.ndarray, joints: np.ndarray, pelvis: np.ndarray) -> np.ndarray:
    """SMPL forward kinematics with matrices: ``(T, 24, 3, 3)`` local, rest joints, pelvis."""
    g = np.empty_like(mats)
    p = np.empty((*mats.shape[:2], 3))
    g[:, 0], p[:, 0] = mats[:, 0], pelvis
    for j in range(1, 24):
        par = skeleton.PARENTS[j]
        g[:, j] = g[:, par] @ mats[:, j]
        p[:, j] = p[:, par] + g[:, par] @ (joints[j] - joints[par])
    return p


def smpl_skin(arrays, betas, mats, pelvis) -> np.ndarray:
    """SMPL linear blend skinning with matrices, one frame, SMPL conventions."""
    b = np.zeros(10) if betas is None else betas[:10]
    shaped = arrays["v_template"] + arrays["shapedirs"] @ b
    joints = arrays["J_regressor"] @ shaped
    shaped = shaped + arrays["posedirs"] @ (mats[1:] - np.eye(3)).ravel()
    g = np.empty_like(mats)
    g[0] = mats[0]
    for j in range(1, 24):
        g[j] = g[skeleton.PARENTS[j]] @ mats[j]
    p = smpl_fk(mats[None], joints, pelvis[None])[0]
    out = np.zeros_like(shaped)
    for j in range(24):
        out += arrays["weights"][:, [j]] * ((shaped - joints[j]) @ g[j].T + p[j])
    return out


def random_motion(rng, frames: int, joints: int = 24) -> np.ndarray:
    """Smooth made-up SMPL axis-angles ``(T, joints, 3)``: a standing person (root Rx 90°
    for a z-up world is added by the caller) with joints swinging up to ~0.6 rad."""
    t = np.arange(frames)[:, None, None] / frames
    amp, freq, phase = (rng.uniform(0, 0.6, (1, joints, 3)) for _ in range(3))
    return amp * np.sin(2 * np.pi * (1 + 3 * freq) * t + 6 * phase)


def amass_arrays(rng, frames: int = 121, columns: int = 156) -> dict[str, np.ndarray]:
    """AMASS SMPL-H layout: poses (N, 156), trans, betas (16), 120 fps, z-up world."""
    body = random_motion(rng, frames, 22).reshape(frames, 66)
    # Root: the y-up → z-up change AMASS bakes in, then a turning heading about world z.
    heading = Rotation.from_rotvec(np.outer(np.linspace(0, 2.0, frames), [0, 0, 1]))
    root = heading * Rotation.from_rotvec([np.pi / 2, 0, 0]) * Rotation.from_rotvec(body[:, :3])
    body[:, :3] = root.as_rotvec()
    poses = np.concatenate([body, rng.normal(0, 0.3, (frames, columns - 66))], axis=1)
    trans = np.column_stack(
        [np.linspace(0, 1.5, frames), 0.2 * np.sin(np.linspace(0, 3, frames)), np.full(frames, 0.9)]
    )
    return {
        "poses": poses,
        "trans": trans,
        "betas": rng.normal(0, 1, 16),
        "mocap_framerate": np.array(120.0),
        "gender": np.array("neutral"),
        "dmpls": np.zeros((frames, 8)),
    }


def amass_reference(data: dict, arrays: dict | None, rest: np.ndarray | None = None):
    """Source joints (AMASS world = ours): SMPL FK, pelvis = J0(β) + trans."""
    poses = data["poses"]
    n = len(poses)
    k = 24 if poses.shape[1] == 72 else 22
    rotvecs = np.zeros((n, 24, 3))
    rotvecs[:, :k] = poses[:, : 3 * k].reshape(n, k, 3)
    mats = Rotation.from_rotvec(rotvecs.reshape(-1, 3)).as_matrix().reshape(n, 24, 3, 3)
    joints = rest if rest is not None else rest_joints(arrays, data["betas"])
    return smpl_fk(mats, joints, data["trans"] + joints[0]), mats


def write_npz(path: Path, data: dict) -> Path:
    np.savez(path, **data)
    return path


# --- AMASS ---------------------------------------------------------------------------------


@pytest.mark.parametrize("columns", [156, 72])
def test_amass_fk_matches_source_joints(tmp_path, model, model_arrays, columns) -> None:
    data = amass_arrays(np.random.default_rng(0), columns=columns)
    clip = load_amass(write_npz(tmp_path / "walk_poses.npz", data), model=model)
    assert isinstance(clip, LoadedMotion) and clip.fps == 120 and clip.frames == 121
    want, _ = amass_reference(data, model_arrays)
    err = np.abs(clip.joint_positions() - want).max()
    assert err < CM, err
    np.testing.assert_allclose(
        clip.root, data["trans"] + rest_joints(model_arrays, data["betas"])[0], atol=1e-12
    )
    if columns == 156:  # SMPL-H: no SMPL hand joints, so unrotated
        np.testing.assert_allclose(np.abs(clip.local[:, 22:, 0]), 1.0)


def test_amass_skinned_mesh_matches_smpl(tmp_path, model, model_arrays) -> None:
    data = amass_arrays(np.random.default_rng(1), frames=5, columns=72)
    clip = load_amass(write_npz(tmp_path / "m.npz", data), model=model)
    _, mats = amass_reference(data, model_arrays)
    for k in range(5):
        pelvis = data["trans"][k] + rest_joints(model_arrays, data["betas"])[0]
        want = smpl_skin(model_arrays, data["betas"], mats[k], pelvis)
        np.testing.assert_allclose(clip.vertices(k), want, atol=1e-9)
    assert clip.vertices(slice(0, 3)).shape == (3, 50, 3)


def test_amass_standing_pose_is_upright(tmp_path, model) -> None:
    # AMASS stores a standing person with root_orient = +90° about x (SMPL's y up → z up).
    n = 3
    data = {
        "poses": np.hstack([np.tile([np.pi / 2, 0, 0], (n, 1)), np.zeros((n, 153))]),
        "trans": np.tile([0.5, -0.3, 0.95], (n, 1)),
        "betas": np.zeros(16),
        "mocap_framerate": np.array(60.0),
    }
    path = write_npz(tmp_path / "stand.npz", data)
    for clip in (load_amass(path, model=model), load_amass(path)):
        pos = clip.joint_positions()[0]
        up = pos[skeleton.JOINT["head"]] - pos[FEET].mean(axis=0)
        assert up[2] / np.linalg.norm(up) > 0.99, up
        assert pos[15, 2] > pos[12, 2] > pos[0, 2] > pos[4, 2] > pos[7, 2]
        np.testing.assert_allclose(rot.rotate(clip.local[0, 0], [0, 0, 1]), [0, 0, 1], atol=1e-9)
        # Body +x is the person's right: SMPL's right hip is at −x_smpl, which Rx(90°) keeps.
        right = rot.rotate(clip.local[0, 0], [1, 0, 0])
        np.testing.assert_allclose(right, [-1, 0, 0], atol=1e-9)
        hips = pos[skeleton.JOINT["right_hip"]] - pos[skeleton.JOINT["left_hip"]]
        assert np.dot(hips, right) > 0.9 * np.linalg.norm(hips)


def test_amass_without_model_uses_our_proportions_on_the_floor(tmp_path) -> None:
    data = amass_arrays(np.random.default_rng(2))
    clip = load_amass(write_npz(tmp_path / "a.npz", data), height=1.8)
    np.testing.assert_allclose(clip.offsets, skeleton.rest_offsets(1.8))
    # Same motion as SMPL FK on our proportions (mapped into SMPL's frame), up to one
    # vertical shift that puts the feet on the floor.
    rest = skeleton.rest_positions(1.8) @ C
    want, _ = amass_reference(data, None, rest=rest - rest[0])
    diff = clip.joint_positions() - want
    np.testing.assert_allclose(diff, np.broadcast_to(diff[0, 0], diff.shape), atol=1e-9)
    assert diff[0, 0, :2] == pytest.approx([0, 0], abs=1e-9)
    lowest = clip.joint_positions()[:, FEET, 2].min()
    assert lowest == pytest.approx(skeleton.rest_positions(1.8)[FEET, 2].min())


def test_amass_smplx_g_keys(tmp_path, model) -> None:
    data = amass_arrays(np.random.default_rng(3), frames=10)
    g = {
        "root_orient": data["poses"][:, :3],
        "pose_body": data["poses"][:, 3:66],
        "trans": data["trans"],
        "betas": data["betas"],
        "mocap_frame_rate": np.array(30.0),
    }
    a = load_amass(write_npz(tmp_path / "h.npz", data), model=model)
    b = load_amass(write_npz(tmp_path / "x_stageii.npz", g), model=model)
    assert b.fps == 30
    np.testing.assert_allclose(b.joint_positions(), a.joint_positions(), atol=1e-12)


def test_amass_resampling_120_to_30_keeps_the_motion(tmp_path, model) -> None:
    data = amass_arrays(np.random.default_rng(4), frames=121)
    path = write_npz(tmp_path / "r.npz", data)
    full = load_amass(path, model=model)
    slow = load_amass(path, model=model, fps=30)
    assert slow.fps == 30 and slow.frames == 31 and slow.duration == pytest.approx(1.0)
    assert slow.offsets is full.offsets or np.array_equal(slow.offsets, full.offsets)
    # Common times: every 4th source frame.
    err = np.abs(slow.joint_positions() - full.joint_positions()[::4]).max()
    assert err < 1e-9, err
    # Upsampling back to 120 fps interpolates between the kept frames: close to the source.
    back = slow.resampled(120)
    assert isinstance(back, LoadedMotion) and back.model is model
    assert np.abs(back.joint_positions() - full.joint_positions()).max() < 0.05


# --- HAPS ----------------------------------------------------------------------------------


def haps_arrays(rng, frames: int = 40) -> tuple[dict, np.ndarray]:
    """A ``<rep>_smpl_params.npy`` dict (y-up) and its source rotation matrices."""
    rotvecs = random_motion(rng, frames)
    mats = Rotation.from_rotvec(rotvecs.reshape(-1, 3)).as_matrix().reshape(frames, 24, 3, 3)
    r6d = mats[..., :2, :].reshape(frames, 24, 6)  # PyTorch3D: the first two rows
    thetas = np.moveaxis(r6d, 0, -1)  # (24, 6, T)
    root = np.stack(
        [
            0.3 * np.sin(np.arange(frames) / 7),
            0.93 + 0.02 * np.cos(np.arange(frames)),
            np.linspace(0, 1.2, frames),
        ]
    )  # (3, T), y up
    motion = np.concatenate([thetas, np.vstack([root, np.zeros((3, frames))])[None]], axis=0)
    data = {
        "motion": motion,
        "thetas": thetas,
        "root_translation": root,
        "faces": np.zeros((1, 3), int),
        "vertices": np.zeros((50, 3, frames)),
        "text": TEXT,
        "length": frames,
    }
    return data, mats


def write_haps(folder: Path, data: dict, rep: int = 0) -> Path:
    sub = folder / "human_motion_meshes" / haps_dir_name(TEXT)
    sub.mkdir(parents=True, exist_ok=True)
    path = sub / f"{rep}_smpl_params.npy"
    np.save(path, data)
    return path


def test_haps_fk_matches_source_joints(tmp_path, model, model_arrays) -> None:
    data, mats = haps_arrays(np.random.default_rng(5))
    clip = load_haps(write_haps(tmp_path, data), model=model)
    assert clip.fps == 20 and clip.frames == 40 and clip.name == TEXT
    want = smpl_fk(mats, rest_joints(model_arrays, None), data["root_translation"].T) @ C.T
    err = np.abs(clip.joint_positions() - want).max()
    assert err < CM, err
    np.testing.assert_allclose(clip.root, data["root_translation"].T @ C.T, atol=1e-12)
    want_v = smpl_skin(model_arrays, None, mats[7], data["root_translation"][:, 7]) @ C.T
    np.testing.assert_allclose(clip.vertices(7), want_v, atol=1e-9)


def test_haps_rot6d_decoding(tmp_path) -> None:
    data, mats = haps_arrays(np.random.default_rng(6))
    clip = load_haps(write_haps(tmp_path, data))
    back = C.T @ rot.to_matrix(clip.local) @ C  # our local rotations, in SMPL axes again
    np.testing.assert_allclose(back, mats, atol=1e-9)
    # The 'motion' array alone (rows 0–23 rot6d, row 24 translation) decodes the same.
    only = {"motion": data["motion"], "text": TEXT}
    clip2 = load_haps(write_haps(tmp_path / "b", only))
    np.testing.assert_allclose(clip2.local, clip.local, atol=1e-12)
    np.testing.assert_allclose(clip2.root, clip.root, atol=1e-12)


def test_haps_faces_forward_and_trims_to_length(tmp_path, model) -> None:
    data, _ = haps_arrays(np.random.default_rng(7))
    data["thetas"][:] = np.moveaxis(np.tile([1.0, 0, 0, 0, 1, 0], (40, 24, 1)), 0, -1)
    data["length"] = 25
    clip = load_haps(write_haps(tmp_path, data), model=model)
    assert clip.frames == 25
    pos = clip.joint_positions()[0]
    assert pos[15, 2] > pos[0, 2] > pos[7, 2]  # upright
    toes = pos[[10, 11]].mean(axis=0) - pos[[7, 8]].mean(axis=0)
    assert toes[1] > 0.8 * np.linalg.norm(toes[:2])  # SMPL's +z facing is our +y
    assert pos[skeleton.JOINT["right_hip"], 0] > pos[skeleton.JOINT["left_hip"], 0]


def test_haps_resampling_20_to_30(tmp_path, model) -> None:
    data, _ = haps_arrays(np.random.default_rng(8), frames=41)
    path = write_haps(tmp_path, data)
    src = load_haps(path, model=model)
    fast = load_haps(path, model=model, fps=30)
    assert fast.fps == 30 and fast.frames == 61
    # Common times k/10 s: source frame 2k, resampled frame 3k.
    err = np.abs(fast.joint_positions()[::3] - src.joint_positions()[::2]).max()
    assert err < 1e-9, err
    # In between, slerped poses stay close to the source's motion.
    mid = src.resampled(40).joint_positions()[1::2]  # at (2k+1)/40 s
    assert np.abs(fast.resampled(40).joint_positions()[1::2] - mid).max() < 0.02


def test_haps_folder(tmp_path, model) -> None:
    data, _ = haps_arrays(np.random.default_rng(9))
    for rep in (2, 0, 1):
        write_haps(tmp_path, data, rep)
    (tmp_path / "human_motion_meshes" / haps_dir_name(TEXT) / "0_obj").mkdir()
    (tmp_path / "human_motion_meshes" / "empty_prompt").mkdir()
    motions = load_haps_folder(tmp_path, model=model)
    key = "hallway:Someone_talking_on_the_phone_while_pacing_turning."
    assert list(motions) == [key] and haps_dir_name(TEXT) == key
    assert [Path(c.source).name for c in motions[key]] == [f"{r}_smpl_params.npy" for r in range(3)]
    assert load_haps_folder(tmp_path / "human_motion_meshes").keys() == motions.keys()
    with pytest.raises(MissingDataError, match="empty_prompt"):
        load_haps_folder(tmp_path / "human_motion_meshes" / "empty_prompt")


# --- MDM -----------------------------------------------------------------------------------


def mdm_arrays(rng, samples: int = 2, reps: int = 2, frames: int = 30) -> dict:
    base = skeleton.rest_positions(1.7)[:22] @ C  # y-up joints, feet near y = 0
    t = np.arange(frames) / 20
    walk = np.stack([0.1 * np.sin(t), 0.05 * np.sin(3 * t), 0.8 * t], axis=-1)  # along +z
    motion = base[None, :, :, None] + walk.T[None, None] + rng.normal(0, 0.02, (4, 22, 3, frames))
    motion[:, :, 1] += 0.3  # float above the floor: the loader puts the feet down
    return {
        "motion": motion[: samples * reps],
        "text": [f"a person walks {i}" for i in range(samples)] * reps,
        "lengths": np.array([30, 20, 25, 10])[: samples * reps],
        "num_samples": samples,
        "num_repetitions": reps,
    }


def test_mdm_positions_floor_and_lengths(tmp_path) -> None:
    data = mdm_arrays(np.random.default_rng(10))
    path = tmp_path / "results.npy"
    np.save(path, data)
    clips = load_mdm(path)
    assert [c.frames for c in clips] == [30, 20, 25, 10]
    assert [c.name for c in clips] == data["text"]
    for clip, motion, n in zip(clips, data["motion"], data["lengths"], strict=True):
        assert clip.fps == 20 and clip.local is None and clip.offsets is None
        want = motion[:, :, :n].transpose(2, 0, 1) @ C.T  # (T, 22, 3), z up
        want[..., 2] -= want[:, FEET, 2].min()
        assert np.abs(clip.positions[:, :22] - want).max() < 1e-3
        assert clip.positions[:, FEET, 2].min() == pytest.approx(0.0, abs=1e-12)
        np.testing.assert_array_equal(clip.positions[:, 22:], clip.positions[:, 20:22])
        np.testing.assert_array_equal(clip.root, clip.positions[:, 0])
        assert clip.positions[-1, 0, 1] > clip.positions[0, 0, 1]  # walked along +y
    fast = load_mdm(path, fps=30)[0]
    assert fast.fps == 30 and np.abs(fast.positions[::3] - clips[0].positions[::2]).max() < 1e-9


# --- errors --------------------------------------------------------------------------------


def test_missing_files_are_named(tmp_path) -> None:
    for loader, name in (
        (load_amass, "x.npz"),
        (load_haps, "0_smpl_params.npy"),
        (load_mdm, "results.npy"),
    ):
        with pytest.raises(MissingDataError, match=re.escape(name)):
            loader(tmp_path / name)
    with pytest.raises(MissingDataError, match="nothere"):
        load_haps_folder(tmp_path / "nothere")


def test_amass_format_errors_name_file_and_key(tmp_path) -> None:
    good = amass_arrays(np.random.default_rng(11), frames=4)
    cases = {
        "no_trans": ({k: v for k, v in good.items() if k != "trans"}, "'trans'"),
        "no_poses": ({k: v for k, v in good.items() if k != "poses"}, "'poses'"),
        "no_rate": ({k: v for k, v in good.items() if k != "mocap_framerate"}, "framerate"),
        "narrow": ({**good, "poses": good["poses"][:, :30]}, "'poses'"),
        "short_trans": ({**good, "trans": good["trans"][:2]}, "'trans'"),
        "zero_rate": ({**good, "mocap_framerate": np.array(0.0)}, "framerate"),
    }
    for name, (data, key) in cases.items():
        with pytest.raises(MalformedDataError, match=key) as err:
            load_amass(write_npz(tmp_path / f"{name}.npz", data))
        assert f"{name}.npz" in str(err.value)
    with pytest.raises(InvalidArgumentError, match="fps"):
        load_amass(write_npz(tmp_path / "ok.npz", good), fps=-1)


def test_haps_and_mdm_format_errors_name_file_and_key(tmp_path) -> None:
    data, _ = haps_arrays(np.random.default_rng(12), frames=5)
    cases = {
        "no_root": (
            {k: v for k, v in data.items() if k not in ("root_translation",)},
            "root_translation",
        ),
        "bad_thetas": ({**data, "thetas": data["thetas"][:23]}, "'thetas'"),
        "nothing": ({"text": TEXT}, "'thetas'"),
    }
    for name, (content, key) in cases.items():
        path = tmp_path / f"{name}.npy"
        np.save(path, content)
        with pytest.raises(MalformedDataError, match=key) as err:
            load_haps(path)
        assert f"{name}.npy" in str(err.value)
    mdm = mdm_arrays(np.random.default_rng(13))
    cases = {
        "joints24": ({**mdm, "motion": np.zeros((4, 24, 3, 30))}, "'motion'"),
        "no_lengths": ({k: v for k, v in mdm.items() if k != "lengths"}, "'lengths'"),
        "long": ({**mdm, "lengths": np.array([31, 1, 1, 1])}, "'lengths'"),
        "reps": ({**mdm, "num_repetitions": 3}, "num_repetitions"),
    }
    for name, (content, key) in cases.items():
        path = tmp_path / f"{name}.npy"
        np.save(path, content)
        with pytest.raises(MalformedDataError, match=key) as err:
            load_mdm(path)
        assert f"{name}.npy" in str(err.value)
    plain = tmp_path / "plain.npy"
    np.save(plain, np.zeros(3))
    for loader in (load_haps, load_mdm):
        with pytest.raises(MalformedDataError, match=r"plain\.npy"):
            loader(plain)
