"""When and how the collision signal is measured, and which clock people follow.

Two protocols are supported, each a pair of small frozen settings the simulator's batch uses:

* **Strict** (the default, :meth:`CollisionRule.strict` and :meth:`HumanClock.continuous`):
  the signal covers every action continuously (sampled at ≥ 16 Hz along the body's track,
  :func:`~havln_mj.sim.proximity.knots_proximity`), measured horizontally from the agent's base
  to each person's pelvis; people follow each element's own simulated time, which every
  action advances by its duration.
* **HA3D** (:meth:`CollisionRule.ha3d` and :meth:`HumanClock.ha3d`), the rules of the HA3D
  simulator's code (``HA3DSim.py`` and ``src/utils/get_info.py`` of the public
  ``HA3D_simulator`` repository):

  - the signal is computed only in the state after each action and in the start state
    (``HASimulator.getState``), at the viewpoint the agent stands on;
  - it is the 3-D distance from the agent's camera (the viewpoint's position) to one
    tracked point per person (``getHumanLocations``: a mesh vertex near the body's floor
    origin, lifted by the 1.36 m HA3D placed bodies below the camera); here the pelvis's
    horizontal position at :data:`~havln_mj.sim.crowd.HA3D_TRACK_HEIGHT` above the
    person's floor (:func:`~havln_mj.sim.crowd.ha3d_points`);
  - people follow one clock of 120 frames shared by every episode (``frameNum``): the
    start state advances it 16 frames (``getState(16)``), every action 32 (``makeAction``
    then ``getState(16)``), and it restarts at 0 when it reaches 120 (reset, not wrapped);
    frame ``f`` is ``f / 20`` seconds of the people's motions (HAPS clips: 120 frames at
    20 fps).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

from havln_mj.errors import InvalidArgumentError
from havln_mj.sim.crowd import COLLISION_DISTANCE

CHECKS = ("action", "state")
DISTANCES = ("horizontal", "camera_3d")
CLOCKS = ("continuous", "ha3d")


@dataclass(frozen=True)
class CollisionRule:
    """How the simulator decides that the agent collided with a person.

    Attributes:
        check: ``"action"``: anywhere along every action (the start state included);
            ``"state"``: only in the state after each action and the start state.
        distance: ``"horizontal"``: from the body's base to each pelvis, horizontally;
            ``"camera_3d"``: from the camera at the state's viewpoint to each person's
            HA3D tracked point (see :func:`~havln_mj.sim.crowd.ha3d_points`), in 3-D.
        threshold: Collision when the distance is at most this (metres).
    """

    check: str = "action"
    distance: str = "horizontal"
    threshold: float = COLLISION_DISTANCE

    def __post_init__(self) -> None:
        if self.check not in CHECKS:
            raise InvalidArgumentError(f"collision check {self.check!r} unknown; valid: {CHECKS}")
        if self.distance not in DISTANCES:
            raise InvalidArgumentError(
                f"collision distance {self.distance!r} unknown; valid: {DISTANCES}"
            )
        if self.check == "action" and self.distance != "horizontal":
            raise InvalidArgumentError(
                "the continuous collision check measures horizontally (distance='horizontal')"
            )
        t = self.threshold
        if isinstance(t, bool) or not isinstance(t, numbers.Real) or not math.isfinite(t) or t <= 0:
            raise InvalidArgumentError(f"collision threshold must be metres > 0, got {t!r}")

    @classmethod
    def strict(cls, threshold: float = COLLISION_DISTANCE) -> CollisionRule:
        """Continuously along every action, horizontally from base to pelvis."""
        return cls("action", "horizontal", threshold)

    @classmethod
    def ha3d(cls, threshold: float = COLLISION_DISTANCE) -> CollisionRule:
        """HA3D's: in each state, 3-D from the camera to each person's tracked point."""
        return cls("state", "camera_3d", threshold)


@dataclass(frozen=True)
class HumanClock:
    """Which time people are posed at.

    Attributes:
        kind: ``"continuous"``: each element's own simulated time; ``"ha3d"``: HA3D's shared
            frame counter (see the module docstring).
        frames: HA3D's clip length in frames (the counter restarts at 0 on reaching it).
        fps: Frames per second of the people's motions.
        start_frames: Frames the start of a batch of episodes advances the counter by.
        step_frames: Frames every action advances it by (in two halves, each followed by
            the restart check, as ``makeAction`` and ``getState`` do).
    """

    kind: str = "continuous"
    frames: int = 120
    fps: float = 20.0
    start_frames: int = 16
    step_frames: int = 32

    def __post_init__(self) -> None:
        if self.kind not in CLOCKS:
            raise InvalidArgumentError(f"human clock {self.kind!r} unknown; valid: {CLOCKS}")
        for name in ("frames", "start_frames", "step_frames"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, numbers.Integral) or v < 1:
                raise InvalidArgumentError(f"human clock {name} must be an integer ≥ 1, got {v!r}")
        if self.step_frames % 2:
            raise InvalidArgumentError(
                f"human clock step_frames must be even (two halves), got {self.step_frames}"
            )
        f = self.fps
        if isinstance(f, bool) or not isinstance(f, numbers.Real) or not math.isfinite(f) or f <= 0:
            raise InvalidArgumentError(f"human clock fps must be > 0, got {f!r}")

    @classmethod
    def continuous(cls) -> HumanClock:
        """People follow each element's simulated time."""
        return cls("continuous")

    @classmethod
    def ha3d(cls) -> HumanClock:
        """HA3D's shared 120-frame counter: +16 at a start, +32 per action, reset at 120."""
        return cls("ha3d")

    def advance(self, frame: int, frames: int) -> int:
        """The counter after ``frames`` more (HA3D: reset to 0 once it reaches the end)."""
        frame += frames
        return 0 if frame >= self.frames else frame

    def after_start(self, frame: int) -> int:
        """The counter after a batch of episodes starts."""
        return self.advance(frame, self.start_frames)

    def after_action(self, frame: int) -> int:
        """The counter after an action (``makeAction``, then ``getState``)."""
        half = self.step_frames // 2
        return self.advance(self.advance(frame, half), half)

    def seconds(self, frame: int) -> float:
        """The people's time at ``frame``."""
        return frame / self.fps


