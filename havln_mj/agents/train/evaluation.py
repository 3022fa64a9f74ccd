"""Greedy rollouts of a trained agent during training: SR, navigation error, collisions."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from havln_mj.agents.checkpoint import AgentBundle
from havln_mj.agents.policy import make_policy
from havln_mj.agents.rollouts import EgoRollouts
from havln_mj.tasks.episodes import Instruction
from havln_mj.tasks.rewards import SUCCESS_DISTANCE, StepOutcome, get_reward, step_reward


def _chunk(
    bundle: AgentBundle, rollouts: EgoRollouts, chunk: Sequence[Instruction], reward: str
) -> list[tuple[bool, float, float]]:
    """Runs one batch of instructions to the end: (success, final distance, collisions) each."""
    fn = get_reward(reward)
    rollouts.start(chunk)
    policies = [make_policy(bundle) for _ in chunk]
    for policy, ids in zip(policies, rollouts.encoded_instructions(), strict=True):
        policy.reset(ids)
    n = len(chunk)
    last: list[float | None] = [None] * n
    hits, final = np.zeros(n), np.zeros(n)
    while not rollouts.done[:n].all():
        obs, masks = rollouts.observe()
        actions = np.zeros(rollouts.batch_size, np.int64)
        running = np.flatnonzero(~rollouts.done[:n])
        for i in running:
            actions[i] = policies[i].act(obs[i], masks[i], last[i])
        r = rollouts.step(actions)
        for i in running:
            out = StepOutcome(
                bool(r.stopped[i]), float(r.distance[i]), float(r.delta[i]), bool(r.collided[i])
            )
            last[i] = step_reward(fn, out)
            hits[i] += r.collided[i]
            final[i] = r.distance[i]
    return [(f < SUCCESS_DISTANCE, f, h) for f, h in zip(final, hits, strict=True)]


def evaluate(
    bundle: AgentBundle,
    rollouts: EgoRollouts,
    instructions: Sequence[Instruction],
    reward: str = "paper",
) -> dict[str, float]:
    """Greedy rollouts of the bundle's policy: SR, NE (geodesic), collisions per episode."""
    results = []
    bsz = rollouts.batch_size
    for first in range(0, len(instructions), bsz):
        results += _chunk(bundle, rollouts, list(instructions[first : first + bsz]), reward)
    a = np.array(results, float)
    return {
        "sr": float(a[:, 0].mean()),
        "ne": float(a[:, 1].mean()),
        "collisions": float(a[:, 2].mean()),
    }
