"""Trained agents as experts of the evaluation harness (``python -m havln_mj.eval --agent X.pt``).

:class:`AgentExpert` follows the :class:`havln_mj.tasks.experts.Expert` protocol: at each step
it reads the observation (the cached feature of the current view plus the agent's own
inputs), masks the invalid actions and asks the network. A viewpoint's features are rendered,
with the evaluation's people seed, the first time an agent stands on it, and added to the
feature cache: an evaluation renders only the viewpoints its agent reaches. VLN-DT conditions
on the return still to go: the reward of each action (the one it was trained with) is
computed from the simulator's outcome, as a decision transformer is evaluated.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path

import numpy as np

from havln_mj.agents.checkpoint import AgentBundle
from havln_mj.agents.featurize import encode_viewpoints, feature_store
from havln_mj.agents.observations import action_mask, observe
from havln_mj.agents.rollouts import INSTRUCTION_LENGTH
from havln_mj.agents.views import ViewRenderer
from havln_mj.errors import InvalidArgumentError
from havln_mj.sim.egocentric import EgoAction
from havln_mj.sim.state import SimState
from havln_mj.sim.viewing import ELEVATION_INCREMENT
from havln_mj.tasks.experts import ExpertContext
from havln_mj.tasks.rewards import StepOutcome, get_reward, step_reward

MAX_STEPS = 30  # HA3D's agents act at most 30 times


def make_policy(bundle: AgentBundle):
    """The step-by-step policy of a bundle's network."""
    if bundle.agent == "vln_cm":
        from havln_mj.agents.vln_cm import CMPolicy

        return CMPolicy(bundle.model)
    from havln_mj.agents.vln_dt import DTPolicy

    return DTPolicy(bundle.model)


class AgentExpert:
    """A trained VLN-CM / VLN-DT driving the simulator through one instruction at a time.

    Args:
        bundle: The agent.
        seed: The people seed of the evaluation (its features are rendered with it).
        connectivity_dir: Navigation graphs of real scans (for rendering their features).
        human_placements: HA3D placement file (for rendering real scans' people).
        max_steps: Cap on actions.
    """

    def __init__(
        self,
        bundle: AgentBundle,
        *,
        seed: int = 0,
        connectivity_dir: str | Path | None = None,
        human_placements: str | Path | None = None,
        max_steps: int = MAX_STEPS,
    ) -> None:
        self.bundle = bundle
        self.name = bundle.agent
        self.max_steps = max_steps
        self._spec = dataclasses.replace(bundle.features, seed=int(seed))
        self._render = {"connectivity_dir": connectivity_dir, "human_placements": human_placements}
        self._renderer: ViewRenderer | None = None
        self.store = feature_store(bundle.encoder, self._spec)
        self.policy = make_policy(bundle)
        reward = bundle.model_config.get("reward", "paper")
        self._reward = get_reward(reward)
        self._distance = 0.0

    def _ensure_features(self, scan: str, viewpoint: str) -> None:
        if self.store.has_viewpoint(scan, viewpoint):
            return
        if self._renderer is None:
            self._renderer = ViewRenderer(
                self._spec.view, seed=self._spec.seed, person_masks=False, **self._render
            )
        views = self._renderer.render(scan, [viewpoint])
        self.store.add(scan, *encode_viewpoints(self.bundle.encoder, views, self._spec.view))

    def reset(self, ctx: ExpertContext) -> None:
        """Encodes the instruction.

        Raises:
            InvalidArgumentError: The simulator does not use discretised views (agents look
                at the 36 discrete views).
        """
        state = ctx.sim.getState()[0]
        if state.viewIndex == 0 and abs(state.elevation + ELEVATION_INCREMENT) > 1e-6:
            raise InvalidArgumentError(
                "trained agents need setDiscretizedViewingAngles(True): they observe the 36 "
                "discrete views"
            )
        ids = self.bundle.vocab.encode(ctx.instruction_text, INSTRUCTION_LENGTH)
        self.policy.reset(ids)
        self._distance = ctx.graph.distance(state.location.viewpointId, ctx.goal)

    def act(self, ctx: ExpertContext, state: SimState) -> EgoAction:
        """The network's next action (greedy)."""
        half = ctx.sim.half_hfov
        last_reward = None
        distance = ctx.graph.distance(state.location.viewpointId, ctx.goal)
        if ctx.step > 0:
            outcome = StepOutcome(False, distance, distance - self._distance, bool(state.isCrushed))
            last_reward = step_reward(self._reward, outcome)
        self._distance = distance
        self._ensure_features(state.scanId, state.location.viewpointId)
        mask = action_mask(state, half)
        action = self.policy.act(observe(self.store, state, mask), mask, last_reward)
        return EgoAction(action)


def load_agent(
    path: str | Path,
    *,
    seed: int = 0,
    connectivity_dir: str | Path | None = None,
    human_placements: str | Path | None = None,
) -> Callable[[np.random.Generator], AgentExpert]:
    """The evaluation harness's factory for a checkpoint: ``(rng) -> AgentExpert``.

    The network and the feature set are loaded once and shared by every episode.

    Raises:
        MissingDataError: No such checkpoint.
        MalformedDataError: The file is not an agent checkpoint.
    """
    bundle = AgentBundle.load(path)
    expert = AgentExpert(
        bundle, seed=seed, connectivity_dir=connectivity_dir, human_placements=human_placements
    )
    return lambda rng: expert
