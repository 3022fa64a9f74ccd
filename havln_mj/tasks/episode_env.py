"""One HA-R2R instruction per episode, behind any environment API (gym-free).

:class:`EpisodeEnv` is what the gymnasium environments (:mod:`havln_mj.gym`) and the
``dm_env`` adapter (:mod:`havln_mj.dmenv`) share: the configuration and its checks, the
episodes (procedural, or a dataset file or split), the vocabulary, the simulator, the
observations (:mod:`havln_mj.tasks.observations`), the action sets and the task step
(:mod:`havln_mj.tasks.step`). The adapters only translate to their API.

Action sets, each a range of integers:

* ``"graph"`` (point body): ``Discrete(max_candidates + 1)``; 0 is STOP, ``k ≥ 1`` moves to
  navigable candidate ``k`` (row ``k`` of ``candidates``) and turns to face the direction
  moved. A ``k`` whose row is empty is a wait in place (one second) and sets
  ``info["invalid_action"]``.
* ``"ego"`` (point body): HA-VLN's six egocentric actions, numbered as
  :class:`~havln_mj.sim.egocentric.EgoAction` (0 STOP).
* ``"robot"`` (GO1): :data:`~havln_mj.sim.body.ROBOT_ACTIONS` (0 stop, 1 forward 0.5 m,
  2 turn_left, 3 turn_right 45°).

``info`` always has ``scan``, ``path_id``, ``instr_id``, ``instruction``, ``goal``,
``viewpoint``, ``distance`` (to the goal, from where the body truly is), ``time``,
``reward_terms``, ``collision``, ``fell``, ``arrived``, ``stopped``, ``success`` and
``invalid_action``.
"""

from __future__ import annotations

import functools
import math
import numbers
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from havln_mj.errors import InvalidActionError, InvalidArgumentError, NotInitializedError
from havln_mj.sim.body import ROBOT_ACTIONS
from havln_mj.sim.egocentric import EgoAction
from havln_mj.tasks.datasets import load_dataset
from havln_mj.tasks.episodes import Episode, Instruction
from havln_mj.tasks.observations import Observations
from havln_mj.tasks.rewards import RewardFn
from havln_mj.tasks.step import STOP, Action, StepResult, TaskStep
from havln_mj.tasks.vocab import Vocabulary

DEFAULT_SCENES = ("proc-0",)
ACTION_SETS = {"graph": "point", "ego": "point", "robot": "go1"}  # action set -> body
_OPTIONS = ("instr_id", "index")


@functools.lru_cache(maxsize=8)
def _shared_episodes(scenes: tuple[str, ...], per_scene: int, seed: int) -> tuple[Episode, ...]:
    # Every env of a process shares them; scene i gets path ids from i * 10_000.
    from havln_mj.tasks.procedural import procedural_episodes

    return tuple(procedural_episodes(scenes, per_scene, seed, first_id=0))


