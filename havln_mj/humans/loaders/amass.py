"""AMASS-style SMPL motion files (``.npz``: axis-angle poses, translations, frame rate).

AMASS's world is already z up: each frame's root orientation holds the change from SMPL's
y-up model frame, so the world maps to ours unchanged (``W = I``) and only the model axes are
converted (see :mod:`havln_mj.humans.loaders.motion`). As in SMPL, the root rotates about
the pelvis J0(β), whose world position is ``J0(β) + trans`` (J0 unrotated, in world axes).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from havln_mj.errors import MalformedDataError
from havln_mj.humans import rotations as rot
from havln_mj.humans.loaders.motion import (
    DEFAULT_HEIGHT,
    LoadedMotion,
    array,
    check_path,
    from_smpl_pose,
)
from havln_mj.humans.skeleton import NUM_JOINTS
from havln_mj.humans.smpl_model import SmplModel

_WHAT = "AMASS motion"
_BODY_JOINTS = 22  # SMPL-H / SMPL-X keep the body's first 22 joints; hands are separate


def load_amass(
    path: str | Path,
    *,
    fps: float | None = None,
    model: SmplModel | None = None,
    height: float = DEFAULT_HEIGHT,
) -> LoadedMotion:
    """Reads an AMASS-style ``.npz`` into a clip in our frame.

    Keys: ``poses`` (N, 72) SMPL or (N, 156/165) SMPL-H/-X (then the first 66 = 22 joints;
    the hand joints 22, 23 stay unrotated) or the SMPL-X "G" pair ``root_orient`` (N, 3) +
    ``pose_body`` (N, 63); ``trans`` (N, 3); ``mocap_framerate`` or ``mocap_frame_rate``;
    optional ``betas``.

    Args:
        path: The ``.npz`` file.
        fps: Rate to resample to with slerp (None: the source rate).
        model: The user's SMPL model: offsets and pelvis J0 from it and the file's betas, so
            FK reproduces the source joints. Without one, our proportions for ``height`` are
            used, the pelvis follows ``trans`` horizontally (J0 unknown) and the clip is
            lifted so the feet touch z = 0.
        height: Body height (m) for the built-in proportions.

    Raises:
        MissingDataError: No such file.
        MalformedDataError: The file is not an npz with the keys and shapes above.
    """
    path = check_path(path, "AMASS motion file")
    data = _read_npz(path)
    aa, joints = _axis_angles(data, path)
    n = len(aa)
    trans = array(data, "trans", path, (n, 3), _WHAT)
    rate = _frame_rate(data, path)
    betas = array(data, "betas", path, (None,), _WHAT) if "betas" in data else None

    rotations = rot.identity((n, NUM_JOINTS))
    rotations[:, :joints] = rot.from_axis_angle(aa.reshape(n, joints, 3))
    pelvis = trans + (model.joints(betas)[0] if model else 0.0)
    return from_smpl_pose(
        rotations,
        pelvis,
        np.eye(3),
        rate,
        out_fps=fps,
        model=model,
        betas=betas,
        height=height,
        name=path.stem,
        source=path,
    )


def _read_npz(path: Path) -> dict[str, np.ndarray]:
    """The file's arrays (all but ``gender``, which may be an object array)."""
    try:
        npz = np.load(path, allow_pickle=False)
    except (OSError, ValueError) as exc:
        raise MalformedDataError(f"{path}: not a readable AMASS .npz ({exc})") from exc
    with npz:
        return {k: npz[k] for k in npz.files if k != "gender"}


def _axis_angles(data: dict[str, np.ndarray], path: Path) -> tuple[np.ndarray, int]:
    """The ``(N, 3 * joints)`` axis-angle poses, and how many joints they rotate."""
    if "poses" in data:
        poses = array(data, "poses", path, (None, None), _WHAT)
        width = poses.shape[1]
        if width != 3 * NUM_JOINTS and width < 3 * _BODY_JOINTS:
            raise MalformedDataError(
                f"{path}: 'poses' has {width} columns, expected 72 (SMPL) or ≥ 66 (SMPL-H/-X)"
            )
        joints = NUM_JOINTS if width == 3 * NUM_JOINTS else _BODY_JOINTS
        aa = poses[:, : 3 * joints]
    elif "root_orient" in data:
        root = array(data, "root_orient", path, (None, 3), _WHAT)
        body = array(data, "pose_body", path, (len(root), 3 * (_BODY_JOINTS - 1)), _WHAT)
        aa = np.concatenate([root, body], axis=1)
        joints = _BODY_JOINTS
    else:
        raise MalformedDataError(
            f"{path}: AMASS motion lacks key 'poses' (or 'root_orient' + 'pose_body'); "
            f"has {sorted(data)}"
        )
    if len(aa) == 0:
        raise MalformedDataError(f"{path}: 'poses' has no frames")
    return aa, joints


def _frame_rate(data: dict[str, np.ndarray], path: Path) -> float:
    """The source frame rate (``mocap_framerate``, or SMPL-X's ``mocap_frame_rate``)."""
    rate_key = next((k for k in ("mocap_framerate", "mocap_frame_rate") if k in data), None)
    if rate_key is None:
        raise MalformedDataError(
            f"{path}: AMASS motion lacks its frame rate 'mocap_framerate' (or SMPL-X "
            f"'mocap_frame_rate'); has {sorted(data)}"
        )
    rate = array(data, rate_key, path, (None,) * np.ndim(data[rate_key]), _WHAT).ravel()
    if rate.size != 1 or not rate[0] > 0:
        raise MalformedDataError(f"{path}: {rate_key!r} = {rate}, expected one positive rate")
    return float(rate[0])
