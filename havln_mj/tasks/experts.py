"""Experts that drive the discrete simulator through an episode, and the runner that logs them.

* :class:`ShortestPathExpert`: the optimal teacher. With graph actions it is R2R's
  ``_shortest_path_action``: move to the next viewpoint of the shortest path when it is listed
  and within ±30° of the heading, else turn 30° towards it (after levelling the camera); STOP
  at the goal. With egocentric actions it turns until FORWARD would take the next viewpoint.
* :class:`HumanAwareExpert`: HA3D's sub-optimal expert. ``mode="local"`` (HA3D's default)
  re-plans every step on the graph without the nodes within 1 m of the people within 4.5 m of
  the agent (the current node and the goal kept); ``mode="global"`` plans once on G' = G
  without the nodes within 1 m of anyone at the start. When no path exists it waits (index 0,
  no turn) instead of stopping.
* :class:`RandomWalkExpert`: seeded random egocentric actions, at most 30 steps (VLN-DT data).

:func:`run_expert` runs one episode and returns a :class:`Trajectory`: one record per action
with the state after it, the collision signal, the simulated time and the rewards of
:mod:`havln_mj.tasks.rewards`.

Paths are shortest by length (HA3D's sub-optimal expert counts hops; ``weighted=False`` does
that); the planning they follow is in :mod:`havln_mj.tasks.planning` (graph paths around
people) and :mod:`havln_mj.tasks.ego_routes` (egocentric routes).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.frames import wrap_angle
from havln_mj.scene.navgraph import NavGraph
from havln_mj.sim.egocentric import EgoAction
from havln_mj.sim.state import SimState
from havln_mj.tasks.ego_routes import EgoRoutes, ego_plan, forward_target
from havln_mj.tasks.episodes import Episode
from havln_mj.tasks.planning import (
    CLEARANCE,
    SIGHT_RADIUS,
    TURN,
    PathPlanner,
    graph_teacher,
    people_near,
    plan_path,
)
from havln_mj.tasks.rewards import RewardFn
from havln_mj.tasks.step import STOP, Action, GraphAction, StepResult, TaskStep

WAIT: GraphAction = (0, 0.0, 0.0)
# MatterSim's default camera (VFOV 0.8 rad, 320×240), when the simulator cannot tell.
DEFAULT_HALF_HFOV = 0.8 * 320 / 240 / 2


@dataclass
class ExpertContext:
    """What an expert sees of the running episode.

    Attributes:
        sim: The simulator (batch size 1, episode started).
        episode: The episode.
        graph: The scan's navigation graph (the simulator's own).
        step: Number of actions taken so far.
        instruction: Which of the episode's instructions is being followed.
    """

    sim: object
    episode: Episode
    graph: NavGraph
    step: int = 0
    instruction: int = 0

    @property
    def instruction_text(self) -> str:
        """The instruction being followed."""
        return self.episode.instructions[self.instruction]

    @property
    def goal(self) -> str:
        """The goal viewpoint."""
        return self.episode.goal


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


def _level_camera(state: SimState) -> EgoAction | None:
    """LOOK_DOWN / LOOK_UP while the camera is off level (egocentric experts plan level)."""
    if state.elevation > TURN / 2:
        return EgoAction.LOOK_DOWN
    if state.elevation < -TURN / 2:
        return EgoAction.LOOK_UP
    return None


def _sim_half_hfov(sim: object) -> float:
    # The simulator's own half-HFOV rule decides FORWARD.
    return float(getattr(sim, "half_hfov", DEFAULT_HALF_HFOV))


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
        self.max_steps = _positive("max_steps", max_steps)
        self._half_hfov = half_hfov
        self._hfov = DEFAULT_HALF_HFOV
        self._plan: list[tuple[EgoAction, str, float]] = []

    def reset(self, ctx: ExpertContext) -> None:
        """Reads the camera's field of view from the simulator."""
        self._hfov = self._half_hfov if self._half_hfov is not None else _sim_half_hfov(ctx.sim)
        self._plan = []

    def _ego(self, ctx: ExpertContext, state: SimState) -> EgoAction:
        level = _level_camera(state)
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