def positive_int(name: str, value: object) -> int:
    """``value`` as an int ≥ 1, else an error naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
        raise InvalidArgumentError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def positive_float(name: str, value: object) -> float:
    """``value`` as a finite float > 0, else an error naming ``name``."""
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool)
    if not (ok and math.isfinite(value) and value > 0):
        raise InvalidArgumentError(f"{name} must be a positive number, got {value!r}")
    return float(value)


class EpisodeEnv:
    """The shared machinery of the HA-VLN environments.

    Args:
        action_set: ``"graph"``, ``"ego"`` or ``"robot"`` (see the module docstring).
        scenes: Procedural scene ids to generate episodes in (default ``("proc-0",)``);
            with ``dataset``, only the dataset's episodes in these scans are kept.
        episodes_per_scene: Paths generated per procedural scene.
        episode_seed: Seed of the generated episodes and of the simulator's people.
        dataset: An HA-R2R/R2R file or split name instead of procedural episodes.
        connectivity_dir: Folder of ``<scan>_connectivity.json`` for the dataset's scans.
        data_dir: Where split names are looked up (default ``$HAVLN_VLN_DATA``).
        scan_dir: The scans' mesh folder (the simulator's ``setDatasetPath``).
        humans: Whether scans have people.
        width: Image width (pixels).
        height: Image height (pixels).
        vfov: Vertical field of view (radians; default MatterSim's).
        rgb: Whether observations hold the RGB image.
        depth: Whether observations hold depth.
        human_mask: Whether observations hold the human mask.
        render: Whether frames are rendered for ``render()`` even without image fields.
        max_depth: Depth is clipped to this (metres).
        instruction_length: Token ids per instruction (longer ones are cut).
        vocab: A :class:`Vocabulary`, a token list, a ``vocab_<split>.txt`` file, or None to
            build it from the episodes' instructions.
        max_candidates: Navigable viewpoints described (and, in the graph set, actions).
        restricted_navigation: MatterSim's field-of-view rule for navigable viewpoints.
        reward: A reward name of :data:`havln_mj.tasks.rewards.REWARDS` or a function.
        reward_weights: Weight per reward term (default 1 for each).

    Raises:
        InvalidArgumentError: A bad value (the message names it and what is valid).
        MissingDataError: The dataset or vocabulary file does not exist.
    """

    def __init__(
        self,
        action_set: str,
        *,
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
        render: bool = False,
        max_depth: float = 20.0,
        instruction_length: int = 80,
        vocab: Vocabulary | Sequence[str] | str | Path | None = None,
        max_candidates: int = 16,
        restricted_navigation: bool = False,
        reward: str | RewardFn = "paper",
        reward_weights: Mapping[str, float] | None = None,
    ) -> None:
        if action_set not in ACTION_SETS:
            raise InvalidArgumentError(
                f"action set {action_set!r} unknown; valid: {', '.join(ACTION_SETS)}"
            )
        self.action_set = action_set
        self.body = ACTION_SETS[action_set]
        width, height = positive_int("width", width), positive_int("height", height)
        self._vfov = None if vfov is None else positive_float("vfov", vfov)
        self._humans = bool(humans)
        self._restricted = bool(restricted_navigation)
        self._paths = (connectivity_dir, scan_dir)
        if isinstance(episode_seed, bool) or not isinstance(episode_seed, numbers.Integral):
            raise InvalidArgumentError(f"episode_seed must be an integer, got {episode_seed!r}")
        self.episode_seed = int(episode_seed)
        self.episodes = self._load_episodes(
            scenes, episodes_per_scene, dataset, connectivity_dir, data_dir
        )
        self.instructions: tuple[Instruction, ...] = tuple(
            item for e in self.episodes for item in e.instruction_items()
        )
        self.vocab = self._load_vocab(vocab)
        self.observations = Observations(
            width=width,
            height=height,
            rgb=bool(rgb),
            depth=bool(depth),
            human_mask=bool(human_mask),
            max_depth=positive_float("max_depth", max_depth),
            instruction_length=positive_int("instruction_length", instruction_length),
            vocab_size=len(self.vocab),
            max_candidates=positive_int("max_candidates", max_candidates),
        )
        self._rendering = self.observations.rendering or bool(render)
        self._reward = (reward, reward_weights)
        self.weights = TaskStep(None, reward=reward, reward_weights=reward_weights).weights
        self.sim = None
        self._task: TaskStep | None = None
        self.current: Instruction | None = None
        self._tokens = np.zeros(self.observations.length, np.int64)
        self._last: StepResult | None = None

    @property
    def n_actions(self) -> int:
        """How many actions the action set has."""
        if self.action_set == "graph":
            return self.observations.k + 1
        return len(EgoAction) if self.action_set == "ego" else len(ROBOT_ACTIONS)

    def _load_episodes(self, scenes, per_scene, dataset, connectivity_dir, data_dir):
        if isinstance(scenes, str):
            raise InvalidArgumentError(f"scenes takes a list of scene ids, got {scenes!r}")
        if dataset is None:
            scenes = tuple(scenes or DEFAULT_SCENES)
            per_scene = positive_int("episodes_per_scene", per_scene)
            return _shared_episodes(scenes, per_scene, self.episode_seed)
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

    def _make_sim(self):
        from havln_mj.sim.simulator import Simulator

        obs = self.observations
        sim = Simulator(humans=self._humans, body=self.body)
        connectivity_dir, scan_dir = self._paths
        if connectivity_dir is not None:
            sim.setNavGraphPath(connectivity_dir)
        if scan_dir is not None:
            sim.setDatasetPath(scan_dir)
        sim.setRenderingEnabled(self._rendering)
        sim.setCameraResolution(obs.width, obs.height)
        if self._vfov is not None:
            sim.setCameraVFOV(self._vfov)
        sim.setDepthEnabled(obs.depth)
        sim.set_human_mask_enabled(obs.human_mask)
        sim.set_color_order("RGB")
        sim.set_depth_units("metres")
        sim.setRestrictedNavigation(self._restricted)
        sim.setSeed(self.episode_seed)  # the people the episodes were annotated with
        sim.initialize()
        return sim

    def __getstate__(self) -> dict[str, Any]:
        # The simulator (and its GL context) stays behind: an unpickled copy builds its own.
        state = self.__dict__.copy()
        state.update(sim=None, _task=None, current=None, _last=None)
        return state

    def choose(self, options: Mapping[str, Any], rng: np.random.Generator) -> Instruction:
        """The instruction ``options`` names (``instr_id`` or ``index``), else a random one."""
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
        return self.instructions[int(rng.integers(len(self.instructions)))]

    def reset(self, item: Instruction) -> tuple[dict[str, Any], dict[str, Any]]:
        """Starts ``item``'s episode at its path's start, heading, elevation 0."""
        if self.sim is None:
            self.sim = self._make_sim()
            reward, weights = self._reward
            self._task = TaskStep(self.sim, reward=reward, reward_weights=weights)
        self.current = item
        self._tokens = self.vocab.encode(item.text, self.observations.length)
        self._last = self._task.start([item.episode])[0]
        return self._observe(self._last), self.info(self._last, False)

    def check_action(self, action: object) -> int:
        """``action`` as an int of the action set, else :class:`InvalidActionError`."""
        if isinstance(action, np.ndarray) and action.shape == ():
            action = action.item()
        n = self.n_actions
        if isinstance(action, bool) or not isinstance(action, numbers.Integral):
            raise InvalidActionError(f"action must be an integer in 0–{n - 1}, got {action!r}")
        if not 0 <= action < n:
            raise InvalidActionError(f"action {action} out of range; valid 0–{n - 1}")
        return int(action)

    def _translate(self, action: int) -> tuple[Action, bool]:
        if self.action_set == "ego":
            return EgoAction(action), False
        if self.action_set == "robot":
            return ROBOT_ACTIONS[action], False
        if action == 0:
            return STOP, False
        navigable = self._last.state.navigableLocations
        if action >= len(navigable):
            return (0, 0.0, 0.0), True
        return (action, navigable[action].rel_heading, 0.0), False

    def step(self, action: object) -> tuple[dict[str, Any], float, bool, dict[str, Any]]:
        """Takes one action; returns ``(observation, reward, terminated, info)``.

        Raises:
            NotInitializedError: No episode is running.
            InvalidActionError: ``action`` is not in the action set.
        """
        if self._last is None or self._last.terminated:
            raise NotInitializedError("step() needs a running episode: call reset() first")
        act, invalid = self._translate(self.check_action(action))
        self._last = self._task.step([act])[0]
        r = self._last
        return self._observe(r), r.reward, r.terminated, self.info(r, invalid)

    def _observe(self, result: StepResult) -> dict[str, Any]:
        return self.observations.build(result.state, self._tokens, result.collided)

    def info(self, result: StepResult, invalid: bool) -> dict[str, Any]:
        """The step's ``info`` (the same keys at every step and at the start)."""
        item, state = self.current, result.state
        return {
            "scan": item.episode.scan,
            "path_id": item.episode.path_id,
            "instr_id": item.instr_id,
            "instruction": item.text,
            "goal": item.episode.goal,
            "viewpoint": state.location.viewpointId,
            "distance": result.distance,
            "time": float(state.time),
            "reward_terms": dict(result.reward_terms),
            "collision": result.collided,
            "fell": result.fell,
            "arrived": bool(state.arrived),
            "stopped": result.stopped,
            "success": result.success,
            "invalid_action": invalid,
        }

    def frame(self) -> np.ndarray | None:
        """A copy of the current RGB camera image (None before the first reset)."""
        if self._last is None:
            return None
        return np.array(self._last.state.rgb, copy=True)

    def close(self) -> None:
        """Releases the simulator (and its GL context); ``reset`` builds a new one."""
        if self.sim is not None:
            self.sim.close()
        self.sim = None
        self._task = None
        self.current = None
        self._last = None
