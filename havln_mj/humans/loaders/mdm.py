"""MDM text-to-motion output (``results.npy``): joint positions only, played in segment mode.

The file is a dict saved with ``np.save``: ``motion`` (N·reps, 22, 3, T) HumanML3D joint
positions (SMPL joints 0–21, metres, y up), ``text`` and ``lengths`` per sample, and
``num_samples``, ``num_repetitions`` (sample index = rep·num_samples + i). 20 fps. There are
no rotations, so no IK: clips hold the positions and bones are drawn between joints.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from havln_mj.errors import MalformedDataError
from havln_mj.humans.loaders.motion import (
    FOOT_JOINTS,
    LoadedMotion,
    array,
    check_fps,
    check_path,
    read_pickled_dict,
)
from havln_mj.humans.skeleton import JOINT, SMPL_TO_BODY

MDM_FPS = 20.0
_JOINTS = 22  # HumanML3D: SMPL without the two hand joints
_WHAT = "MDM results"


def load_mdm(path: str | Path, *, fps: float | None = None) -> list[LoadedMotion]:
    """Reads MDM's ``results.npy`` into one segment-mode clip per sample.

    Each clip is converted to our frame (y-up → z-up by the SMPL → body rotation, so MDM's
    +z facing becomes +y), trimmed to its ``lengths`` entry, given hand joints equal to the
    wrists, and shifted vertically so its lowest ankle/toe joint over the clip is at z = 0.

    Args:
        path: The ``results.npy`` file.
        fps: Rate to resample to (None: MDM's 20 fps).

    Returns:
        Clips in the file's sample order, named by their text.

    Raises:
        MissingDataError: No such file.
        MalformedDataError: The file is not such a dict, or lacks a key or has a wrong shape.
    """
    check_fps(fps)
    path = check_path(path, "MDM results file")
    data = read_pickled_dict(path, _WHAT)
    motion = array(data, "motion", path, (None, _JOINTS, 3, None), _WHAT)
    count, frames = motion.shape[0], motion.shape[3]
    lengths = array(data, "lengths", path, (count,), _WHAT).astype(int)
    if np.any(lengths < 1) or np.any(lengths > frames):
        raise MalformedDataError(f"{path}: 'lengths' {lengths.tolist()} outside 1..{frames}")
    texts = list(np.asarray(data.get("text", [""] * count), dtype=object).ravel())
    if len(texts) != count:
        raise MalformedDataError(f"{path}: 'text' has {len(texts)} entries, expected {count}")
    samples, reps = data.get("num_samples"), data.get("num_repetitions")
    if samples is not None and reps is not None and int(samples) * int(reps) != count:
        raise MalformedDataError(
            f"{path}: num_samples·num_repetitions = {int(samples)}·{int(reps)} ≠ {count} motions"
        )
    clips = []
    for i in range(count):
        joints = motion[i, :, :, : lengths[i]].transpose(2, 0, 1) @ SMPL_TO_BODY.T  # (T, 22, 3)
        pos = np.concatenate(
            [joints, joints[:, [JOINT["left_wrist"], JOINT["right_wrist"]]]], axis=1
        )
        pos[..., 2] -= pos[:, list(FOOT_JOINTS), 2].min()
        clip = LoadedMotion(
            pos[:, 0].copy(), MDM_FPS, positions=pos, name=str(texts[i]), source=str(path)
        )
        clips.append(clip if fps is None or fps == MDM_FPS else clip.resampled(fps))
    return clips
