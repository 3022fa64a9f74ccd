"""Smooth transitions between clips: one clip plays, then crossfades into the next.

Rotations are slerped and the pelvis interpolated with a smoothstep weight. The result
keeps looping the last clip's loop, so it can end in any looping recipe.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.humans import rotations as rot
from havln_mj.humans.clip import Clip


def blend(a: Clip, b: Clip, seconds: float = 0.5) -> Clip:
    """``a`` once, then ``b``, crossfading over the last ``seconds`` of ``a``.

    Both clips must be in the same anchor frame (the pelvis is interpolated, not moved).
    ``b`` is resampled to ``a``'s rate if needed and plays from its start; the result loops
    ``b``'s loop.

    Args:
        a: The clip played first (all of it, looping part once).
        b: The clip that follows.
        seconds: Length of the crossfade (clipped to ``a``'s duration).

    Raises:
        InvalidArgumentError: Negative or non-finite ``seconds``, or one clip holds joint
            rotations and the other joint positions.
    """
    if not (math.isfinite(seconds) and seconds >= 0):
        raise InvalidArgumentError(f"blend seconds must be ≥ 0, got {seconds!r}")
    if (a.local is None) != (b.local is None):
        raise InvalidArgumentError(
            f"cannot blend {a.name!r} and {b.name!r}: one has joint rotations, the other "
            "joint positions"
        )
    if b.fps != a.fps:
        b = b.resampled(a.fps)
    k = min(round(seconds * a.fps), a.frames - 1)
    period = b.frames - 1 - b.loop_start
    start = max(k, b.loop_start)  # where the result's loop begins, in b's frames
    end = start + period if period > 0 else max(k, b.frames - 1)
    pose_b, root_b = b.sample(np.arange(end + 1) / b.fps)
    pose_a = a.local if a.local is not None else a.positions
    head = a.frames - k
    w = np.arange(1, k + 1) / (k + 1)
    w = w * w * (3 - 2 * w)
    if a.local is not None:
        mixed = rot.slerp(pose_a[head:], pose_b[:k], w[:, None])
    else:
        mixed = pose_a[head:] + w[:, None, None] * (pose_b[:k] - pose_a[head:])
    root_mixed = a.root[head:] + w[:, None] * (root_b[:k] - a.root[head:])
    pose = np.concatenate([pose_a[:head], mixed, pose_b[k:]])
    root = np.concatenate([a.root[:head], root_mixed, root_b[k:]])
    kind = "local" if a.local is not None else "positions"
    loop_start = head + (start if period > 0 else end)
    return Clip(root, a.fps, loop_start=loop_start, name=f"{a.name}+{b.name}", **{kind: pose})


def sequence(clips: Sequence[Clip], blend_s: float = 0.5) -> Clip:
    """The clips one after another with crossfades, looping the last one's loop.

    Raises:
        InvalidArgumentError: No clips given (see also :func:`blend`).
    """
    if not clips:
        raise InvalidArgumentError("sequence needs at least one clip")
    out = clips[0]
    for nxt in clips[1:]:
        out = blend(out, nxt, blend_s)
    return out
