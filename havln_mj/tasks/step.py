"""The task step: one rule for starts, collisions, rewards, success and goal distance.

Every caller that runs episodes — the experts (:func:`havln_mj.tasks.experts.run_expert`),
the agents' batched rollouts, the gymnasium environments and the ``dm_env`` adapter — steps
a :class:`TaskStep`, so one rule holds everywhere:

* **Actions**, per batch element: a graph action ``(index, dHeading, dElevation)``, an
  :class:`~havln_mj.sim.egocentric.EgoAction`, a robot action name of
  :data:`~havln_mj.sim.body.ROBOT_ACTIONS`, or None to leave the element alone (an episode
  that has ended while others run). ``EgoAction.STOP`` and ``"stop"`` are STOP: the episode
  ends and the simulator is not called (no step, no time, no collision).
* **Collision**: the start state counts (an agent placed within the collision distance of a
  person has collided), then every action's ``isCrushed`` (the simulator's signal along the
  whole action); STOP never collides.
* **Goal distance**: :meth:`Simulator.getGeodesicDistance` — from where the body truly is (the
  GO1's true pose on its level's navigability grid), the same for every caller.
* **Reward**: the terms of :mod:`havln_mj.tasks.rewards` times their weights.
* **Success**: STOP strictly closer than :data:`SUCCESS_DISTANCE` to the goal.
* **End**: STOP, a fall or diverged physics (terminated), or the step cap (truncated).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Union

from havln_mj.errors import InvalidArgumentError, NotInitializedError
from havln_mj.sim.egocentric import EgoAction
from havln_mj.sim.state import SimState
from havln_mj.tasks.episodes import Episode
from havln_mj.tasks.rewards import SUCCESS_DISTANCE, RewardFn, StepOutcome, get_reward

GraphAction = tuple[int, float, float]
Action = Union[EgoAction, GraphAction, str]  # noqa: UP007 - a runtime alias
STOP = EgoAction.STOP

__all__ = ["STOP", "SUCCESS_DISTANCE", "Action", "GraphAction", "StepResult", "TaskStep"]


@dataclass(frozen=True)
class StepResult:
    """One element's start or step.

    Attributes:
        state: The simulator's state afterwards (unchanged by STOP).
        action: The action (None at the start).
        distance: Walking distance from the body to the goal (metres).
        delta: Change of ``distance`` over the action (0 at the start).
        collided: Whether this start or action collided with a person (the task's rule).
        crushed_by: Indices of the people collided with.
        reward_terms: Weighted reward terms by name (zeros at the start).
        reward: Their sum.
        stopped: The action was STOP.
        success: Stopped strictly closer than the success distance to the goal.
        fell: The body has fallen (or its physics diverged).
        terminated: The episode ended (STOP, a fall, diverged physics).
        truncated: The episode hit the step cap.
        step: Actions taken in the episode so far.
    """

    state: SimState
    action: Action | None
    distance: float
    delta: float
    collided: bool
    crushed_by: tuple[int, ...]
    reward_terms: Mapping[str, float] = field(default_factory=dict)
    reward: float = 0.0
    stopped: bool = False
    success: bool = False
    fell: bool = False
    terminated: bool = False
    truncated: bool = False
    step: int = 0

    @property
    def done(self) -> bool:
        """The episode is over (terminated or truncated)."""
        return self.terminated or self.truncated


def is_stop(action: object) -> bool:
    """Whether ``action`` is STOP in any action space."""
    return action is STOP or (isinstance(action, str) and action == "stop")


class TaskStep:
    """Runs the simulator's batch as HA-VLN episodes.

    Args:
        sim: An initialised (or initialisable) :class:`~havln_mj.sim.simulator.Simulator`;
            its batch size is the number of episodes run together.
        reward: A reward name of :data:`havln_mj.tasks.rewards.REWARDS` or a function.
        reward_weights: Weight per reward term (default 1 each).
        success_distance: Success when stopping strictly closer than this (metres).
        max_steps: Step cap per episode (None: no cap).

    Raises:
        InvalidArgumentError: An unknown reward or term, or a bad number.
    """

    def __init__(
        self,
        sim: object,
        *,
        reward: str | RewardFn = "paper",
        reward_weights: Mapping[str, float] | None = None,
        success_distance: float = SUCCESS_DISTANCE,
        max_steps: int | None = None,
    ) -> None:
        self.sim = sim
        self.reward_fn = get_reward(reward)
        self.weights = self._check_weights(reward_weights)
        ok = isinstance(success_distance, numbers.Real) and math.isfinite(success_distance)
        if not ok or success_distance <= 0:
            raise InvalidArgumentError(
                f"success_distance must be a positive number of metres, got {success_distance!r}"
            )
        self.success_distance = float(success_distance)
        bad_cap = isinstance(max_steps, bool) or not isinstance(max_steps, numbers.Integral)
        if max_steps is not None and (bad_cap or max_steps < 1):
            raise InvalidArgumentError(f"max_steps must be an integer ≥ 1, got {max_steps!r}")
        self.max_steps = max_steps
        self.episodes: list[Episode] = []
        self._last: list[StepResult] = []

    def _check_weights(self, weights: Mapping[str, float] | None) -> dict[str, float]:
        terms = self.reward_fn(StepOutcome(False, 0.0, 0.0, False))
        out = dict.fromkeys(terms, 1.0)
        for name, w in (weights or {}).items():
            if name not in out:
                raise InvalidArgumentError(
                    f"reward_weights names unknown term {name!r}; valid: {', '.join(out)}"
                )
            if not (isinstance(w, numbers.Real) and math.isfinite(w)):
                raise InvalidArgumentError(f"reward weight of {name!r} must be finite, got {w!r}")
            out[name] = float(w)
        return out

    @property
    def results(self) -> list[StepResult]:
        """Each element's latest result."""
        return self._last

    def start(self, episodes: Sequence[Episode]) -> list[StepResult]:
        """Starts one episode per batch element at its start, heading, elevation 0."""
        sim = self.sim
        sim.newEpisode(
            [e.scan for e in episodes],
            [e.start for e in episodes],
            [e.heading for e in episodes],
            [0.0] * len(episodes),
        )
        self.episodes = list(episodes)
        states = sim.getState()
        goals = sim.getGeodesicDistance([e.goal for e in episodes])
        self._last = [
            StepResult(
                s,
                None,
                float(d),
                0.0,
                bool(s.isCrushed),
                tuple(s.crushedBy),
                dict.fromkeys(self.weights, 0.0),
                fell=s.fell or s.diverged,
                terminated=s.fell or s.diverged,
            )
            for s, d in zip(states, goals, strict=True)
        ]
        return self._last

    def step(self, actions: Sequence[Action | None]) -> list[StepResult]:
        """Takes one action per element (None: leave it alone) and scores it.

        Raises:
            NotInitializedError: No episode was started.
            InvalidActionError: An action the simulator rejects.
        """
        if not self._last:
            raise NotInitializedError("TaskStep.step() before start()")
        acting = [
            None if a is None or is_stop(a) or self._last[i].done else a
            for i, a in enumerate(actions)
        ]
        if any(a is not None for a in acting):
            self.sim.step(acting)
        states = self.sim.getState()
        goals = [e.goal for e in self.episodes]
        moved = [i for i, a in enumerate(acting) if a is not None]
        distances = dict(zip(moved, self._distances(moved, goals), strict=True))
        out = []
        for i, (action, state) in enumerate(zip(actions, states, strict=True)):
            last = self._last[i]
            if action is None or last.done:
                out.append(last)
                continue
            out.append(self._score(last, action, state, distances.get(i, last.distance)))
        self._last = out
        return out

    def _distances(self, which: list[int], goals: list[str]) -> list[float]:
        if not which:
            return []
        all_d = self.sim.getGeodesicDistance(goals)
        return [float(all_d[i]) for i in which]

    def _score(
        self, last: StepResult, action: Action, state: SimState, distance: float
    ) -> StepResult:
        stopped = is_stop(action)
        collided = bool(state.isCrushed) and not stopped
        raw = self.reward_fn(StepOutcome(stopped, distance, distance - last.distance, collided))
        terms = {name: self.weights.get(name, 1.0) * float(v) for name, v in raw.items()}
        fell = bool(state.fell or state.diverged)
        step = last.step + 1
        return StepResult(
            state,
            action,
            distance,
            distance - last.distance,
            collided,
            tuple(state.crushedBy) if collided else (),
            terms,
            float(sum(terms.values())),
            stopped,
            stopped and distance < self.success_distance,
            fell,
            stopped or fell,
            self.max_steps is not None and step >= self.max_steps and not (stopped or fell),
            step,
        )
