"""Per-step rewards of HA-VLN's decision-transformer data (paper terms and HA3D's strategies).

A reward function sees one :class:`StepOutcome` and returns its terms, by name; the step's
reward is their sum. ``"paper"`` is the HA-VLN paper's definition:

* target: +5 when the agent stops closer than 3 m (geodesic) to the goal, −5 when it stops
  farther; 0 on other actions;
* distance: +1 when an action brings the agent closer to the goal, −0.1 otherwise (turning
  and waiting included); STOP gets none;
* human: −2 when the action collided with a person.

``"strategy_1"`` … ``"strategy_6"`` are the strategies of the HA3D simulator's
``reward.py``: 1 target ±5 only; 2 = 1 plus collision −2; 3 collision −2
only; 4 = 2 plus ±1 for getting closer / farther; 5 = 2 plus −1 for getting farther; 6 = 4 with
a collision −5.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from havln_mj.errors import InvalidArgumentError, did_you_mean

SUCCESS_DISTANCE = 3.0  # metres; success is strictly closer (HA3D: dist < 3.0)


@dataclass(frozen=True)
class StepOutcome:
    """What a reward function may look at after one action.

    Attributes:
        stopped: The action was STOP (the episode ends).
        distance: Geodesic distance from the agent to the goal after the action (metres).
        delta: Change of that distance over the action (negative: closer).
        collided: The action brought the agent within the collision distance of a person.
    """

    stopped: bool
    distance: float
    delta: float
    collided: bool


RewardFn = Callable[[StepOutcome], dict[str, float]]


def _target(o: StepOutcome) -> float:
    if not o.stopped:
        return 0.0
    return 5.0 if o.distance < SUCCESS_DISTANCE else -5.0


def _sign(delta: float, closer: float, farther: float) -> float:
    if delta < 0:
        return closer
    return farther if delta > 0 else 0.0


def paper_reward(o: StepOutcome) -> dict[str, float]:
    """The HA-VLN paper's reward: target ±5, distance +1 / −0.1, human −2."""
    distance = 0.0 if o.stopped else (1.0 if o.delta < 0 else -0.1)
    return {"target": _target(o), "distance": distance, "human": -2.0 if o.collided else 0.0}


def strategy_1(o: StepOutcome) -> dict[str, float]:
    """HA3D strategy 1: +5 / −5 at STOP within / beyond 3 m."""
    return {"target": _target(o), "distance": 0.0, "human": 0.0}


def strategy_2(o: StepOutcome) -> dict[str, float]:
    """HA3D strategy 2: strategy 1 plus −2 per collision."""
    return {"target": _target(o), "distance": 0.0, "human": -2.0 if o.collided else 0.0}


def strategy_3(o: StepOutcome) -> dict[str, float]:
    """HA3D strategy 3: −2 per collision only."""
    return {"target": 0.0, "distance": 0.0, "human": -2.0 if o.collided else 0.0}


def strategy_4(o: StepOutcome) -> dict[str, float]:
    """HA3D strategy 4: strategy 2 plus +1 closer / −1 farther."""
    return strategy_2(o) | {"distance": _sign(o.delta, 1.0, -1.0)}


def strategy_5(o: StepOutcome) -> dict[str, float]:
    """HA3D strategy 5: strategy 2 plus −1 when moving away from the goal."""
    return strategy_2(o) | {"distance": _sign(o.delta, 0.0, -1.0)}


def strategy_6(o: StepOutcome) -> dict[str, float]:
    """HA3D strategy 6: strategy 4 with −5 per collision."""
    return strategy_4(o) | {"human": -5.0 if o.collided else 0.0}


REWARDS: dict[str, RewardFn] = {
    "paper": paper_reward,
    "strategy_1": strategy_1,
    "strategy_2": strategy_2,
    "strategy_3": strategy_3,
    "strategy_4": strategy_4,
    "strategy_5": strategy_5,
    "strategy_6": strategy_6,
}


def step_reward(fn: RewardFn, outcome: StepOutcome) -> float:
    """The step's reward: the sum of ``fn``'s terms for ``outcome``."""
    return float(sum(fn(outcome).values()))


def get_reward(reward: str | RewardFn) -> RewardFn:
    """A reward function by name (see :data:`REWARDS`), or ``reward`` itself if callable.

    Raises:
        InvalidArgumentError: Unknown name.
    """
    if callable(reward):
        return reward
    fn = REWARDS.get(reward)
    if fn is None:
        raise InvalidArgumentError(
            f"unknown reward {reward!r}; valid: {', '.join(REWARDS)}."
            f"{did_you_mean(reward, REWARDS)}"
        )
    return fn
