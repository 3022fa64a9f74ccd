"""HA-VLN episodes as a ``dm_env.Environment``, over the shared gym-free episode core.

Observations, actions, rewards and the task rule are those of
:class:`~havln_mj.tasks.episode_env.EpisodeEnv` (the gymnasium environments use the same
core), turned into ``dm_env`` terms:

* ``reset()`` draws an instruction with the environment's seeded generator and returns a
  ``FIRST`` time step; ``step()`` on a fresh environment or after a ``LAST`` step resets.
* STOP, a fall or diverged physics end the episode with a ``LAST`` step and discount 0; the
  step limit (:data:`MAX_STEPS`, per action set) ends it with discount 1 (truncation).
* The latest step's ``info`` dictionary is :attr:`HAVLNEnvironment.info`.
"""

from __future__ import annotations

from typing import Any

import dm_env
import numpy as np
from dm_env import specs

from havln_mj.errors import InvalidArgumentError
from havln_mj.tasks.episode_env import ACTION_SETS, EpisodeEnv, positive_int
from havln_mj.tasks.observations import Field

MAX_STEPS = {"graph": 40, "ego": 120, "robot": 200}
"""Step limit per action set (the gymnasium ids' ``max_episode_steps``)."""


def field_spec(field: Field) -> specs.Array:
    """The ``dm_env`` spec of an observation field."""
    return specs.BoundedArray(field.shape, field.dtype, field.low, field.high, name=field.name)


class HAVLNEnvironment(dm_env.Environment):
    """One HA-R2R instruction per episode, as a ``dm_env`` environment.

    Args:
        action_set: ``"graph"``, ``"ego"`` or ``"robot"`` (the GO1).
        seed: Seed of the generator that draws instructions.
        max_steps: Step limit (default :data:`MAX_STEPS` of the action set).
        **kwargs: :class:`~havln_mj.tasks.episode_env.EpisodeEnv`'s keyword arguments.

    Raises:
        InvalidArgumentError: A bad value (the message names it and what is valid).
    """

    def __init__(
        self,
        action_set: str = "graph",
        *,
        seed: int | None = None,
        max_steps: int | None = None,
        **kwargs: Any,
    ) -> None:
        if action_set not in ACTION_SETS:
            raise InvalidArgumentError(
                f"action set {action_set!r} unknown; valid: {', '.join(ACTION_SETS)}"
            )
        self.core = EpisodeEnv(action_set, **kwargs)
        cap = MAX_STEPS[action_set] if max_steps is None else max_steps
        self.max_steps = positive_int("max_steps", cap)
        self._rng = np.random.default_rng(seed)
        self._steps = 0
        self._needs_reset = True
        self.info: dict[str, Any] = {}
        self._obs_spec = {f.name: field_spec(f) for f in self.core.observations.fields}

    def reset(self) -> dm_env.TimeStep:
        """Starts a new episode with a random instruction."""
        obs, self.info = self.core.reset(self.core.choose({}, self._rng))
        self._steps = 0
        self._needs_reset = False
        return dm_env.restart(obs)

    def step(self, action: int | np.integer | np.ndarray) -> dm_env.TimeStep:
        """Takes one action (a new episode starts after a ``LAST`` step)."""
        if self._needs_reset:
            return self.reset()
        obs, reward, terminated, self.info = self.core.step(action)
        self._steps += 1
        if terminated:
            self._needs_reset = True
            return dm_env.termination(reward, obs)
        if self._steps >= self.max_steps:
            self._needs_reset = True
            return dm_env.truncation(reward, obs)
        return dm_env.transition(reward, obs)

    def observation_spec(self) -> dict[str, specs.Array]:
        """The observation fields' specs."""
        return self._obs_spec

    def action_spec(self) -> specs.DiscreteArray:
        """A discrete action of the action set."""
        return specs.DiscreteArray(self.core.n_actions, dtype=np.int64, name="action")

    def close(self) -> None:
        """Releases the simulator (and its GL context)."""
        self.core.close()


def load(action_set: str = "graph", **kwargs: Any) -> HAVLNEnvironment:
    """An HA-VLN ``dm_env`` environment (see :class:`HAVLNEnvironment`)."""
    return HAVLNEnvironment(action_set, **kwargs)