class HumanAwareExpert:
    """HA3D's sub-optimal expert: avoids the nodes near people, waits when boxed in.

    With egocentric actions (``action_space="ego"``, the teacher of the egocentric agents)
    it follows :func:`ego_plan` with FORWARD kept out of the avoided nodes. The egocentric set
    has no wait, and HA3D's "no path" answer is the STOP tuple, which would teach an agent to
    stop beside people; so when no route avoids them it takes the shortest egocentric route
    regardless, counting the step in ``waits``.

    Args:
        mode: ``"local"`` re-plans each step around the people within ``sight_radius`` of
            the agent; ``"global"`` plans once around everyone (re-planning only while no
            path exists).
        action_space: ``"graph"`` (``makeAction`` tuples) or ``"ego"`` (``EgoAction``).
        sight_radius: How near the agent a person must be to matter (local mode).
        clearance: Nodes this close to such a person are removed (start and goal kept).
        weighted: Shortest by length (True) or by number of edges (HA3D).
        max_steps: Default cap on actions.

    Attributes:
        last_plan: The path planned at the last step (None when blocked; graph actions).
        waits: How many times the expert waited in the current episode (ego: went on
            without a route around people).
    """

    def __init__(
        self,
        mode: str = "local",
        *,
        action_space: str = "graph",
        sight_radius: float = SIGHT_RADIUS,
        clearance: float = CLEARANCE,
        weighted: bool = True,
        max_steps: int = 150,
    ) -> None:
        if mode not in ("local", "global"):
            raise InvalidArgumentError(f"mode {mode!r} unknown; valid: 'local', 'global'")
        if action_space not in ("graph", "ego"):
            raise InvalidArgumentError(
                f"action_space {action_space!r} unknown; valid: 'graph', 'ego'"
            )
        for name, value in (("sight_radius", sight_radius), ("clearance", clearance)):
            if not (isinstance(value, int | float) and value >= 0 and math.isfinite(value)):
                raise InvalidArgumentError(f"{name} must be a finite number ≥ 0, got {value!r}")
        self.mode = mode
        self.action_space = action_space
        self.name = f"human_aware_{mode}" + ("_ego" if action_space == "ego" else "")
        self.sight_radius = float(sight_radius)
        self.clearance = float(clearance)
        self.weighted = weighted
        self.max_steps = _positive("max_steps", max_steps)
        self.last_plan: list[str] | None = None
        self.waits = 0
        self._route: list[str] | None = None
        self._avoid: frozenset[str] = frozenset()  # global mode, egocentric actions
        self._hfov = DEFAULT_HALF_HFOV
        self._routes: dict[str, EgoRoutes] = {}
        self._planners: dict[str, PathPlanner] = {}

    @staticmethod
    def _people(ctx: ExpertContext) -> np.ndarray:
        return np.asarray(ctx.sim.getHumanPositions()[0], float).reshape(-1, 3)

    def _planner(self, ctx: ExpertContext) -> PathPlanner:
        planner = self._planners.get(ctx.episode.scan)
        if planner is None or planner.graph is not ctx.graph:
            planner = self._planners[ctx.episode.scan] = PathPlanner(ctx.graph)
        return planner

    def _blocked_near(self, ctx: ExpertContext, here: str) -> set[str]:
        """Local mode: the nodes near the people within sight of ``here``."""
        near = people_near(ctx.graph, here, self._people(ctx), self.sight_radius)
        return self._planner(ctx).blocked(near, self.clearance, (here, ctx.goal))

    def _global_route(self, ctx: ExpertContext, here: str) -> list[str] | None:
        planner = self._planner(ctx)
        blocked = planner.blocked(self._people(ctx), self.clearance, (here, ctx.goal))
        return planner.plan(here, ctx.goal, blocked, weighted=self.weighted)

    def reset(self, ctx: ExpertContext) -> None:
        """Plans G' once (global mode)."""
        self.last_plan, self.waits = None, 0
        self._hfov = _sim_half_hfov(ctx.sim)
        if self.action_space == "ego":
            keep = (ctx.episode.start, ctx.goal)
            people = self._people(ctx) if self.mode == "global" else ()
            self._avoid = frozenset(self._planner(ctx).blocked(people, self.clearance, keep))
            return
        self._route = self._global_route(ctx, ctx.episode.start) if self.mode == "global" else None

    def _ego(self, ctx: ExpertContext, state: SimState) -> EgoAction:
        level = _level_camera(state)
        if level is not None:
            return level
        here, goal, graph = state.location.viewpointId, ctx.goal, ctx.graph
        if here == goal:
            return STOP
        if self.mode == "local":
            avoid = frozenset(self._blocked_near(ctx, here))
        else:
            avoid = self._avoid - {here}
        routes = self._routes.get(ctx.episode.scan)
        if routes is None or routes.graph is not graph or routes.half_hfov != self._hfov:
            routes = self._routes[ctx.episode.scan] = EgoRoutes(graph, self._hfov)
        step = routes.heading_step(state.heading)
        if step is None:  # continuous headings: plan from here
            plan = ego_plan(graph, here, state.heading, goal, self._hfov, avoid)
            if plan is None:
                self.waits += 1
                plan = ego_plan(graph, here, state.heading, goal, self._hfov)
            return STOP if plan is None else plan[0]
        action = routes.first_action(here, step, goal, avoid)
        if action is None:
            self.waits += 1
            action = routes.first_action(here, step, goal, frozenset())
        return STOP if action is None else action

    def act(self, ctx: ExpertContext, state: SimState) -> Action:
        """The next action: teacher towards the planned next node, WAIT when blocked."""
        if self.action_space == "ego":
            return self._ego(ctx, state)
        here, goal, graph = state.location.viewpointId, ctx.goal, ctx.graph
        if here == goal:
            return STOP
        if self.mode == "local":
            blocked = self._blocked_near(ctx, here)
            path = self._planner(ctx).plan(here, goal, blocked, weighted=self.weighted)
        else:
            if self._route is None or here not in self._route:
                self._route = self._global_route(ctx, here)
            path = None if self._route is None else self._route[self._route.index(here) :]
        self.last_plan = path
        if path is None:
            self.waits += 1
            return WAIT
        return graph_teacher(state, path[1], graph)


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
        self.max_steps = _positive("max_steps", max_steps)
        self.probabilities = p
        self.name = "random_walk"

    def reset(self, ctx: ExpertContext) -> None:
        """Nothing to prepare."""

    def act(self, ctx: ExpertContext, state: SimState) -> Action:
        """A random action; STOP on the last allowed step."""
        if ctx.step >= self.max_steps - 1:
            return STOP
        return self.ACTIONS[int(self.rng.choice(4, p=self.probabilities))]


