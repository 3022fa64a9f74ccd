"""Many instructions run side by side in one simulator with egocentric actions.

:class:`EgoRollouts` drives a batch simulator (rendering off: agents read cached features)
through up to ``B`` instructions at once. It gives each element's observation and action mask,
the human-aware expert's action (the teacher of VLN-CM, also for states the agent reached on
its own: student forcing), takes a batch of actions and reports their outcomes. STOP ends an
element's episode; an element also ends at the step cap.

:func:`collect_demos` records whole rollouts as :class:`~havln_mj.agents.demos.Demo` for
teacher forcing and offline training: the expert's, or a random walk's (HA-VLN's VLN-DT data:
at most 30 steps, FORWARD / left / right / STOP drawn 0.5 / 0.2 / 0.2 / 0.1 among the actions
valid in the state).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from tqdm import tqdm

from havln_mj.agents.demos import N_ACTIONS, Demo
from havln_mj.agents.features import FeatureStore
from havln_mj.agents.observations import action_mask, observe
from havln_mj.errors import InvalidArgumentError
from havln_mj.sim.egocentric import EgoAction
from havln_mj.sim.simulator import Simulator
from havln_mj.tasks.episodes import Instruction
from havln_mj.tasks.experts import ExpertContext, HumanAwareExpert
from havln_mj.tasks.step import TaskStep
from havln_mj.tasks.vocab import Vocabulary

INSTRUCTION_LENGTH = 80  # tokens, as HA3D's encoder reads
RANDOM_MAX_STEPS = 30
RANDOM_PROBABILITIES = {
    EgoAction.FORWARD: 0.5,
    EgoAction.TURN_LEFT: 0.2,
    EgoAction.TURN_RIGHT: 0.2,
    EgoAction.STOP: 0.1,
}


def make_simulator(
    batch_size: int,
    seed: int,
    *,
    humans: bool = True,
    connectivity_dir: str | None = None,
    human_placements: str | None = None,
) -> Simulator:
    """A rendering-off simulator for rollouts: discretised views, the given people seed."""
    sim = Simulator(humans=humans, human_placements=human_placements)
    if connectivity_dir is not None:
        sim.setNavGraphPath(str(connectivity_dir))
    sim.setBatchSize(batch_size)
    sim.setRenderingEnabled(False)
    sim.setDiscretizedViewingAngles(True)
    sim.setSeed(seed)
    sim.initialize()
    return sim


class _ElementView:
    """What the expert sees of one batch element: its people and the camera's FOV."""

    def __init__(self, rollouts: EgoRollouts, i: int) -> None:
        self._rollouts, self._i = rollouts, i
        self.half_hfov = rollouts.sim.half_hfov

    def getHumanPositions(self) -> list[np.ndarray]:  # noqa: N802 - the simulator's name
        return [self._rollouts.human_positions()[self._i]]


@dataclass(frozen=True)
class StepResult:
    """Outcomes of one batch step (arrays over the batch; meaningful where ``acted``).

    Attributes:
        acted: The element was running and took an action.
        distance: Geodesic distance to the goal after the action.
        delta: Its change over the action.
        collided: The action came within the collision distance of a person.
        stopped: The action was STOP.
    """

    acted: np.ndarray
    distance: np.ndarray
    delta: np.ndarray
    collided: np.ndarray
    stopped: np.ndarray


