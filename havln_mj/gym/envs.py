"""Gymnasium environments over :class:`havln_mj.sim.simulator.Simulator`.

Every environment runs one HA-R2R instruction per episode: ``reset`` draws an instruction
uniformly over the episodes' instructions with the environment's generator (so
``reset(seed=s)`` always starts the same episode) and places the agent at the path's start,
heading, elevation 0. The people are the simulator's for ``episode_seed``, the seed the
procedural episodes were generated with, so the dataset's human annotations hold.

Observations (a ``Dict``; ``H×W`` is ``height×width``):

=================  ==========================================================================
``rgb``            ``H×W×3 uint8`` RGB camera image (unless ``rgb=False``)
``depth``          ``H×W×1 float32`` planar depth in metres, 0 = no reading, clipped to
                   ``max_depth`` (only with ``depth=True``)
``human_mask``     ``H×W uint8``, 1 where a person is seen (only with ``human_mask=True``)
``instruction``    ``L int64`` token ids of :attr:`HAVLNEnv.vocab`, 0-padded (``L`` =
                   ``instruction_length``)
``heading``        ``(1,) float32`` radians in [0, 2π), 0 facing +y, right positive
``elevation``      ``(1,) float32`` radians, up positive
``candidates``     ``(K+1)×4 float32``: row 0 is the agent's own location (zeros), row k ≥ 1
                   the k-th navigable viewpoint (nearest the view centre first):
                   ``sin rel_heading, cos rel_heading, rel_elevation, rel_distance`` (metres,
                   clipped to 50); zeros where there is none (``K`` = ``max_candidates``)
``candidate_mask`` ``MultiBinary(K+1)``: 1 for row 0 and for every row holding a viewpoint
``collision``      ``Discrete(2)``: 1 when the last action came within the collision distance
                   of a person
=================  ==========================================================================

Rewards are the paper's terms (:mod:`havln_mj.tasks.rewards`) times ``reward_weights``; the
weighted terms are ``info["reward_terms"]`` and sum to the reward. ``terminated`` is True on
STOP and when the GO1 falls; truncation is the registered ``TimeLimit``'s. ``info`` always has
``scan``, ``path_id``, ``instr_id``, ``instruction``, ``goal``, ``viewpoint``, ``distance``
(geodesic to the goal, metres), ``time``, ``reward_terms``, ``collision``, ``fell``,
``stopped``, ``success`` (stopped within 3 m) and ``invalid_action`` (zeros and False at reset).

Pickling keeps the configuration, episodes, vocabulary and generator but not the simulator
nor the running episode: an unpickled environment builds its own simulator (and GL context)
at its first ``reset``, which is what lets every ``AsyncVectorEnv`` worker own one. A process
that has rendered already must start its workers with ``context="spawn"``: a forked child
inherits the parent's EGL state and hangs.
"""

from __future__ import annotations

import abc
import functools
import math
import numbers
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from havln_mj.errors import InvalidActionError, InvalidArgumentError, NotInitializedError
from havln_mj.sim.egocentric import EgoAction
from havln_mj.sim.simulator import ROBOT_ACTIONS, Simulator
from havln_mj.sim.state import SimState
from havln_mj.tasks.datasets import load_dataset
from havln_mj.tasks.episodes import Episode, Instruction
from havln_mj.tasks.rewards import SUCCESS_DISTANCE, RewardFn, StepOutcome, get_reward
from havln_mj.tasks.vocab import Vocabulary

DEFAULT_SCENES = ("proc-0",)
MAX_CANDIDATE_DISTANCE = 50.0  # metres; candidate distances are clipped so the Box is bounded
CANDIDATE_FEATURES = 4
_OPTIONS = ("instr_id", "index")


@functools.lru_cache(maxsize=8)
def procedural_episodes(scenes: tuple[str, ...], per_scene: int, seed: int) -> tuple[Episode, ...]:
    """HA-R2R episodes of procedural scenes (cached: every env of a process shares them).

    Scene ``i`` gets path ids from ``i * 10_000``, as :func:`build_split` numbers a split.
    """
    from havln_mj.tasks.procedural import procedural_episodes as generate

    return tuple(generate(scenes, per_scene, seed, first_id=0))


def _positive_int(name: str, value: object) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
        raise InvalidArgumentError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def _positive_float(name: str, value: object) -> float:
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool)
    if not (ok and math.isfinite(value) and value > 0):
        raise InvalidArgumentError(f"{name} must be a positive number, got {value!r}")
    return float(value)


