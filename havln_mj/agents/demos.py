"""Recorded rollouts an agent learns from: one instruction, the observations and the actions.

A :class:`Demo` is what teacher forcing (VLN-CM) and offline training (VLN-DT) read. Each step
holds the observation the action was chosen from (a view feature plus the agent's own
proprioceptive inputs, see :mod:`havln_mj.agents.observations`), the egocentric action
(:class:`havln_mj.sim.egocentric.EgoAction` values), the actions valid there, and the outcome
of the action (distance to the goal after it, its change, a collision with a person, STOP),
from which any reward of :mod:`havln_mj.tasks.rewards` is computed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.tasks.rewards import (
    SUCCESS_DISTANCE,
    RewardFn,
    StepOutcome,
    get_reward,
    step_reward,
)

N_ACTIONS = 6  # STOP, FORWARD, TURN_LEFT, TURN_RIGHT, LOOK_UP, LOOK_DOWN


@dataclass(frozen=True)
class Demo:
    """One rollout of one instruction, ``T`` actions long.

    Attributes:
        instr_id: ``"<path_id>_<k>"``.
        source: Who acted: ``"expert"`` or ``"random"``.
        instruction: ``(L,)`` int64 token ids, 0-padded.
        obs: ``(T, D)`` float32 observation before each action.
        actions: ``(T,)`` int64 action taken (the last one is STOP when ``stopped``).
        masks: ``(T, 6)`` bool, the actions valid before each action.
        distance: ``(T,)`` float32 geodesic distance to the goal after each action (metres).
        delta: ``(T,)`` float32 change of that distance over the action.
        collided: ``(T,)`` bool, the action came within the collision distance of a person.
    """

    instr_id: str
    source: str
    instruction: np.ndarray
    obs: np.ndarray
    actions: np.ndarray
    masks: np.ndarray
    distance: np.ndarray
    delta: np.ndarray
    collided: np.ndarray

    def __post_init__(self) -> None:
        t = len(self.actions)
        if t < 1:
            raise InvalidArgumentError(f"demo {self.instr_id} has no actions")
        shapes = {
            "obs": (self.obs.shape[:1], (t,)),
            "masks": (self.masks.shape, (t, N_ACTIONS)),
            "distance": (self.distance.shape, (t,)),
            "delta": (self.delta.shape, (t,)),
            "collided": (self.collided.shape, (t,)),
        }
        for name, (got, want) in shapes.items():
            if tuple(got) != want:
                raise InvalidArgumentError(
                    f"demo {self.instr_id}: {name} has shape {got}, expected {want}"
                )
        if not self.masks[np.arange(t), self.actions].all():
            raise InvalidArgumentError(f"demo {self.instr_id} takes an action its mask forbids")

    def __len__(self) -> int:
        return len(self.actions)

    @property
    def stopped(self) -> bool:
        """Whether the rollout ended with STOP (not at a step cap)."""
        return bool(self.actions[-1] == 0)

    @property
    def success(self) -> bool:
        """Whether it stopped within the success distance of the goal."""
        return self.stopped and bool(self.distance[-1] < SUCCESS_DISTANCE)

    def rewards(self, reward: str | RewardFn = "paper") -> np.ndarray:
        """``(T,)`` float32 reward of each action (a reward of :mod:`havln_mj.tasks.rewards`)."""
        fn = get_reward(reward)
        outcomes = (
            StepOutcome(bool(a == 0), float(d), float(dd), bool(c))
            for a, d, dd, c in zip(
                self.actions, self.distance, self.delta, self.collided, strict=True
            )
        )
        return np.array([step_reward(fn, o) for o in outcomes], np.float32)
