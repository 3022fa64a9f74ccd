"""HAPS motions (HA3D's MDM clips fitted with SMPL): ``<rep>_smpl_params.npy`` files.

Each file is a dict saved with ``np.save``: ``thetas`` (24, 6, T) SMPL local rotations in
6-D form (first two matrix rows, PyTorch3D's convention), ``root_translation`` (3, T) the
pelvis trajectory MDM generated (SMPLify's target, so no J0 is added), and ``motion``
(25, 6, T) holding both (row 24 = translation in its first 3 numbers); optional
``vertices``, ``text``, ``length``. 20 fps, SMPL's y-up frame, so the world maps to ours
with the SMPL → body rotation, and a person facing +z there faces +y (heading 0) here.

A HAPS download is laid out as ``human_motion_meshes/<prompt, ' ' and '/' → '_'>/`` with
``<rep>_smpl_params.npy`` for reps 0–2; :func:`load_haps_folder` reads all of it.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from havln_mj.errors import MalformedDataError, MissingDataError
from havln_mj.humans import rotations as rot
from havln_mj.humans.loaders.motion import (
    DEFAULT_HEIGHT,
    LoadedMotion,
    array,
    check_path,
    from_smpl_pose,
    read_pickled_dict,
)
from havln_mj.humans.skeleton import NUM_JOINTS, SMPL_TO_BODY
from havln_mj.humans.smpl_model import SmplModel

HAPS_FPS = 20.0
_SUFFIX = "_smpl_params.npy"
_WHAT = "HAPS motion"


def haps_dir_name(text: str) -> str:
    """The folder HAPS stores a prompt's motions in (spaces and slashes become ``_``)."""
    return text.replace(" ", "_").replace("/", "_")


def load_haps(
    path: str | Path,
    *,
    fps: float | None = None,
    model: SmplModel | None = None,
    betas: np.ndarray | None = None,
    height: float = DEFAULT_HEIGHT,
) -> LoadedMotion:
    """Reads one ``<rep>_smpl_params.npy`` into a clip in our frame.

    Args:
        path: The file.
        fps: Rate to resample to with slerp (None: HAPS's 20 fps).
        model: The user's SMPL model: offsets from it (HAPS meshes use the mean shape, so
            ``betas`` defaults to zeros). Without one, our proportions for ``height`` and
            the feet put on the floor.
        betas: Shape coefficients for ``model``.
        height: Body height (m) for the built-in proportions.

    Raises:
        MissingDataError: No such file.
        MalformedDataError: The file is not such a dict, or lacks a key or has a wrong shape.
    """
    path = check_path(path, "HAPS motion file")
    data = read_pickled_dict(path, _WHAT)
    if "thetas" in data or "motion" not in data:
        r6d = array(data, "thetas", path, (NUM_JOINTS, 6, None), _WHAT)
        trans = array(data, "root_translation", path, (3, r6d.shape[2]), _WHAT)
    else:
        motion = array(data, "motion", path, (NUM_JOINTS + 1, 6, None), _WHAT)
        r6d, trans = motion[:NUM_JOINTS], motion[NUM_JOINTS, :3]
    frames = r6d.shape[2]
    if "length" in data:
        try:
            frames = min(frames, int(np.asarray(data["length"]).ravel()[0]))
        except (TypeError, ValueError, IndexError) as exc:
            raise MalformedDataError(f"{path}: 'length' is not a frame count") from exc
    if frames < 1:
        raise MalformedDataError(f"{path}: HAPS motion has no frames")
    rotations = rot.from_rot6d(np.moveaxis(r6d[..., :frames], -1, 0))  # (T, 24, 4)
    pelvis = trans[:, :frames].T
    text = data.get("text")
    return from_smpl_pose(
        rotations,
        pelvis,
        SMPL_TO_BODY,
        HAPS_FPS,
        out_fps=fps,
        model=model,
        betas=betas,
        height=height,
        name=str(text) if isinstance(text, str) and text else path.parent.name,
        source=path,
    )


def load_haps_folder(
    folder: str | Path,
    *,
    fps: float | None = None,
    model: SmplModel | None = None,
    height: float = DEFAULT_HEIGHT,
) -> dict[str, list[LoadedMotion]]:
    """Reads every HAPS motion under ``folder``, grouped by prompt folder.

    Args:
        folder: ``human_motion_meshes`` itself or a folder containing it.
        fps: Rate to resample to (None: 20 fps).
        model: The user's SMPL model (see :func:`load_haps`).
        height: Body height for the built-in proportions.

    Returns:
        ``{folder name: [clip of rep 0, rep 1, ...]}``; the folder name is the prompt as
        :func:`haps_dir_name` writes it, so a caller holding HA3D's ``"region:activity"``
        text finds its clips under ``haps_dir_name(text)``.

    Raises:
        MissingDataError: The folder does not exist or holds no ``*_smpl_params.npy``.
    """
    folder = Path(folder)
    if (folder / "human_motion_meshes").is_dir():
        folder = folder / "human_motion_meshes"
    if not folder.is_dir():
        raise MissingDataError(f"HAPS folder not found: {folder}")
    out: dict[str, list[LoadedMotion]] = {}
    for sub in sorted(p for p in folder.iterdir() if p.is_dir()):
        files = sorted(sub.glob(f"*{_SUFFIX}"), key=_rep_index)
        if files:
            out[sub.name] = [load_haps(f, fps=fps, model=model, height=height) for f in files]
    if not out:
        raise MissingDataError(
            f"no HAPS motions (<prompt>/<rep>{_SUFFIX}) under {folder}; expected HAPS's "
            "human_motion_meshes folder"
        )
    return out


def _rep_index(path: Path) -> tuple[int, str]:
    match = re.match(r"(\d+)", path.name)
    return (int(match.group(1)) if match else 1 << 30, path.name)
