"""What the loaders return, and the steps they share: reading files, SMPL poses to our frame.

SMPL poses are local rotations about SMPL-frame axes, the root one mapping the model into the
source's world. With ``W`` the source-world → our-world rotation and ``C`` = SMPL → body
(:data:`~havln_mj.humans.skeleton.SMPL_TO_BODY`), FK in our frame reproduces the source's
joints when ``q_j = C R_j C⁻¹`` for j ≥ 1, ``q_0 = W R_0 C⁻¹`` and the offsets are
``C (J_j − J_parent)``. The pelvis is the source's pelvis mapped by ``W``.
"""

from __future__ import annotations

import dataclasses
import pickle
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from havln_mj.errors import InvalidArgumentError, MalformedDataError, MissingDataError
from havln_mj.humans import rotations as rot
from havln_mj.humans import skeleton
from havln_mj.humans.clip import Clip
from havln_mj.humans.smpl_model import SmplModel

DEFAULT_HEIGHT = 1.70
FOOT_JOINTS = tuple(
    skeleton.JOINT[n] for n in ("left_ankle", "right_ankle", "left_foot", "right_foot")
)


@dataclass(frozen=True)
class LoadedMotion(Clip):
    """A clip read from a user's motion file, with what it takes to reproduce the source.

    Attributes:
        offsets: Rest joint offsets ``(24, 3)`` in our body frame that FK must use to reproduce
            the source's joints (None in segment mode).
        betas: The source's shape coefficients, if any.
        model: The SMPL model the offsets came from, or None (built-in proportions).
        source: The file read.
    """

    offsets: np.ndarray | None = None
    betas: np.ndarray | None = None
    model: SmplModel | None = None
    source: str = ""

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.local is not None and (
            self.offsets is None or self.offsets.shape != (skeleton.NUM_JOINTS, 3)
        ):
            shape = None if self.offsets is None else self.offsets.shape
            raise InvalidArgumentError(f"a rotation clip needs offsets (24, 3), got {shape}")

    def joint_positions(self) -> np.ndarray:
        """Joint positions ``(T, 24, 3)`` of every frame (FK with :attr:`offsets`)."""
        if self.local is None:
            return self.positions
        return skeleton.forward_kinematics(self.offsets, self.local, self.root)[0]

    def vertices(self, frames: np.ndarray | slice | int = slice(None)) -> np.ndarray:
        """Skinned mesh vertices ``(..., V, 3)`` of ``frames`` (needs :attr:`model`)."""
        if self.model is None or self.local is None:
            raise InvalidArgumentError(
                f"{self.source or self.name}: skinning needs an SMPL model and rotations"
            )
        return self.model.skin(self.betas, self.local[frames], self.root[frames])

    def resampled(self, fps: float) -> LoadedMotion:
        """The same motion at ``fps`` (slerp), keeping offsets, shape and model."""
        clip = super().resampled(fps)
        return dataclasses.replace(
            self,
            root=clip.root,
            fps=clip.fps,
            local=clip.local,
            positions=clip.positions,
            loop_start=clip.loop_start,
        )


def check_path(path: str | Path, what: str) -> Path:
    """The path as a ``Path``; raises :class:`~havln_mj.errors.MissingDataError` if no file."""
    path = Path(path)
    if not path.is_file():
        raise MissingDataError(f"{what} not found: {path}")
    return path


def read_pickled_dict(path: Path, what: str) -> dict:
    """The dict stored by ``np.save(path, {...})`` (a 0-d object array)."""
    try:
        data = np.load(path, allow_pickle=True)
    except (OSError, ValueError, EOFError, pickle.UnpicklingError) as exc:
        raise MalformedDataError(f"{path}: not a readable {what} .npy ({exc})") from exc
    if isinstance(data, np.ndarray) and data.dtype == object and data.ndim == 0:
        data = data.item()
    if not isinstance(data, dict):
        raise MalformedDataError(
            f"{path}: expected a {what} (a dict saved with np.save), got {type(data).__name__}"
        )
    return data


def array(
    data: Mapping, key: str, path: Path, shape: tuple[int | None, ...], what: str
) -> np.ndarray:
    """``data[key]`` as a float array of ``shape`` (None = any size); format errors name both."""
    if key not in data:
        raise MalformedDataError(f"{path}: {what} lacks key {key!r} (has {sorted(data)})")
    try:
        arr = np.asarray(data[key], dtype=float)
    except (TypeError, ValueError) as exc:
        raise MalformedDataError(f"{path}: {key!r} is not numeric ({exc})") from exc
    if arr.ndim != len(shape) or any(
        s is not None and s != n for s, n in zip(shape, arr.shape, strict=True)
    ):
        want = "(" + ", ".join("N" if s is None else str(s) for s in shape) + ")"
        raise MalformedDataError(f"{path}: {key!r} has shape {arr.shape}, expected {want}")
    if not np.all(np.isfinite(arr)):
        raise MalformedDataError(f"{path}: {key!r} holds non-finite values")
    return arr


def check_fps(fps: float | None) -> None:
    """Raises :class:`~havln_mj.errors.InvalidArgumentError` unless ``fps`` is None or > 0."""
    if fps is not None and not (np.isfinite(fps) and fps > 0):
        raise InvalidArgumentError(f"fps must be positive, got {fps!r}")


def from_smpl_pose(
    rotations: np.ndarray,
    pelvis: np.ndarray,
    world: np.ndarray,
    fps: float,
    *,
    out_fps: float | None,
    model: SmplModel | None,
    betas: np.ndarray | None,
    height: float,
    name: str,
    source: Path,
) -> LoadedMotion:
    """A clip in our frame from SMPL poses.

    Args:
        rotations: SMPL local rotations ``(T, 24, 4)`` (SMPL-frame axes; joint 0 maps the
            model into the source world).
        pelvis: Pelvis positions ``(T, 3)`` in the source world.
        world: Source world → our world rotation ``(3, 3)``.
        fps: The source rate.
        out_fps: Rate to resample to (None: keep ``fps``).
        model: The user's SMPL model (offsets from it and ``betas``), or None: our
            proportions for ``height`` and feet put on the floor (the source pelvis height
            belongs to a different skeleton).
        betas: Shape coefficients for ``model``.
        height: Body height for the built-in proportions.
        name: Clip name.
        source: The file read (for messages).
    """
    check_fps(out_fps)
    if not (np.isfinite(height) and height > 0):
        raise InvalidArgumentError(f"height must be positive metres, got {height!r}")
    local = skeleton.smpl_to_body_rotations(rotations)
    # Root: q_0 = W R_0 C⁻¹ = (W C⁻¹) ⊗ (C R_0 C⁻¹).
    lead = rot.from_matrix(world @ skeleton.SMPL_TO_BODY.T)
    local[:, 0] = rot.mul(lead, local[:, 0])
    root = pelvis @ np.asarray(world, float).T
    offsets = model.rest_offsets(betas) if model else skeleton.rest_offsets(height)
    if model is None:
        pos = skeleton.forward_kinematics(offsets, local, root)[0]
        rest = skeleton.rest_positions(height)[list(FOOT_JOINTS), 2].min()
        root = root + np.array([0.0, 0.0, rest - pos[:, list(FOOT_JOINTS), 2].min()])
    clip = LoadedMotion(
        root,
        float(fps),
        local=local,
        name=name,
        offsets=offsets,
        betas=None if betas is None else np.asarray(betas, float),
        model=model,
        source=str(source),
    )
    return clip if out_fps is None or out_fps == fps else clip.resampled(out_fps)
