"""Checks of a camera's arguments: image size, field of view, camera name, geom groups, MSAA.

Each raises :class:`~havln_mj.errors.InvalidArgumentError` naming the value and what is valid.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence

import mujoco

from havln_mj.errors import InvalidArgumentError, did_you_mean

MAX_SIZE = 8192
"""Largest accepted image width or height, in pixels."""

MAX_MSAA_SAMPLES = 16
"""Largest accepted ``msaa_samples``."""

_NGROUP = int(mujoco.mjNGROUP)


def check_size(name: str, value: object) -> int:
    """An image side in pixels, an int in [1, :data:`MAX_SIZE`]."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise InvalidArgumentError(f"{name} must be an int, got {value!r}")
    if not 1 <= int(value) <= MAX_SIZE:
        raise InvalidArgumentError(f"{name} must be in [1, {MAX_SIZE}], got {value!r}")
    return int(value)


def check_vfov(value: object) -> float:
    """A vertical field of view in degrees, in (0, 180)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InvalidArgumentError(f"vfov_deg must be a number, got {value!r}")
    deg = float(value)
    if not (math.isfinite(deg) and 0.0 < deg < 180.0):
        raise InvalidArgumentError(f"vfov_deg must be in (0, 180) degrees, got {value!r}")
    return deg


def camera_id(model: mujoco.MjModel, camera: object) -> int:
    """The id of the model camera named ``camera`` (the error lists the valid names)."""
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_CAMERA, i) for i in range(model.ncam)]
    if not isinstance(camera, str):
        raise InvalidArgumentError(f"camera must be a camera name (str), got {camera!r}")
    cam_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
    if cam_id < 0:
        valid = ", ".join(repr(n) for n in names if n) or "none (the model has no named camera)"
        raise InvalidArgumentError(
            f"Unknown camera {camera!r}; valid cameras: {valid}."
            f"{did_you_mean(camera, [n for n in names if n])}"
        )
    return cam_id


def check_groups(groups: Sequence[int] | None) -> list[int] | None:
    """Geom groups to draw as a list of ints in [0, 5], or None."""
    if groups is None:
        return None
    if isinstance(groups, str | bytes) or not isinstance(groups, Sequence):
        raise InvalidArgumentError(f"geom_groups must be a sequence of ints, got {groups!r}")
    out = []
    for g in groups:
        if isinstance(g, bool) or not isinstance(g, numbers.Integral) or not 0 <= g < _NGROUP:
            raise InvalidArgumentError(
                f"geom_groups entries must be ints in [0, {_NGROUP - 1}], got {g!r} in {groups!r}"
            )
        out.append(int(g))
    return out


def check_msaa(samples: object) -> int:
    """Multisamples of the offscreen buffer, an int in [0, :data:`MAX_MSAA_SAMPLES`]."""
    if (
        isinstance(samples, bool)
        or not isinstance(samples, numbers.Integral)
        or not 0 <= samples <= MAX_MSAA_SAMPLES
    ):
        raise InvalidArgumentError(
            f"msaa_samples must be an int in [0, {MAX_MSAA_SAMPLES}], got {samples!r}"
        )
    return int(samples)
