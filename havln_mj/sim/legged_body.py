"""The GO1 behind the Body seam: graph and robot actions executed by physics, told truthfully.

A graph action walks the robot to the target viewpoint's floor point (through a route's stops
where the scan walks the edge by a route) and turns it to the requested heading; the state's
viewpoint is then the one the robot really stands at (:func:`~havln_mj.sim.body.stands_at`):
the target if it got there, else the last viewpoint it stood at on the way, and
``arrived`` is False. A robot action (forward, turn) leaves the robot wherever physics puts
it; the state's viewpoint is then the one nearest the robot on its floor. Distances to a goal
are walked from the robot's true position (:meth:`LeggedBody.goal_distance`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import mujoco
import numpy as np

from havln_mj.errors import InvalidActionError
from havln_mj.frames import wrap_angle
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.scan import Scan
from havln_mj.sim.body import (
    ROBOT_ACTIONS,
    Film,
    Outcome,
    ignore,
    nearest_viewpoint,
    stands_at,
)
from havln_mj.sim.crowd import Crowd
from havln_mj.sim.frame import Frames, View, ViewSettings
from havln_mj.sim.legged import LeggedAgent, LeggedOptions, LeggedWorld, WalkResult
from havln_mj.sim.world import WorldOptions


class LeggedKind:
    """Makes GO1 bodies; keeps one physics world (and its frames) per scan.

    Args:
        scan: Loads a scan by id.
        world_options: How worlds are built (collision "none" becomes "auto": a robot needs
            floors).
        options: How the GO1 is set up and driven.
    """

    name = "go1"
    robot_actions = ROBOT_ACTIONS[1:]

    def __init__(
        self, scan: Callable[[str], Scan], world_options: WorldOptions, options: LeggedOptions
    ) -> None:
        self._scan = scan
        self._world_options = world_options
        self.options = options
        self._worlds: dict[str, tuple[LeggedWorld, Frames]] = {}

    def world(self, scan_id: str, crowd: Crowd) -> tuple[LeggedWorld, Frames]:
        """The scan's physics world and its frame pipeline (built once)."""
        entry = self._worlds.get(scan_id)
        if entry is None:
            world = LeggedWorld(self._scan(scan_id), self._world_options, crowd, self.options)
            frames = Frames(
                world.model, crowd, self._world_options.people_style, world.scan.room_plan
            )
            entry = self._worlds[scan_id] = (world, frames)
        return entry

    def prepare(self, scan_id: str, crowd: Crowd, rendering: bool) -> None:
        """Builds the scan's physics world ahead of use."""
        self.world(scan_id, crowd)

    def body(self, scan_id: str, graph: NavGraph, crowd: Crowd) -> LeggedBody:
        """A new GO1 on ``scan_id`` with its own physics state."""
        world, frames = self.world(scan_id, crowd)
        return LeggedBody(LeggedAgent(world), frames, graph)

    def close(self) -> None:
        """Releases the renderers."""
        for _, frames in self._worlds.values():
            frames.close()
        self._worlds.clear()