class EgoRollouts:
    """Up to ``sim``'s batch size of instructions, stepped together.

    Args:
        sim: An initialised simulator (rendering off, discretised views); its batch size is
            the most instructions run at once.
        store: The view features the observations are read from.
        vocab: Encodes the instructions.
        max_steps: Step cap per episode.
    """

    def __init__(
        self, sim: Simulator, store: FeatureStore, vocab: Vocabulary, max_steps: int = 40
    ) -> None:
        if max_steps < 1:
            raise InvalidArgumentError(f"max_steps must be at least 1, got {max_steps}")
        self.sim, self.store, self.vocab, self.max_steps = sim, store, vocab, max_steps
        self.batch_size = sim.batch_size
        self.instructions: list[Instruction] = []
        self.done = np.ones(0, bool)
        self.steps = np.zeros(0, int)
        # One teacher for every element: its egocentric route tables are per scan and goal,
        # so they are shared by the whole batch and kept across episodes.
        self._expert = HumanAwareExpert(mode="local", action_space="ego")
        self._contexts: list[ExpertContext] = []
        self._humans: list[np.ndarray] | None = None
        self._task = TaskStep(sim)

    def human_positions(self) -> list[np.ndarray]:
        """Every element's people's pelvis positions now (computed once per step)."""
        if self._humans is None:
            self._humans = self.sim.getHumanPositions()
        return self._humans

    def start(self, instructions: Sequence[Instruction]) -> None:
        """Starts one episode per instruction (at most the batch size).

        Unused batch elements repeat the last instruction and are marked done.
        """
        n = len(instructions)
        if not 1 <= n <= self.batch_size:
            raise InvalidArgumentError(
                f"{n} instructions for a batch of {self.batch_size}; valid: 1–{self.batch_size}"
            )
        padded = list(instructions) + [instructions[-1]] * (self.batch_size - n)
        episodes = [ins.episode for ins in padded]
        self._task.start(episodes)
        self.instructions = list(instructions)
        self.done = np.arange(self.batch_size) >= n
        self.steps = np.zeros(self.batch_size, int)
        self._humans = None
        self._contexts = [
            ExpertContext(_ElementView(self, i), e, self.sim.graph(e.scan))
            for i, e in enumerate(episodes)
        ]
        for ctx in self._contexts:
            self._expert.reset(ctx)

    def encoded_instructions(self, length: int = INSTRUCTION_LENGTH) -> np.ndarray:
        """``(n, length)`` int64 token ids of the running instructions."""
        return np.stack([self.vocab.encode(i.text, length) for i in self.instructions])

    def observe(self) -> tuple[np.ndarray, np.ndarray]:
        """``(B, D)`` observations and ``(B, 6)`` action masks of every element."""
        half = self.sim.half_hfov
        states = self.sim.getState()
        masks = np.stack([action_mask(s, half) for s in states])
        obs = np.stack([observe(self.store, s, m) for s, m in zip(states, masks, strict=True)])
        return obs, masks

    def expert_actions(self) -> np.ndarray:
        """``(B,)`` the human-aware egocentric expert's action per element (STOP when done)."""
        states = self.sim.getState()
        out = np.zeros(self.batch_size, np.int64)
        for i, (ctx, state) in enumerate(zip(self._contexts, states, strict=True)):
            if not self.done[i]:
                ctx.step = int(self.steps[i])
                out[i] = int(self._expert.act(ctx, state))
        return out

    def step(self, actions: Sequence[int] | np.ndarray) -> StepResult:
        """Takes one action per element; done elements are left alone.

        Raises:
            InvalidArgumentError: An action is not an egocentric action index.
        """
        actions = np.asarray(actions, np.int64)
        if actions.shape != (self.batch_size,) or ((actions < 0) | (actions >= N_ACTIONS)).any():
            raise InvalidArgumentError(
                f"actions must be {self.batch_size} egocentric action indices 0–{N_ACTIONS - 1}, "
                f"got {actions.tolist()}"
            )
        acted = ~self.done
        before = np.array([r.distance for r in self._task.results])
        results = self._task.step(
            [EgoAction(int(a)) if run else None for a, run in zip(actions, acted, strict=True)]
        )
        self._humans = None
        distance = np.array([r.distance for r in results])
        collided = np.array(
            [bool(r.collided) and run for r, run in zip(results, acted, strict=True)]
        )
        stopped = acted & (actions == EgoAction.STOP)
        self.steps += acted
        self.done = self.done | stopped | (self.steps >= self.max_steps)
        return StepResult(acted, distance, distance - before, collided, stopped)


def _random_action(mask: np.ndarray, rng: np.random.Generator, last: bool) -> int:
    if last:
        return int(EgoAction.STOP)
    actions = [a for a in RANDOM_PROBABILITIES if mask[a]]
    p = np.array([RANDOM_PROBABILITIES[a] for a in actions])
    return int(actions[int(rng.choice(len(actions), p=p / p.sum()))])


def collect_demos(
    rollouts: EgoRollouts,
    instructions: Sequence[Instruction],
    source: str,
    rng: np.random.Generator | None = None,
    *,
    progress: bool = True,
) -> list[Demo]:
    """Runs the expert or a random walk through every instruction and records it.

    Args:
        rollouts: The batch runner.
        instructions: What to run.
        source: ``"expert"`` (the human-aware egocentric expert) or ``"random"``.
        rng: The random walk's generator (required for ``"random"``).
        progress: Show a progress bar.

    Raises:
        InvalidArgumentError: Unknown ``source``, or ``"random"`` without a generator.
    """
    if source not in ("expert", "random"):
        raise InvalidArgumentError(f"demo source {source!r} unknown; valid: 'expert', 'random'")
    if source == "random" and rng is None:
        raise InvalidArgumentError("random-walk demos need a numpy Generator (rng=...)")
    cap = rollouts.max_steps if source == "expert" else min(rollouts.max_steps, RANDOM_MAX_STEPS)
    out: list[Demo] = []
    bsz = rollouts.batch_size
    bar = tqdm(total=len(instructions), desc=f"{source} demos", unit="instr", disable=not progress)
    for first in range(0, len(instructions), bsz):
        chunk = list(instructions[first : first + bsz])
        rollouts.start(chunk)
        ids = rollouts.encoded_instructions()
        rec: list[dict[str, list]] = [
            {k: [] for k in ("obs", "act", "mask", "dist", "delta", "hit")} for _ in chunk
        ]
        while not rollouts.done[: len(chunk)].all():
            obs, masks = rollouts.observe()
            if source == "expert":
                actions = rollouts.expert_actions()
            else:
                actions = np.array(
                    [
                        _random_action(masks[i], rng, rollouts.steps[i] >= cap - 1)
                        for i in range(bsz)
                    ]
                )
            running = ~rollouts.done
            result = rollouts.step(actions)
            for i in np.flatnonzero(running[: len(chunk)]):
                r = rec[i]
                r["obs"].append(obs[i])
                r["act"].append(actions[i])
                r["mask"].append(masks[i])
                r["dist"].append(result.distance[i])
                r["delta"].append(result.delta[i])
                r["hit"].append(result.collided[i])
        for ins, token_ids, r in zip(chunk, ids, rec, strict=True):
            out.append(
                Demo(
                    instr_id=ins.instr_id,
                    source=source,
                    instruction=token_ids,
                    obs=np.stack(r["obs"]).astype(np.float32),
                    actions=np.array(r["act"], np.int64),
                    masks=np.stack(r["mask"]),
                    distance=np.array(r["dist"], np.float32),
                    delta=np.array(r["delta"], np.float32),
                    collided=np.array(r["hit"], bool),
                )
            )
        bar.update(len(chunk))
    bar.close()
    return out