def _positive(name: str, value: object) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise InvalidArgumentError(f"{name} must be an integer ≥ 1, got {value!r}")
    return value


# ---------------------------------------------------------------------- running


@dataclass(frozen=True)
class StepRecord:
    """The state after one action (or the start state).

    Attributes:
        action: The action (None for the start state).
        viewpoint: Viewpoint id after the action.
        heading: Heading after the action (radians).
        elevation: Elevation after the action (radians).
        is_crushed: HA3D's ``isCrushed``: 1 when the action came within the collision
            distance of a person.
        crushed_by: Indices of those people in ``getHumanState()``.
        time: Simulated seconds since the start.
        distance: Geodesic distance to the goal (metres).
        rewards: Reward terms by name plus ``"total"`` (empty for the start state).
    """

    action: Action | None
    viewpoint: str
    heading: float
    elevation: float
    is_crushed: int
    crushed_by: tuple[int, ...]
    time: float
    distance: float
    rewards: Mapping[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class Trajectory:
    """An expert's run through one episode.

    Attributes:
        episode: The episode.
        expert: The expert's name.
        records: The start state, then one record per action (STOP included).
        stopped: Whether the expert chose STOP (False: it hit the step cap).
    """

    episode: Episode
    expert: str
    records: tuple[StepRecord, ...]
    stopped: bool

    @property
    def steps(self) -> tuple[StepRecord, ...]:
        """The records of the actions (without the start state)."""
        return self.records[1:]

    @property
    def final_viewpoint(self) -> str:
        """Where the agent ended."""
        return self.records[-1].viewpoint

    @property
    def path(self) -> list[str]:
        """Viewpoints visited, consecutive repeats merged."""
        out: list[str] = []
        for r in self.records:
            if not out or out[-1] != r.viewpoint:
                out.append(r.viewpoint)
        return out

    @property
    def collisions(self) -> int:
        """Number of actions with ``isCrushed`` (HA3D's per-step count)."""
        return sum(r.is_crushed for r in self.records)

    @property
    def total_reward(self) -> float:
        """Sum of the step rewards."""
        return sum(r.rewards.get("total", 0.0) for r in self.records)

    def _moves(self) -> list[StepRecord]:
        return [r for r in self.records if r.action is not STOP]

    def r2r(self) -> list[list]:
        """R2R's submission trajectory ``[[viewpoint, heading, elevation], ...]``.

        STOP is left out: it does not change the state.
        """
        return [[r.viewpoint, r.heading, r.elevation] for r in self._moves()]

    def ha3d(self) -> list[list]:
        """HA3D's trajectory ``[[viewpoint, heading, elevation, isCrushed], ...]``."""
        return [[r.viewpoint, r.heading, r.elevation, r.is_crushed] for r in self._moves()]

    def submission(self, k: int = 0) -> dict:
        """The R2R results entry ``{"instr_id": "<path_id>_<k>", "trajectory": [...]}``."""
        return {"instr_id": f"{self.episode.path_id}_{k}", "trajectory": self.r2r()}


def _sim_graph(sim: object, scan: str) -> NavGraph:
    # Sharing the simulator's graph shares the all-pairs distances it has computed.
    graph = getattr(sim, "graph", None)
    if not callable(graph):
        raise InvalidArgumentError(
            "cannot get the navigation graph from this simulator; pass graph=NavGraph(...)"
        )
    return graph(scan)


def _record(result: StepResult) -> StepRecord:
    state = result.state
    rewards = {**result.reward_terms, "total": result.reward} if result.action is not None else {}
    return StepRecord(
        result.action,
        state.location.viewpointId,
        float(state.heading),
        float(state.elevation),
        int(result.collided),
        result.crushed_by,
        float(state.time),
        result.distance,
        rewards,
    )


def run_expert(
    sim: object,
    episode: Episode,
    expert: Expert,
    *,
    graph: NavGraph | None = None,
    reward: str | RewardFn = "paper",
    max_steps: int | None = None,
    instruction: int = 0,
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
            read it find it in :attr:`ExpertContext.instruction_text`).

    Returns:
        The trajectory, with per-step rewards.
    """
    cap = _positive("max_steps", expert.max_steps if max_steps is None else max_steps)
    episode.instruction(instruction)  # raises for an index the episode does not have
    task = TaskStep(sim, reward=reward, max_steps=cap)
    result = task.start([episode])[0]
    graph = graph or _sim_graph(sim, episode.scan)
    ctx = ExpertContext(sim, episode, graph, instruction=instruction)
    records = [_record(result)]
    expert.reset(ctx)
    while not result.done:
        result = task.step([expert.act(ctx, result.state)])[0]
        records.append(_record(result))
        ctx.step += 1
    return Trajectory(episode, expert.name, tuple(records), result.stopped)