class HAVLNEnv(gym.Env[dict[str, Any], np.int64], abc.ABC):
    """The shared machinery of the HA-VLN environments (use a subclass).

    Attributes:
        vocab: The instruction vocabulary (``instruction`` ids index ``vocab.tokens``).
        episodes: The episodes drawn from.
        instructions: Every instruction of ``episodes``; ``reset`` draws one of them.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"], "render_fps": 4}
    body: ClassVar[str] = "point"

    def __init__(
        self,
        *,
        render_mode: str | None = None,
        scenes: Sequence[str] | None = None,
        episodes_per_scene: int = 20,
        episode_seed: int = 0,
        dataset: str | Path | None = None,
        connectivity_dir: str | Path | None = None,
        data_dir: str | Path | None = None,
        scan_dir: str | Path | None = None,
        humans: bool = True,
        width: int = 128,
        height: int = 128,
        vfov: float | None = None,
        rgb: bool = True,
        depth: bool = False,
        human_mask: bool = False,
        max_depth: float = 20.0,
        instruction_length: int = 80,
        vocab: Vocabulary | Sequence[str] | str | Path | None = None,
        max_candidates: int = 16,
        restricted_navigation: bool = False,
        reward: str | RewardFn = "paper",
        reward_weights: Mapping[str, float] | None = None,
    ) -> None:
        """Creates the environment; the simulator is built at the first ``reset``.

        Args:
            render_mode: None or ``"rgb_array"`` (``render`` returns the camera image).
            scenes: Procedural scene ids to generate episodes in (default ``("proc-0",)``);
                with ``dataset``, only the dataset's episodes in these scans are kept.
            episodes_per_scene: Paths generated per procedural scene.
            episode_seed: Seed of the generated episodes and of the simulator's people.
            dataset: An HA-R2R/R2R file or split name (:func:`load_dataset`) instead of
                procedural episodes.
            connectivity_dir: Folder of ``<scan>_connectivity.json`` for the dataset's scans.
            data_dir: Where split names are looked up (default ``$HAVLN_VLN_DATA``).
            scan_dir: The scans' mesh folder (the simulator's ``setDatasetPath``).
            humans: Whether scans have people.
            width: Image width (pixels).
            height: Image height (pixels).
            vfov: Vertical field of view (radians; default MatterSim's).
            rgb: Whether observations hold the RGB image. With ``rgb``, ``depth`` and
                ``human_mask`` all off and no render mode, nothing is rendered (fastest).
            depth: Whether observations hold depth.
            human_mask: Whether observations hold the human mask.
            max_depth: Depth is clipped to this (metres).
            instruction_length: Token ids per instruction (longer ones are cut).
            vocab: The vocabulary: a :class:`Vocabulary`, a token list, a ``vocab_<split>.txt``
                file, or None to build it from the episodes' instructions.
            max_candidates: Navigable viewpoints described (and, in the graph env, actions);
                farther from the view centre ones beyond it are left out.
            restricted_navigation: MatterSim's rule that only viewpoints in the field of view
                are navigable; off by default so every neighbour is a candidate.
            reward: A reward name of :data:`havln_mj.tasks.rewards.REWARDS` or a function.
            reward_weights: Weight per reward term (default 1 for each).

        Raises:
            InvalidArgumentError: A bad value (the message names it and what is valid).
            MissingDataError: The dataset or vocabulary file does not exist.
        """
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise InvalidArgumentError(
                f"render_mode {render_mode!r} unknown; valid: None, "
                f"{', '.join(map(repr, self.metadata['render_modes']))}"
            )
        self.render_mode = render_mode
        self._width = _positive_int("width", width)
        self._height = _positive_int("height", height)
        self._vfov = None if vfov is None else _positive_float("vfov", vfov)
        self._max_depth = _positive_float("max_depth", max_depth)
        self._length = _positive_int("instruction_length", instruction_length)
        self._k = _positive_int("max_candidates", max_candidates)
        self._rgb, self._depth, self._mask = bool(rgb), bool(depth), bool(human_mask)
        self._rendering = self._rgb or self._depth or self._mask or render_mode == "rgb_array"
        self._humans = bool(humans)
        self._restricted = bool(restricted_navigation)
        self._paths = (connectivity_dir, scan_dir)
        self._episode_seed = int(episode_seed)
        self.episodes = self._load_episodes(
            scenes, episodes_per_scene, dataset, connectivity_dir, data_dir
        )
        self.instructions: tuple[Instruction, ...] = tuple(
            item for e in self.episodes for item in e.instruction_items()
        )
        self.vocab = self._load_vocab(vocab)
        self._reward_fn = get_reward(reward)
        self._weights = self._check_weights(reward_weights)
        self.observation_space = self._observation_space()
        self.action_space = self._action_space()
        self._sim: Simulator | None = None
        self._current: Instruction | None = None
        self._tokens = np.zeros(self._length, np.int64)
        self._distance = 0.0
        self._done = True

    # ------------------------------------------------------------------ setup

    def _load_episodes(
        self,
        scenes: Sequence[str] | None,
        per_scene: int,
        dataset: str | Path | None,
        connectivity_dir: str | Path | None,
        data_dir: str | Path | None,
    ) -> tuple[Episode, ...]:
        if isinstance(scenes, str):
            raise InvalidArgumentError(f"scenes takes a list of scene ids, got {scenes!r}")
        if dataset is None:
            scenes = tuple(scenes or DEFAULT_SCENES)
            per_scene = _positive_int("episodes_per_scene", per_scene)
            return procedural_episodes(scenes, per_scene, self._episode_seed)
        data = load_dataset(dataset, connectivity_dir=connectivity_dir, data_dir=data_dir)
        episodes = tuple(e for e in data if scenes is None or e.scan in scenes)
        if not episodes:
            raise InvalidArgumentError(
                f"dataset {data.source} has no episodes in scans {list(scenes or [])!r}"
            )
        return episodes

    def _load_vocab(self, vocab: Vocabulary | Sequence[str] | str | Path | None) -> Vocabulary:
        if vocab is None:
            return Vocabulary.from_texts(i.text for i in self.instructions)
        if isinstance(vocab, Vocabulary):
            return vocab
        if isinstance(vocab, str | Path):
            return Vocabulary.from_file(vocab)
        return Vocabulary(vocab)

    def _check_weights(self, weights: Mapping[str, float] | None) -> dict[str, float]:
        terms = self._reward_fn(StepOutcome(False, 0.0, 0.0, False))
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

    def _observation_space(self) -> spaces.Dict:
        h, w, k = self._height, self._width, self._k
        d: dict[str, spaces.Space] = {}
        if self._rgb:
            d["rgb"] = spaces.Box(0, 255, (h, w, 3), np.uint8)
        if self._depth:
            d["depth"] = spaces.Box(0.0, self._max_depth, (h, w, 1), np.float32)
        if self._mask:
            d["human_mask"] = spaces.Box(0, 1, (h, w), np.uint8)
        d["instruction"] = spaces.Box(0, len(self.vocab) - 1, (self._length,), np.int64)
        d["heading"] = spaces.Box(0.0, 2 * math.pi, (1,), np.float32)
        d["elevation"] = spaces.Box(-math.pi / 2, math.pi / 2, (1,), np.float32)
        low = np.tile(np.array([-1.0, -1.0, -math.pi, 0.0], np.float32), (k + 1, 1))
        high = np.tile(
            np.array([1.0, 1.0, math.pi, MAX_CANDIDATE_DISTANCE], np.float32), (k + 1, 1)
        )
        d["candidates"] = spaces.Box(low, high, dtype=np.float32)
        d["candidate_mask"] = spaces.MultiBinary(k + 1)
        d["collision"] = spaces.Discrete(2)
        return spaces.Dict(d)

    @abc.abstractmethod
    def _action_space(self) -> spaces.Discrete:
        """The env's discrete action space."""

    def _make_sim(self) -> Simulator:
        sim = Simulator(humans=self._humans, body=self.body)
        connectivity_dir, scan_dir = self._paths
        if connectivity_dir is not None:
            sim.setNavGraphPath(connectivity_dir)
        if scan_dir is not None:
            sim.setDatasetPath(scan_dir)
        sim.setRenderingEnabled(self._rendering)
        sim.setCameraResolution(self._width, self._height)
        if self._vfov is not None:
            sim.setCameraVFOV(self._vfov)
        sim.setDepthEnabled(self._depth)
        sim.set_human_mask_enabled(self._mask)
        sim.set_color_order("RGB")
        sim.set_depth_units("metres")
        sim.setRestrictedNavigation(self._restricted)
        sim.setSeed(self._episode_seed)  # the people the episodes were annotated with
        sim.initialize()
        return sim

    # ------------------------------------------------------------------ pickling

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state.update(_sim=None, _current=None, _done=True)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)

    # ------------------------------------------------------------------ gym API

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
        item = self._choose(options or {})
        if self._sim is None:
            self._sim = self._make_sim()
        e = item.episode
        self._sim.newEpisode([e.scan], [e.start], [e.heading], [0.0])
        self._current = item
        self._tokens = self.vocab.encode(item.text, self._length)
        self._distance = self._goal_distance()
        self._done = False
        state = self._sim.getState()[0]
        info = self._info(state)
        # The step keys too, so every info of an episode (and a vector env's) has the same keys.
        info.update(
            reward_terms=dict.fromkeys(self._weights, 0.0),
            collision=False,
            fell=bool(state.fell),
            stopped=False,
            success=False,
            invalid_action=False,
        )
        return self._obs(state, False), info

    def _choose(self, options: Mapping[str, Any]) -> Instruction:
        unknown = sorted(set(options) - set(_OPTIONS))
        if unknown or len(options) > 1:
            raise InvalidArgumentError(
                f"reset options {sorted(options)!r} invalid; give at most one of: "
                f"{', '.join(_OPTIONS)}"
            )
        if "instr_id" in options:
            for item in self.instructions:
                if item.instr_id == options["instr_id"]:
                    return item
            raise InvalidArgumentError(
                f"no instruction {options['instr_id']!r} in this environment's episodes "
                f"(ids look like {self.instructions[0].instr_id!r})"
            )
        if "index" in options:
            i = options["index"]
            n = len(self.instructions)
            if isinstance(i, bool) or not isinstance(i, numbers.Integral) or not 0 <= i < n:
                raise InvalidArgumentError(f"instruction index {i!r} out of range 0–{n - 1}")
            return self.instructions[int(i)]
        return self.instructions[int(self.np_random.integers(len(self.instructions)))]

    def step(
        self, action: int | np.integer
    ) -> tuple[dict[str, Any], float, bool, bool, dict[str, Any]]:
        """Takes one action; see the subclass for what the actions are.

        Raises:
            NotInitializedError: No episode is running (call ``reset``).
            InvalidActionError: ``action`` is not in the action space.
        """
        if self._done or self._sim is None:
            raise NotInitializedError("step() needs a running episode: call reset() first")
        a = self._check_action(action)
        stopped, invalid = self._act(a)
        state = self._sim.getState()[0]
        previous = self._distance
        if not stopped:
            self._distance = self._goal_distance()
        collided = bool(state.isCrushed) and not stopped  # STOP does not act
        raw = self._reward_fn(
            StepOutcome(stopped, self._distance, self._distance - previous, collided)
        )
        terms = {name: self._weights.get(name, 1.0) * float(v) for name, v in raw.items()}
        fell = bool(state.fell)
        self._done = stopped or fell
        info = self._info(state)
        info.update(
            reward_terms=terms,
            collision=collided,
            fell=fell,
            stopped=stopped,
            success=stopped and self._distance < SUCCESS_DISTANCE,
            invalid_action=invalid,
        )
        return self._obs(state, collided), float(sum(terms.values())), self._done, False, info

    def _check_action(self, action: object) -> int:
        if isinstance(action, np.ndarray) and action.shape == ():
            action = action.item()
        n = int(self.action_space.n)
        if isinstance(action, bool) or not isinstance(action, numbers.Integral):
            raise InvalidActionError(f"action must be an integer in 0–{n - 1}, got {action!r}")
        if not 0 <= action < n:
            raise InvalidActionError(f"action {action} out of range; valid 0–{n - 1}")
        return int(action)

    @abc.abstractmethod
    def _act(self, action: int) -> tuple[bool, bool]:
        """Performs ``action``; returns (it was STOP, it was invalid and became a wait)."""

    def _goal_distance(self) -> float:
        return float(self._sim.getGeodesicDistance([self._current.episode.goal])[0])

    def render(self) -> np.ndarray | None:
        """The current RGB camera image (``rgb_array`` mode), else None."""
        if self.render_mode != "rgb_array" or self._sim is None or self._current is None:
            return None
        return np.array(self._sim.getState()[0].rgb, copy=True)

    def close(self) -> None:
        """Releases the simulator (and its GL context); ``reset`` builds a new one."""
        if self._sim is not None:
            self._sim.close()
        self._sim = None
        self._current = None
        self._done = True

    # ------------------------------------------------------------------ observations

    def _obs(self, state: SimState, collided: bool) -> dict[str, Any]:
        obs: dict[str, Any] = {}
        if self._rgb:
            obs["rgb"] = np.array(state.rgb, np.uint8, copy=True)
        if self._depth:
            obs["depth"] = np.clip(state.depth, 0.0, self._max_depth).astype(np.float32)
        if self._mask:
            mask = state.humanMask
            shape = (self._height, self._width)
            obs["human_mask"] = np.zeros(shape, np.uint8) if mask is None else mask.astype(np.uint8)
        obs["instruction"] = self._tokens.copy()
        obs["heading"] = np.array([state.heading], np.float32)
        obs["elevation"] = np.array([state.elevation], np.float32)
        cands = np.zeros((self._k + 1, CANDIDATE_FEATURES), np.float32)
        mask = np.zeros(self._k + 1, np.int8)
        mask[0] = 1
        for k, vp in enumerate(state.navigableLocations[1 : self._k + 1], start=1):
            cands[k] = (
                math.sin(vp.rel_heading),
                math.cos(vp.rel_heading),
                min(max(vp.rel_elevation, -math.pi), math.pi),
                min(vp.rel_distance, MAX_CANDIDATE_DISTANCE),
            )
            mask[k] = 1
        obs["candidates"] = cands
        obs["candidate_mask"] = mask
        obs["collision"] = int(collided)
        return obs

    def _info(self, state: SimState) -> dict[str, Any]:
        item = self._current
        return {
            "scan": item.episode.scan,
            "path_id": item.episode.path_id,
            "instr_id": item.instr_id,
            "instruction": item.text,
            "goal": item.episode.goal,
            "viewpoint": state.location.viewpointId,
            "distance": self._distance,
            "time": float(state.time),
        }


