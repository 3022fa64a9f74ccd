"""Building a standing or seated clip: arm presets, a pose builder and loop helpers.

:class:`PoseBuilder` holds a clip under construction in the anchor frame (origin on the floor
at the person's spot, z up, facing +y): pelvis, trunk, head and arms set by angle, the legs
solved by IK so the feet stay planted. The recipes in :mod:`~havln_mj.humans.motion.behaviours`
build on it.
"""

from __future__ import annotations

import math

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.humans import rotations as rot
from havln_mj.humans.clip import Clip
from havln_mj.humans.motion import joints as jt
from havln_mj.humans.motion.gait import FPS
from havln_mj.humans.skeleton import JOINT, MAX_HEIGHT, MIN_HEIGHT, NUM_JOINTS, rest_offsets

# Arm presets (shoulder flexion, elbow flexion, abduction, horizontal adduction), radians,
# fitted once with forward kinematics to put the hands where the names say.
HANG = (0.03, 0.15, 0.14, 0.0)
THIGHS = (0.0, 1.3, 0.0, 0.1)  # seated, hands resting on the thighs
BOOK = (0.37, 1.27, 0.1, 0.4)  # holding something in front of the chest
GESTURE = (0.18, 1.4, 0.14, 0.13)  # forearms up, hands at chest height
COUNTER = (0.55, 1.1, 0.1, 0.3)  # hands working at a counter in front of the waist
OVERHEAD = (2.85, 0.15, 0.1, 0.0)
STANCE_X, STANCE_Y = 0.055, -0.012  # standing feet beside the pelvis, fraction of height


def check_height(height: float) -> float:
    """``height`` as a float; raises InvalidArgumentError outside the skeleton's range."""
    if not (math.isfinite(height) and MIN_HEIGHT <= height <= MAX_HEIGHT):
        raise InvalidArgumentError(
            f"height must be in {MIN_HEIGHT}..{MAX_HEIGHT} m, got {height!r}"
        )
    return float(height)


def check_choice(what: str, value: str, valid: tuple[str, ...]) -> None:
    """Raises InvalidArgumentError naming ``what`` when ``value`` is not in ``valid``."""
    if value not in valid:
        raise InvalidArgumentError(f"unknown {what} {value!r}; valid: {', '.join(valid)}")


def loop_times(duration: float, least: float = 1.0) -> np.ndarray:
    """Frame times of one loop, both ends included (a whole number of frames)."""
    if not (math.isfinite(duration) and duration >= least):
        raise InvalidArgumentError(f"duration must be at least {least} s, got {duration!r}")
    return np.arange(round(duration * FPS) + 1) / FPS


def wave(
    rng: np.random.Generator, t: np.ndarray, period: float, hz: float, amp: float
) -> np.ndarray:
    """A sine of about ``hz`` with a whole number of cycles per ``period`` and a random phase."""
    cycles = max(1, round(hz * period))
    return amp * np.sin(2 * np.pi * cycles * t / period + rng.uniform(0, 2 * np.pi))


def minjerk(x: np.ndarray) -> np.ndarray:
    """The minimum-jerk ease from 0 to 1 over ``x`` in [0, 1] (clipped outside)."""
    x = np.clip(x, 0.0, 1.0)
    return x**3 * (10 - 15 * x + 6 * x**2)


class PoseBuilder:
    """A clip under construction: pelvis, trunk, head and arms by angle, legs by IK."""

    def __init__(self, height: float, n: int):
        self.height = height
        self.offsets = rest_offsets(height)
        self.local = np.tile(rot.identity(), (n, NUM_JOINTS, 1))
        self.root = np.zeros((n, 3))
        self.root[:, 2] = (0.575 - 0.005) * height  # knees soft
        self.pelvis = rot.identity((n,))
        self.chest = rot.identity((n,))

    def set_pelvis(self, q: np.ndarray) -> None:
        """The pelvis's world orientation, per frame or one for all."""
        self.pelvis = np.broadcast_to(q, self.pelvis.shape).copy()
        self.local[:, 0] = self.pelvis

    def set_trunk(self, chest_world: np.ndarray, head_world: np.ndarray) -> None:
        """World orientations of the chest and head; the spine and neck joints share the turn."""
        self.chest = np.broadcast_to(chest_world, self.pelvis.shape)
        jt.set_spine(self.local, rot.mul(rot.conj(self.pelvis), self.chest))
        jt.set_neck(self.local, rot.mul(rot.conj(self.chest), head_world))

    def set_arm(self, side: float, preset: tuple, **delta: np.ndarray | float) -> None:
        """An arm at ``preset`` plus offsets, e.g. ``flex=...``, ``elbow=...``."""
        names = ("flex", "elbow", "abduct", "across")
        angles = [
            np.asarray(v, float) + delta.get(k, 0.0) for k, v in zip(names, preset, strict=True)
        ]
        jt.set_arm(self.local, side, *angles)

    def plant_feet(
        self,
        spread: float = STANCE_X,
        forward: float = STANCE_Y,
        pitch: np.ndarray | float = 0.0,
        lift: np.ndarray | float = 0.0,
    ) -> None:
        """Feet on the floor beside the anchor (toes slightly out); legs by IK."""
        n, h = len(self.root), self.height
        for side in (jt.LEFT, jt.RIGHT):
            ground = np.zeros((n, 2))
            ground[:, 0] = side * np.asarray(spread, float) * h
            ground[:, 1] = forward * h
            yaw = np.full(n, -side * 0.1)
            ankle, foot = jt.ankle_from_contact(h, ground, yaw, np.broadcast_to(pitch, n), lift)
            self.legs(side, ankle, foot)

    def legs(self, side: float, ankle: np.ndarray, foot: np.ndarray) -> None:
        """One leg reaching ``ankle`` with the foot at ``foot``, by IK."""
        name = "right" if side > 0 else "left"
        hip = self.root + rot.rotate(self.pelvis, self.offsets[JOINT[f"{name}_hip"]])
        hq, kq, aq = jt.leg_ik(self.offsets, side, hip, self.pelvis, ankle, foot)
        self.local[:, JOINT[f"{name}_hip"]] = hq
        self.local[:, JOINT[f"{name}_knee"]] = kq
        self.local[:, JOINT[f"{name}_ankle"]] = aq

    def clip(self, name: str, loop_start: int = 0) -> Clip:
        """The finished clip, named ``name``, looping from frame ``loop_start``."""
        return Clip(
            self.root.copy(), FPS, local=rot.normalize(self.local), loop_start=loop_start, name=name
        )
