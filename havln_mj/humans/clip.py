"""A motion clip: a person's pose sampled at a fixed rate, played as a function of time.

A clip is in the person's *anchor frame*: z up, the origin on the floor where the person is
placed, facing +y at heading 0 (see :mod:`havln_mj.humans.skeleton`). The crowd places the
anchor in the world. Poses are either local joint rotations plus the pelvis position (the
usual case; forward kinematics gives the joints) or, for position-only sources such as MDM
output, the joint positions themselves ("segment mode": bones are drawn between joints).

Playback: frame ``k`` is at ``k / fps`` seconds; between frames rotations are slerped and
positions interpolated linearly. Past the end the clip loops from ``loop_start`` (0 loops the
whole clip; a later frame plays an intro once, e.g. sitting down, then loops the rest). The
looping part must end where it starts: its last frame is played as frame ``loop_start``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.humans import rotations as rot
from havln_mj.humans.skeleton import NUM_JOINTS


@dataclass(frozen=True)
class Clip:
    """A sampled motion.

    Attributes:
        root: Pelvis positions ``(T, 3)`` in the anchor frame.
        fps: Frames per second.
        local: Local joint rotations ``(T, 24, 4)``, or None in segment mode.
        positions: Joint positions ``(T, 24, 3)`` in the anchor frame (segment mode), else None.
        loop_start: First frame of the looping part.
        name: What the clip shows (for logs and tests).
    """

    root: np.ndarray
    fps: float
    local: np.ndarray | None = None
    positions: np.ndarray | None = None
    loop_start: int = 0
    name: str = ""

    def __post_init__(self) -> None:
        n = len(self.root)
        if self.root.shape != (n, 3) or n == 0:
            raise InvalidArgumentError(
                f"clip root must be (T, 3) with T ≥ 1, got {self.root.shape}"
            )
        if (self.local is None) == (self.positions is None):
            raise InvalidArgumentError("a clip has either local rotations or joint positions")
        if self.local is not None and self.local.shape != (n, NUM_JOINTS, 4):
            raise InvalidArgumentError(f"clip local must be ({n}, 24, 4), got {self.local.shape}")
        if self.positions is not None and self.positions.shape != (n, NUM_JOINTS, 3):
            raise InvalidArgumentError(
                f"clip positions must be ({n}, 24, 3), got {self.positions.shape}"
            )
        if not (np.isfinite(self.fps) and self.fps > 0):
            raise InvalidArgumentError(f"clip fps must be positive, got {self.fps!r}")
        if not 0 <= self.loop_start < n:
            raise InvalidArgumentError(f"loop_start {self.loop_start} outside 0..{n - 1}")

    @property
    def frames(self) -> int:
        """Number of frames."""
        return len(self.root)

    @property
    def duration(self) -> float:
        """Seconds from the first to the last frame."""
        return (self.frames - 1) / self.fps

    def frame_time(self, t: np.ndarray | float) -> np.ndarray:
        """Fractional frame indices for times ``t`` (seconds), looping as described above."""
        f = np.asarray(t, float) * self.fps
        last, start = self.frames - 1, self.loop_start
        if last == 0:
            return np.zeros_like(f)
        period = last - start
        if period == 0:
            return np.clip(f, 0.0, last)
        # The loop wraps from the last frame back to loop_start, so a loop spans `period`.
        return np.where(f <= last, np.maximum(f, 0.0), start + np.mod(f - start, period))

    def blend_frames(self, t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The two frames around times ``t`` and the weight of the second: ``(i0, i1, w)``."""
        if isinstance(t, float):  # one instant, every frame of playback: plain arithmetic
            f, last, start = t * self.fps, self.frames - 1, self.loop_start
            if f > last and last > start:
                f = start + (f - start) % (last - start)
            f = min(max(f, 0.0), float(last))
            i0 = int(f)
            return i0, min(i0 + 1, last), f - i0
        f = self.frame_time(t)
        i0 = np.floor(f).astype(int)
        return i0, np.minimum(i0 + 1, self.frames - 1), f - i0

    def root_at(self, t: np.ndarray | float) -> np.ndarray:
        """Pelvis positions ``(..., 3)`` at times ``t`` (cheaper than a full ``sample``)."""
        i0, i1, w = self.blend_frames(t)
        w = np.asarray(w)
        return self.root[i0] + w[..., None] * (self.root[i1] - self.root[i0])

    def sample(self, t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """Pose at times ``t`` (any shape).

        Returns:
            ``(local or positions, root)``: local rotations ``(..., 24, 4)`` (or joint
            positions ``(..., 24, 3)`` in segment mode) and pelvis positions ``(..., 3)``.
        """
        i0, i1, w = self.blend_frames(t)
        w = np.asarray(w)
        root = self.root[i0] + w[..., None] * (self.root[i1] - self.root[i0])
        if self.local is not None:
            return rot.slerp(self.local[i0], self.local[i1], w[..., None]), root
        p0, p1 = self.positions[i0], self.positions[i1]
        return p0 + w[..., None, None] * (p1 - p0), root

    def resampled(self, fps: float) -> Clip:
        """The same motion sampled at ``fps`` (slerp for rotations)."""
        n = max(1, round(self.duration * fps) + 1)
        t = np.arange(n) / fps
        pose, root = self.sample(np.minimum(t, self.duration))
        start = min(n - 1, round(self.loop_start / self.fps * fps))
        if self.local is not None:
            return Clip(root, fps, local=pose, loop_start=start, name=self.name)
        return Clip(root, fps, positions=pose, loop_start=start, name=self.name)