class LeggedBody:
    """One element's GO1."""

    def __init__(self, agent: LeggedAgent, frames: Frames, graph: NavGraph) -> None:
        self.agent, self.frames, self.graph = agent, frames, graph
        self.viewpoint = ""
        self.observe = ignore

    def _floor(self) -> float:
        """Height of the floor under the trunk, from the trunk's standing height."""
        return float(self.agent.position()[2]) - self.agent.body.gains.foot_depth

    def _outcome(self, walk: WalkResult, viewpoint: str, arrived: bool) -> Outcome:
        self.viewpoint = viewpoint
        self.observe(walk.track)
        return Outcome(
            walk.duration,
            walk.track,
            viewpoint,
            self.agent.heading(),
            arrived,
            walk.fell,
            walk.diverged,
            walk.human_contacts,
            walk.primitives,
        )

    def start(self, viewpoint: str, heading: float, elevation: float, t: float) -> Outcome:
        """Stands the robot on ``viewpoint``'s floor facing ``heading``."""
        g = self.graph
        self.agent.place(g.position(viewpoint), g.floor_z(viewpoint), heading, t)
        track = np.array([[t, *self.agent.position()]])
        walk = WalkResult(0.0, self.agent.fell, self.agent.diverged, 0, [], track)
        return self._outcome(walk, viewpoint, True)

    def move(
        self,
        target: str,
        heading: float,
        elevation: float,
        t: float,
        wait_s: float,
        film: Film | None = None,
    ) -> Outcome:
        """Walks to ``target`` (or turns / stands in place) and faces ``heading``."""
        agent, tick = self.agent, None if film is None else film.tick
        if target == self.viewpoint:
            turn = wrap_angle(heading - agent.heading())
            plan = [("stand", wait_s)] if abs(turn) < 1e-9 else [("turn", turn)]
            return self._outcome(agent.run(plan, t, on_tick=tick), target, True)
        g = self.graph
        goal = np.array([*g.position(target)[:2], g.floor_z(target)])
        walk = agent.go_to(goal, heading, t, on_tick=tick)
        if not walk.diverged and stands_at(g, target, agent.position(), self._floor()):
            return self._outcome(walk, target, True)
        return self._outcome(walk, self._last_reached(walk, target), False)

    def _last_reached(self, walk: WalkResult, target: str) -> str:
        """The last viewpoint of the route to ``target`` the robot stood at (else the start)."""
        route = self.agent.world.scan.route(self.viewpoint, target)
        stops = [s for s in route[1:-1] if isinstance(s, str)] if route is not None else []
        last = self.viewpoint
        if not stops or walk.track is None:
            return last
        foot = self.agent.body.gains.foot_depth
        for vp in stops:
            if any(stands_at(self.graph, vp, p[1:], p[3] - foot) for p in walk.track):
                last = vp
        return last

    def robot_action(self, action: str, t: float, film: Film | None = None) -> Outcome:
        """Forward ``forward_m`` or turn ``±turn_rad``; the viewpoint is the nearest one.

        Raises:
            InvalidActionError: ``action`` is not a moving robot action.
        """
        opts = self.agent.world.options
        plans = {
            "forward": [("forward", opts.forward_m)],
            "turn_left": [("turn", -opts.turn_rad)],
            "turn_right": [("turn", opts.turn_rad)],
        }
        if action not in plans:
            raise InvalidActionError(
                f"robot action {action!r} unknown; valid: {', '.join(ROBOT_ACTIONS)}"
            )
        walk = self.agent.run(plans[action], t, on_tick=None if film is None else film.tick)
        vp, _ = nearest_viewpoint(self.graph, self.agent.position(), self._floor())
        return self._outcome(walk, vp, True)

    def pose(self) -> np.ndarray:
        """The true trunk pose ``(x, y, z, heading)``."""
        return np.append(self.agent.position(), self.agent.heading())

    def goal_distance(self, goal: str) -> float:
        """Walking distance from the robot's true position to ``goal``.

        On the goal's level, the navigability grid's geodesic from the trunk; across levels
        (or off the grid), the graph's geodesic from the viewpoint the robot stands at plus
        the horizontal gap from the trunk to that viewpoint.
        """
        g = self.graph
        p = self.agent.position()
        here = self.viewpoint
        start = np.array([p[0], p[1], g.floor_z(here)])
        goal_point = np.append(g.position(goal)[:2], g.floor_z(goal))
        on_grid = self.agent.world.geodesic(start, goal_point)
        if math.isfinite(on_grid):
            return on_grid
        gap = float(np.hypot(*(g.position(here)[:2] - p[:2])))
        return g.distance(here, goal) + gap

    def scene(self, elevation: float, t: float) -> tuple[mujoco.MjModel, mujoco.MjData]:
        """The robot's physics world with the people at ``t`` (its state untouched)."""
        self.frames.pose(self.agent.data, t, self.agent.world.camera, elevation)
        return self.agent.world.model, self.agent.data

    def render(
        self, settings: ViewSettings, elevation: float, t: float, camera: str | None = None
    ) -> View:
        """The head camera's view (pitched by ``elevation``), or another camera's."""
        cam = camera or self.agent.world.camera
        pitch = elevation if camera is None else 0.0
        return self.frames.render(self.agent.data, t, cam, settings, pitch)