def collision_rule_of(value: object, threshold: float) -> CollisionRule:
    """The rule ``collision_rule=`` names (a name uses ``threshold``)."""
    if isinstance(value, CollisionRule):
        return value
    named = {"strict": CollisionRule.strict, "ha3d": CollisionRule.ha3d}
    if isinstance(value, str) and value in named:
        return named[value](threshold)
    raise InvalidArgumentError(
        f"collision_rule {value!r} unknown; valid: 'strict', 'ha3d' or a CollisionRule"
    )


def human_clock_of(value: object) -> HumanClock:
    """The clock ``human_clock=`` names."""
    if isinstance(value, HumanClock):
        return value
    named = {"continuous": HumanClock.continuous, "ha3d": HumanClock.ha3d}
    if isinstance(value, str) and value in named:
        return named[value]()
    raise InvalidArgumentError(
        f"human_clock {value!r} unknown; valid: 'continuous', 'ha3d' or a HumanClock"
    )


def check_pair(rule: CollisionRule, clock: HumanClock, reactions: object | None) -> None:
    """Refuses what HA3D's clock cannot do: people posed between states, or reacting.

    Raises:
        InvalidArgumentError: HA3D's clock with a per-action check, or with reactions.
    """
    if clock.kind == "ha3d" and rule.check != "state":
        raise InvalidArgumentError(
            "HA3D's human clock poses people only in states: it needs a per-state collision "
            "check (collision_rule='ha3d'), not the continuous one"
        )
    if clock.kind == "ha3d" and reactions is not None:
        raise InvalidArgumentError(
            "HA3D's human clock needs people who do not react (reactions=False): on one "
            "shared frame counter there is no track for them to react to"
        )