class GraphEnv(HAVLNEnv):
    """``HAVLN-Graph-v0``: the point body moving along the navigation graph.

    Actions are ``Discrete(max_candidates + 1)``: 0 is STOP (ends the episode), ``k ≥ 1``
    moves to navigable candidate ``k`` (row ``k`` of ``candidates``) and turns to face the
    direction moved. A ``k`` whose row is empty (``candidate_mask[k] == 0``) is a wait in
    place (one second passes) and sets ``info["invalid_action"]``.
    """

    def _action_space(self) -> spaces.Discrete:
        return spaces.Discrete(self._k + 1)

    def _act(self, action: int) -> tuple[bool, bool]:
        if action == 0:
            return True, False
        navigable = self._sim.getState()[0].navigableLocations
        if action >= len(navigable):
            self._sim.makeAction([0], [0.0], [0.0])
            return False, True
        self._sim.makeAction([action], [navigable[action].rel_heading], [0.0])
        return False, False


class EgoEnv(HAVLNEnv):
    """``HAVLN-Ego-v0``: HA-VLN's six egocentric actions with the point body.

    Actions are ``Discrete(6)``, numbered as :class:`havln_mj.sim.egocentric.EgoAction`:
    0 STOP (ends the episode), 1 FORWARD, 2 TURN_LEFT, 3 TURN_RIGHT, 4 LOOK_UP, 5 LOOK_DOWN.
    """

    def _action_space(self) -> spaces.Discrete:
        return spaces.Discrete(len(EgoAction))

    def _act(self, action: int) -> tuple[bool, bool]:
        if action == EgoAction.STOP:
            return True, False
        self._sim.makeEgoAction([EgoAction(action)])
        return False, False


class Go1Env(HAVLNEnv):
    """``HAVLN-Go1-v0``: the simulated GO1 quadruped with the real robot's primitives.

    Actions are ``Discrete(4)``: 0 stop (ends the episode), 1 forward (0.5 m), 2 turn_left,
    3 turn_right (45°) (:data:`havln_mj.sim.simulator.ROBOT_ACTIONS`). A fall ends the
    episode too. Distances to the goal are walking distances from the robot's true position.
    """

    body: ClassVar[str] = "go1"

    def _action_space(self) -> spaces.Discrete:
        return spaces.Discrete(len(ROBOT_ACTIONS))

    def _act(self, action: int) -> tuple[bool, bool]:
        if ROBOT_ACTIONS[action] == "stop":
            return True, False
        self._sim.makeRobotAction([ROBOT_ACTIONS[action]])
        return False, False
