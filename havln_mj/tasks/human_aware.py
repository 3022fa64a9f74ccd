"""HA3D's sub-optimal expert: the shortest path around the nodes near people.

Distances to people are horizontal (the strict collision rule's) or HA3D's 3-D camera
distances; when no path avoids them the expert waits, walks on regardless or stops, as its
rules say (see :mod:`havln_mj.tasks.protocol`).
"""

from __future__ import annotations

import math

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.sim.egocentric import EgoAction
from havln_mj.sim.state import SimState
from havln_mj.tasks.ego_routes import EgoRoutes, ego_plan
from havln_mj.tasks.expert_context import (
    DEFAULT_HALF_HFOV,
    WAIT,
    ExpertContext,
    level_camera,
    positive_int,
    sim_half_hfov,
)
from havln_mj.tasks.planning import CLEARANCE, SIGHT_RADIUS, PathPlanner, graph_teacher
from havln_mj.tasks.protocol import DEFAULT_MAX_WAITS, ExpertRules, TaskProtocol, get_protocol
from havln_mj.tasks.step import STOP, Action


class HumanAwareExpert:
    """HA3D's sub-optimal expert: avoids the nodes near people; waits or stops when boxed in.

    With graph actions, when no path avoids people it waits (index 0, no turn) and re-plans,
    at most ``max_waits`` times per episode; after that it walks the shortest path
    regardless of people (counting those steps in ``walked_through``), so one blocked
    episode cannot wait to the step cap, or with ``after_waits="stop"`` it stops. HA3D's
    expert stops at once (``max_waits=0``): its "no path" answer is the end action.

    With egocentric actions (``action_space="ego"``, the teacher of the egocentric agents)
    it follows :func:`~havln_mj.tasks.ego_routes.ego_plan` with FORWARD kept out of the avoided
    nodes. The egocentric set has no wait, and HA3D's "no path" answer would teach an agent to
    stop beside people; so when no route avoids them it takes the shortest egocentric route
    regardless (counted in ``walked_through``), or with ``after_waits="stop"`` it stops.

    Args:
        mode: ``"local"`` re-plans each step around the people within ``sight_radius`` of
            the agent; ``"global"`` plans once around everyone (re-planning only while no
            path exists).
        action_space: ``"graph"`` (``makeAction`` tuples) or ``"ego"`` (``EgoAction``).
        sight_radius: How near the agent a person must be to matter (local mode).
        clearance: Nodes this close to such a person are removed (start and goal kept).
        weighted: Shortest by length (True) or by number of edges (HA3D).
        distance: ``"horizontal"`` (pelvis positions on the viewpoint's storey, as the strict
            collision rule) or ``"camera_3d"`` (HA3D: 3-D between viewpoint cameras and the
            simulator's :meth:`~havln_mj.sim.extensions.SimulatorExtensions.collision_points`).
        max_waits: Waits per episode before ``after_waits`` (None: no bound).
        after_waits: ``"walk"`` (on, ignoring people) or ``"stop"``.
        max_steps: Default cap on actions.

    Attributes:
        last_plan: The path planned at the last step (None when blocked; graph actions).
        waits: How many times the expert waited in the current episode.
        walked_through: Steps taken ignoring people in the current episode.
    """

    def __init__(
        self,
        mode: str = "local",
        *,
        action_space: str = "graph",
        sight_radius: float = SIGHT_RADIUS,
        clearance: float = CLEARANCE,
        weighted: bool = True,
        distance: str = "horizontal",
        max_waits: int | None = DEFAULT_MAX_WAITS,
        after_waits: str = "walk",
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
        rules = ExpertRules(distance, bool(weighted), max_waits, after_waits)  # checks them
        self.mode = mode
        self.action_space = action_space
        self.distance, self.weighted = rules.distance, rules.weighted
        self.max_waits, self.after_waits = rules.max_waits, rules.after_waits
        self.walked_through = 0
        self.name = f"human_aware_{mode}" + ("_ego" if action_space == "ego" else "")
        self.sight_radius = float(sight_radius)
        self.clearance = float(clearance)
        self.max_steps = positive_int("max_steps", max_steps)
        self.last_plan: list[str] | None = None
        self.waits = 0
        self._route: list[str] | None = None
        self._avoid: frozenset[str] = frozenset()  # global mode, egocentric actions
        self._hfov = DEFAULT_HALF_HFOV
        self._routes: dict[str, EgoRoutes] = {}
        self._planners: dict[str, PathPlanner] = {}
        self._last_key: tuple | None = None  # the local plan's inputs, and the plan
        self._last_path: list[str] | None = None

    @classmethod
    def for_protocol(
        cls,
        protocol: str | TaskProtocol,
        mode: str = "local",
        *,
        action_space: str = "graph",
        max_steps: int = 150,
    ) -> HumanAwareExpert:
        """The expert as ``protocol`` defines it (planning distance, hops, when blocked)."""
        rules = get_protocol(protocol).expert
        return cls(
            mode,
            action_space=action_space,
            weighted=rules.weighted,
            distance=rules.distance,
            max_waits=rules.max_waits,
            after_waits=rules.after_waits,
            max_steps=max_steps,
        )

    def _people(self, ctx: ExpertContext) -> np.ndarray:
        if self.distance == "camera_3d":
            points = getattr(ctx.sim, "collision_points", None)
            if points is None:
                raise InvalidArgumentError(
                    "distance='camera_3d' needs the simulator's collision_points()"
                )
            return np.asarray(points()[0], float).reshape(-1, 3)
        return np.asarray(ctx.sim.getHumanPositions()[0], float).reshape(-1, 3)

    def _planner(self, ctx: ExpertContext) -> PathPlanner:
        planner = self._planners.get(ctx.episode.scan)
        if planner is None or planner.graph is not ctx.graph:
            planner = self._planners[ctx.episode.scan] = PathPlanner(ctx.graph)
        return planner

    def _local_plan(self, ctx: ExpertContext, here: str, blocked: frozenset) -> list[str] | None:
        """The plan around ``blocked``; the last one again while nothing changed (turns)."""
        key = (ctx.episode.scan, here, ctx.goal, blocked)
        if self._last_key != key:
            path = self._planner(ctx).plan(here, ctx.goal, blocked, weighted=self.weighted)
            self._last_key, self._last_path = key, path
        return self._last_path

    def _blocked_near(self, ctx: ExpertContext, here: str) -> set[str]:
        """Local mode: the nodes near the people within sight of ``here``."""
        planner = self._planner(ctx)
        near = planner.people_near(here, self._people(ctx), self.sight_radius, self.distance)
        return planner.blocked(near, self.clearance, (here, ctx.goal), self.distance)

    def _global_route(self, ctx: ExpertContext, here: str) -> list[str] | None:
        planner = self._planner(ctx)
        people = self._people(ctx)
        blocked = planner.blocked(people, self.clearance, (here, ctx.goal), self.distance)
        return planner.plan(here, ctx.goal, blocked, weighted=self.weighted)

    def reset(self, ctx: ExpertContext) -> None:
        """Plans G' once (global mode)."""
        self.last_plan, self.waits, self.walked_through = None, 0, 0
        self._hfov = sim_half_hfov(ctx.sim)
        if self.action_space == "ego":
            keep = (ctx.episode.start, ctx.goal)
            people = self._people(ctx) if self.mode == "global" else ()
            planner = self._planner(ctx)
            self._avoid = frozenset(planner.blocked(people, self.clearance, keep, self.distance))
            return
        self._route = self._global_route(ctx, ctx.episode.start) if self.mode == "global" else None

    def _ego(self, ctx: ExpertContext, state: SimState) -> EgoAction:
        level = level_camera(state)
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
                if self.after_waits == "stop":
                    return STOP
                self.walked_through += 1
                plan = ego_plan(graph, here, state.heading, goal, self._hfov)
            return STOP if plan is None else plan[0]
        action = routes.first_action(here, step, goal, avoid)
        if action is None:
            if self.after_waits == "stop":
                return STOP
            self.walked_through += 1
            action = routes.first_action(here, step, goal, frozenset())
        return STOP if action is None else action

    def act(self, ctx: ExpertContext, state: SimState) -> Action:
        """The next action: teacher towards the planned next node, or the blocked rule's."""
        if self.action_space == "ego":
            return self._ego(ctx, state)
        here, goal, graph = state.location.viewpointId, ctx.goal, ctx.graph
        if here == goal:
            return STOP
        if self.mode == "local":
            path = self._local_plan(ctx, here, frozenset(self._blocked_near(ctx, here)))
        else:
            if self._route is None or here not in self._route:
                self._route = self._global_route(ctx, here)
            path = None if self._route is None else self._route[self._route.index(here) :]
        self.last_plan = path
        if path is None:
            if self.max_waits is None or self.waits < self.max_waits:
                self.waits += 1
                return WAIT
            if self.after_waits == "stop":
                return STOP
            path = self._planner(ctx).plan(here, goal, weighted=self.weighted)
            if path is None:
                return STOP  # the goal cannot be reached from here at all
            self.walked_through += 1
        return graph_teacher(state, path[1], graph)
