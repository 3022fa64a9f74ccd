"""Experts that drive the discrete simulator through an episode, and the runner that logs them.

* :class:`ShortestPathExpert`: the optimal teacher. With graph actions it is R2R's
  ``_shortest_path_action``: move to the next viewpoint of the shortest path when it is listed
  and within ±30° of the heading, else turn 30° towards it (after levelling the camera); STOP
  at the goal. With egocentric actions it turns until FORWARD would take the next viewpoint.
* :class:`~.HumanAwareExpert`: HA3D's sub-optimal expert. ``mode="local"`` (HA3D's default)
  re-plans every step on the graph without the nodes within 1 m of the people within 4.5 m of
  the agent (the current node and the goal kept); ``mode="global"`` plans once on G' = G
  without the nodes within 1 m of anyone at the start. When no path exists it waits (index 0,
  no turn), up to ``max_waits`` times per episode, then walks on ignoring people (or stops:
  ``after_waits``); HA3D's stops at once (see :mod:`havln_mj.tasks.protocol`).
* :class:`RandomWalkExpert`: seeded random egocentric actions, at most 30 steps (VLN-DT data).

:func:`run_expert` runs one episode and returns a :class:`~.Trajectory`: one record per action
with the state after it, the collision signal, the simulated time and the rewards of
:mod:`havln_mj.tasks.rewards`.

Paths are shortest by length (HA3D's sub-optimal expert counts hops; ``weighted=False`` does
that); the planning they follow is in :mod:`havln_mj.tasks.planning` (graph paths around
people) and :mod:`havln_mj.tasks.ego_routes` (egocentric routes). What every expert is given
is in :mod:`havln_mj.tasks.expert_context`, the human-aware expert in
:mod:`havln_mj.tasks.human_aware` and the records of a run in :mod:`havln_mj.tasks.trajectory`;
their public names are importable from here too.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Protocol

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.frames import wrap_angle
from havln_mj.scene.navgraph import NavGraph
from havln_mj.sim.egocentric import EgoAction
from havln_mj.sim.state import SimState
from havln_mj.tasks.ego_routes import ego_plan, forward_target
from havln_mj.tasks.episodes import Episode
from havln_mj.tasks.expert_context import (
    DEFAULT_HALF_HFOV,
    WAIT,
    ExpertContext,
    level_camera,
    positive_int,
    sim_half_hfov,
)
from havln_mj.tasks.human_aware import HumanAwareExpert
from havln_mj.tasks.planning import TURN, graph_teacher, plan_path
from havln_mj.tasks.protocol import TaskProtocol
from havln_mj.tasks.rewards import RewardFn
from havln_mj.tasks.step import STOP, Action, TaskStep
from havln_mj.tasks.trajectory import StepRecord, Trajectory, record_of

__all__ = [
    "STOP",
    "WAIT",
    "Expert",
    "ExpertContext",
    "HumanAwareExpert",
    "RandomWalkExpert",
    "ShortestPathExpert",
    "StepRecord",
    "Trajectory",
    "run_expert",
]


class Expert(Protocol):
    """An expert policy for :func:`run_expert`.

    Attributes:
        name: Short name for logs.
        max_steps: Default cap on actions per episode.
    """

    name: str
    max_steps: int

    def reset(self, ctx: ExpertContext) -> None:
        """Called after ``newEpisode``, before the first action."""
        ...

    def act(self, ctx: ExpertContext, state: SimState) -> Action:
        """The next action.

        Returns:
            An ``EgoAction`` (``STOP`` ends the episode) or a graph action ``(navigable
            index, dHeading, dElevation)``.
        """
        ...


# ---------------------------------------------------------------------- experts


class ShortestPathExpert:
    """The optimal expert: follows the shortest path to the goal and stops there.

    Args:
        action_space: ``"graph"`` (``makeAction`` tuples) or ``"ego"`` (``EgoAction``).
        half_hfov: Half the camera's horizontal field of view, which decides where FORWARD
            goes (ego only; default: the simulator's).
        max_steps: Default cap on actions.
    """

    def __init__(
        self, action_space: str = "graph", *, half_hfov: float | None = None, max_steps: int = 150
    ) -> None:
        if action_space not in ("graph", "ego"):
            raise InvalidArgumentError(
                f"action_space {action_space!r} unknown; valid: 'graph', 'ego'"
            )
        self.action_space = action_space
        self.name = f"shortest_{action_space}"
        self.max_steps = positive_int("max_steps", max_steps)
        self._half_hfov = half_hfov
        self._hfov = DEFAULT_HALF_HFOV
        self._plan: list[tuple[EgoAction, str, float]] = []

    def reset(self, ctx: ExpertContext) -> None:
        """Reads the camera's field of view from the simulator."""
        self._hfov = self._half_hfov if self._half_hfov is not None else sim_half_hfov(ctx.sim)
        self._plan = []

    def _ego(self, ctx: ExpertContext, state: SimState) -> EgoAction:
        level = level_camera(state)
        if level is not None:
            return level
        here = state.location.viewpointId
        if self._plan:
            # Follow the plan while the simulator lands where it was expected to.
            _, vp, heading = self._plan[0]
            if vp != here or abs(wrap_angle(heading - state.heading)) > 1e-6:
                self._plan = []
        if not self._plan:
            actions = ego_plan(ctx.graph, here, state.heading, ctx.goal, self._hfov)
            if actions is None:
                return STOP  # FORWARD and turns cannot reach the goal from here
            self._plan = self._expected(ctx.graph, here, state.heading, actions)
        return self._plan.pop(0)[0]

    def _expected(
        self, graph: NavGraph, vp: str, heading: float, actions: list[EgoAction]
    ) -> list[tuple[EgoAction, str, float]]:
        """Each action with the (viewpoint, heading) it is taken from."""
        out = []
        for action in actions:
            out.append((action, vp, heading))
            if action is EgoAction.FORWARD:
                vp = forward_target(graph, vp, heading, 0.0, self._hfov) or vp
            elif action is EgoAction.TURN_RIGHT:
                heading += TURN
            elif action is EgoAction.TURN_LEFT:
                heading -= TURN
        return out

    def act(self, ctx: ExpertContext, state: SimState) -> Action:
        """The next teacher action."""
        here, goal = state.location.viewpointId, ctx.goal
        if self.action_space == "ego":
            return self._ego(ctx, state)
        if here == goal:
            return STOP
        path = plan_path(ctx.graph, here, goal)
        if path is None:
            return STOP  # the goal cannot be reached from here at all
        return graph_teacher(state, path[1], ctx.graph)


class RandomWalkExpert:
    """Random egocentric actions from a seeded generator (VLN-DT's random-walk data).

    Each step draws FORWARD, TURN_LEFT, TURN_RIGHT or STOP with ``probabilities``; the walk
    stops at the latest on its ``max_steps``-th action.

    Args:
        rng: The generator every choice comes from.
        max_steps: Most actions per episode, STOP included (the paper: 30).
        probabilities: Of FORWARD, TURN_LEFT, TURN_RIGHT, STOP.
    """

    ACTIONS = (EgoAction.FORWARD, EgoAction.TURN_LEFT, EgoAction.TURN_RIGHT, EgoAction.STOP)

    def __init__(
        self,
        rng: np.random.Generator,
        *,
        max_steps: int = 30,
        probabilities: Sequence[float] = (0.5, 0.2, 0.2, 0.1),
    ) -> None:
        if not isinstance(rng, np.random.Generator):
            raise InvalidArgumentError(f"rng must be a numpy.random.Generator, got {rng!r}")
        p = np.asarray(probabilities, float)
        if p.shape != (4,) or (p < 0).any() or not math.isclose(p.sum(), 1.0):
            raise InvalidArgumentError(
                f"probabilities must be 4 non-negative numbers summing to 1 (FORWARD, "
                f"TURN_LEFT, TURN_RIGHT, STOP), got {probabilities!r}"
            )
        self.rng = rng
        self.max_steps = positive_int("max_steps", max_steps)
        self.probabilities = p
        self.name = "random_walk"

    def reset(self, ctx: ExpertContext) -> None:
        """Nothing to prepare."""

    def act(self, ctx: ExpertContext, state: SimState) -> Action:
        """A random action; STOP on the last allowed step."""
        if ctx.step >= self.max_steps - 1:
            return STOP
        return self.ACTIONS[int(self.rng.choice(4, p=self.probabilities))]


# ---------------------------------------------------------------------- running


def _sim_graph(sim: object, scan: str) -> NavGraph:
    # Sharing the simulator's graph shares the all-pairs distances it has computed.
    graph = getattr(sim, "graph", None)
    if not callable(graph):
        raise InvalidArgumentError(
            "cannot get the navigation graph from this simulator; pass graph=NavGraph(...)"
        )
    return graph(scan)


def run_expert(
    sim: object,
    episode: Episode,
    expert: Expert,
    *,
    graph: NavGraph | None = None,
    reward: str | RewardFn = "paper",
    max_steps: int | None = None,
    instruction: int = 0,
    protocol: str | TaskProtocol | None = None,
) -> Trajectory:
    """Runs ``expert`` through ``episode`` on ``sim`` (batch size 1) with the task step.

    Starts the episode at its start viewpoint, heading and elevation 0, then asks the expert
    for actions until it says STOP or ``max_steps`` actions were taken. Collisions, rewards
    and distances are the task step's (:mod:`havln_mj.tasks.step`).

    Args:
        sim: A ``havln_mj.Simulator`` (rendering may be off).
        episode: The episode.
        expert: The expert.
        graph: The scan's graph (default: the simulator's).
        reward: A reward name of :data:`havln_mj.tasks.rewards.REWARDS` or a function.
        max_steps: Cap on actions (default: the expert's ``max_steps``).
        instruction: Which of the episode's instructions the expert follows (agents that
            read it find it in :attr:`~.ExpertContext.instruction_text`).
        protocol: Sets the simulator's collision rule and human clock for this protocol
            (see :mod:`havln_mj.tasks.protocol`); None leaves them as they are.

    Returns:
        The trajectory, with per-step rewards.
    """
    cap = positive_int("max_steps", expert.max_steps if max_steps is None else max_steps)
    episode.instruction(instruction)  # raises for an index the episode does not have
    task = TaskStep(sim, reward=reward, max_steps=cap, protocol=protocol)
    result = task.start([episode])[0]
    graph = graph or _sim_graph(sim, episode.scan)
    ctx = ExpertContext(sim, episode, graph, instruction=instruction)
    records = [record_of(result)]
    expert.reset(ctx)
    while not result.done:
        result = task.step([expert.act(ctx, result.state)])[0]
        records.append(record_of(result))
        ctx.step += 1
    return Trajectory(episode, expert.name, tuple(records), result.stopped)
