"""Gymnasium environments over the gym-free :class:`~havln_mj.tasks.episode_env.EpisodeEnv`.

Every environment runs one HA-R2R instruction per episode: ``reset`` draws an instruction
uniformly over the episodes' instructions with the environment's generator (so
``reset(seed=s)`` always starts the same episode) and places the agent at the path's start,
heading, elevation 0. The people are the simulator's for ``episode_seed``, the seed the
procedural episodes were generated with, so the dataset's human annotations hold.
Observations, actions, rewards and ``info`` are described in
:mod:`havln_mj.tasks.observations` and :mod:`havln_mj.tasks.episode_env`; the weighted
reward terms are ``info["reward_terms"]`` and sum to the reward. ``terminated`` is True on
STOP and when the GO1 falls; truncation is the registered ``TimeLimit``'s.

Pickling keeps the configuration, episodes, vocabulary and generator but not the simulator
nor the running episode: an unpickled environment builds its own simulator (and GL context)
at its first ``reset``, which is what lets every ``AsyncVectorEnv`` worker own one. A process
that has rendered already must start its workers with ``context="spawn"``: a forked child
inherits the parent's EGL state and hangs.
"""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from havln_mj.errors import InvalidArgumentError
from havln_mj.tasks.episode_env import EpisodeEnv
from havln_mj.tasks.observations import Field


def field_space(field: Field) -> spaces.Space:
    """The gymnasium space of an observation field."""
    if field.kind == "discrete":
        return spaces.Discrete(int(field.high) - int(field.low) + 1, start=int(field.low))
    if field.kind == "binary":
        return spaces.MultiBinary(field.shape[0] if len(field.shape) == 1 else field.shape)
    return spaces.Box(field.low, field.high, field.shape, field.dtype)


class HAVLNEnv(gym.Env[dict[str, Any], np.int64]):
    """An HA-VLN environment; the subclasses fix the action set and the body.

    Keyword arguments are :class:`~havln_mj.tasks.episode_env.EpisodeEnv`'s, plus
    ``render_mode`` (None or ``"rgb_array"``: ``render`` returns the camera image).

    Attributes:
        vocab: The instruction vocabulary (``instruction`` ids index ``vocab.tokens``).
        episodes: The episodes drawn from.
        instructions: Every instruction of ``episodes``; ``reset`` draws one of them.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"], "render_fps": 4}
    action_set: ClassVar[str] = "graph"

    def __init__(self, *, render_mode: str | None = None, **kwargs: Any) -> None:
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise InvalidArgumentError(
                f"render_mode {render_mode!r} unknown; valid: None, "
                f"{', '.join(map(repr, self.metadata['render_modes']))}"
            )
        self.render_mode = render_mode
        self.core = EpisodeEnv(self.action_set, render=render_mode == "rgb_array", **kwargs)
        self.vocab = self.core.vocab
        self.episodes = self.core.episodes
        self.instructions = self.core.instructions
        self.observation_space = spaces.Dict(
            {f.name: field_space(f) for f in self.core.observations.fields}
        )
        self.action_space = spaces.Discrete(self.core.n_actions)

    @property
    def _sim(self):
        """The simulator (None until the first ``reset``)."""
        return self.core.sim

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, Any], dict[str, Any]]:
        """Starts an episode: a random instruction, or the one ``options`` names.

        Args:
            seed: Seeds the environment's generator (the instruction drawn).
            options: ``{"instr_id": "<path_id>_<k>"}`` or ``{"index": i}`` (into
                :attr:`instructions`) to choose the instruction.

        Raises:
            InvalidArgumentError: An unknown option or instruction.
        """
        super().reset(seed=seed)
        return self.core.reset(self.core.choose(options or {}, self.np_random))

    def step(
        self, action: int | np.integer
    ) -> tuple[dict[str, Any], float, bool, bool, dict[str, Any]]:
        """Takes one action (see the subclass for what the actions are).

        Raises:
            NotInitializedError: No episode is running (call ``reset``).
            InvalidActionError: ``action`` is not in the action space.
        """
        obs, reward, terminated, info = self.core.step(action)
        return obs, float(reward), terminated, False, info

    def render(self) -> np.ndarray | None:
        """The current RGB camera image (``rgb_array`` mode), else None."""
        if self.render_mode != "rgb_array":
            return None
        return self.core.frame()

    def close(self) -> None:
        """Releases the simulator (and its GL context); ``reset`` builds a new one."""
        self.core.close()


class GraphEnv(HAVLNEnv):
    """``HAVLN-Graph-v0``: the point body moving along the navigation graph.

    Actions are ``Discrete(max_candidates + 1)``: 0 is STOP (ends the episode), ``k ≥ 1``
    moves to navigable candidate ``k`` (row ``k`` of ``candidates``) and turns to face the
    direction moved. A ``k`` whose row is empty (``candidate_mask[k] == 0``) is a wait in
    place (one second passes) and sets ``info["invalid_action"]``.
    """

    action_set: ClassVar[str] = "graph"


class EgoEnv(HAVLNEnv):
    """``HAVLN-Ego-v0``: HA-VLN's six egocentric actions with the point body.

    Actions are ``Discrete(6)``, numbered as :class:`havln_mj.sim.egocentric.EgoAction`:
    0 STOP (ends the episode), 1 FORWARD, 2 TURN_LEFT, 3 TURN_RIGHT, 4 LOOK_UP, 5 LOOK_DOWN.
    """

    action_set: ClassVar[str] = "ego"


class Go1Env(HAVLNEnv):
    """``HAVLN-Go1-v0``: the simulated GO1 quadruped with the real robot's primitives.

    Actions are ``Discrete(4)``: 0 stop (ends the episode), 1 forward (0.5 m), 2 turn_left,
    3 turn_right (45°) (:data:`havln_mj.sim.body.ROBOT_ACTIONS`). A fall or diverged physics
    ends the episode too. Distances to the goal are walking distances from the robot's true
    position.
    """

    action_set: ClassVar[str] = "robot"
