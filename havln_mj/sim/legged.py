"""The GO1 in the loop: graph and continuous actions executed by a physically simulated robot.

A scan's :class:`LeggedWorld` is its building with collision geometry, its people and one
GO1, compiled once; each batch element is a :class:`LeggedAgent` with its own ``MjData``.

* **Graph actions** (``makeAction`` to a navigable viewpoint) become turn-then-walk primitive
  sequences closed on the robot's state estimate: face the target, walk the distance, and
  correct once more when the robot ends more than :attr:`LeggedOptions.retry_m` away; then
  turn to the heading MatterSim would have (the old heading plus the requested change). An
  edge the scan walks by a route (a graph proxy's line of sight across a stairwell, say:
  :attr:`~havln_mj.scene.scan.Scan.routes`) is walked through the route's stops: viewpoints,
  or the floor points of a flight drawn for it.
* **Continuous actions** (the real-robot setting): forward ``forward_m``, turn
  ``±turn_rad``, stop.
* **Time**: every action advances the element's clock by the physics time it took.
* **People**: poses follow the element's clock. Their geoms make no contact unless
  ``physical_humans`` makes them solid; then the robot's contacts with them are counted. The
  HA-VLN collision signal (1 m, horizontal, trunk to pelvis) is sampled along the whole action
  at every controller tick (≥ 16 Hz).
* **Falls** end the episode: a fallen element ignores further actions and reports ``fell``.
* **Divergence**: after every controller tick MuJoCo's warning counters are read (bad
  positions, velocities or accelerations, full contact or constraint buffers). When physics
  diverges MuJoCo resets the state, so the robot would appear elsewhere: the action stops
  there, and the element reports ``diverged`` and ends as a fall does.

:class:`~havln_mj.sim.legged_body.LeggedBody` puts this behind the simulator's Body seam.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass

import mujoco
import numpy as np

from havln_mj import groups
from havln_mj.errors import InvalidArgumentError
from havln_mj.frames import heading_to, wrap_angle
from havln_mj.humans.mujoco_people import PeopleWriter, add_people
from havln_mj.nav import NavGrid, build_navgrids
from havln_mj.robot.go1.constants import CONTROLLERS, STAND_HEIGHT
from havln_mj.robot.go1.model import add_go1
from havln_mj.robot.go1.primitives import Go1Body, OnTick, PrimitiveResult
from havln_mj.scene.navgraph import LEVEL_GAP
from havln_mj.scene.proxy.routes import route_floor_points
from havln_mj.scene.scan import Scan, floor_heights
from havln_mj.sim.crowd import NO_CROWD, Crowd, Proximity
from havln_mj.sim.divergence import DivergedError, warning_counts
from havln_mj.sim.proximity import knots_proximity
from havln_mj.sim.world import WorldOptions, build_world, world_spec

PREFIX = "go1/"
_AT_VIEWPOINT = 0.5  # metres: a robot this close to a viewpoint stands at it (for routes)
DESCENT = 0.1  # metres: a target floor this far below the robot's is down a stair


@dataclass(frozen=True)
class LeggedOptions:
    """How the GO1 is set up and driven.

    Attributes:
        estimate: ``"truth"`` (primitives closed on the simulator's pose) or ``"odometry"``
            (IMU and leg kinematics, which drift as on the real robot).
        camera_height: None for the GO1's head camera; a height (m) raises it on a mast.
        physical_humans: Whether people's bodies push the robot (contacts are reported).
        forward_m: Size of the continuous FORWARD action.
        turn_rad: Size of the continuous TURN actions.
        retry_m: A graph move ending farther than this from its viewpoint walks again.
        menagerie_xml: A user's Menagerie ``go1.xml`` to use instead of the built-in model.
        controller: The gait: ``"trot"`` (blind, flat floors), ``"terrain"`` (reads a
            height scan), ``"learned"`` (a trained policy's corrections to the terrain
            gait), ``"crawl"`` (the slow stair crawl, which goes down stairs backwards) or
            ``"hybrid"`` (the trot, and the crawl for a walk or turn over steps); see
            :class:`~havln_mj.robot.go1.primitives.Go1Body`.
    """

    estimate: str = "truth"
    camera_height: float | None = None
    physical_humans: bool = False
    forward_m: float = 0.5
    turn_rad: float = math.pi / 4
    retry_m: float = 0.15
    menagerie_xml: str | None = None
    controller: str = "trot"

    def __post_init__(self) -> None:
        if self.controller not in CONTROLLERS:
            raise InvalidArgumentError(
                f"controller {self.controller!r} unknown; valid: {', '.join(CONTROLLERS)}"
            )


@dataclass
class WalkResult:
    """What one run of primitives did to a legged agent.

    Attributes:
        duration: Physics seconds.
        fell: The robot fell.
        diverged: The physics diverged (see the module docstring).
        human_contacts: Most robot–person contacts at once (solid people only).
        primitives: The primitives run.
        track: Trunk positions ``(n, 4)`` of ``(t, x, y, z)`` at every controller tick.
        crowd: The people, for :attr:`contact`.
    """

    duration: float = 0.0
    fell: bool = False
    diverged: bool = False
    human_contacts: int = 0
    primitives: list[PrimitiveResult] | None = None
    track: np.ndarray | None = None
    crowd: Crowd = NO_CROWD

    @functools.cached_property
    def contact(self) -> Proximity | None:
        """The HA-VLN collision signal over the walk (None without people)."""
        if not len(self.crowd) or self.track is None:
            return None
        return knots_proximity(self.crowd, self.track)


class LeggedWorld:
    """A scan's building, people and one GO1, compiled for physics."""

    def __init__(
        self, scan: Scan, world_options: WorldOptions, crowd: Crowd, options: LeggedOptions
    ) -> None:
        self.scan, self.crowd, self.options = scan, crowd, options
        collision = world_options.collision
        if collision == "none":
            collision = "auto"  # a legged robot needs floors to stand on
        spec, self.collision, _ = world_spec(scan, _with_collision(world_options, collision))
        add_people(
            spec,
            crowd.shapes,
            crowd.skins,
            solid=options.physical_humans,
            style=world_options.people_style,
        )
        start = scan.graph.nodes[0]
        x, y, _ = scan.graph.position(start)
        self.handles = add_go1(
            spec,
            (x, y, scan.graph.floor_z(start)),
            prefix=PREFIX,
            camera_height=options.camera_height,
            menagerie_xml=options.menagerie_xml,
        )
        _add_chase_camera(spec, self.handles.trunk)
        self.model = spec.compile()
        self.human_geoms = np.flatnonzero(self.model.geom_group == groups.HUMANS)
        robot_bodies = [
            b for b in range(self.model.nbody) if self.model.body(b).name.startswith(PREFIX)
        ]
        self.robot_geoms = np.flatnonzero(np.isin(self.model.geom_bodyid, robot_bodies))
        self.camera = self.handles.camera
        self._grids: list[tuple[float, NavGrid]] | None = None
        g = scan.graph
        floors = [[*g.position(v)[:2], g.floor_z(v)] for v in g.nodes]
        self._floors = np.array(floors, dtype=float).reshape(-1, 3)

    def waypoints(self, start: np.ndarray, target: np.ndarray) -> list[np.ndarray]:
        """Floor points a move from trunk position ``start`` to floor point ``target`` passes.

        Empty unless the robot stands within ``_AT_VIEWPOINT`` of a viewpoint (horizontally,
        on its floor) and ``target`` is the floor point of a viewpoint whose edge with it the
        scan walks by a route; then the floor points of the route's inner stops, in order.
        """
        if not self.scan.routes:
            return []
        fl = self._floors
        gap = np.hypot(*(fl[:, :2] - start[:2]).T)
        above = start[2] - fl[:, 2]
        here = np.flatnonzero((gap <= _AT_VIEWPOINT) & (above > 0.0) & (above < LEVEL_GAP))
        there = np.flatnonzero(np.all(np.abs(fl - target) < 1e-6, axis=1))
        if not len(here) or not len(there):
            return []
        nodes = self.scan.graph.nodes
        route = self.scan.route(nodes[here[np.argmin(gap[here])]], nodes[there[0]])
        if route is None:
            return []
        return list(route_floor_points(self.scan.graph, route)[1:-1])

    def geodesic(self, start: np.ndarray, goal: np.ndarray) -> float:
        """Walking distance between two floor points on one level (``inf`` if none).

        From the level's navigability grid (collision geometry at robot height, 5 cm cells),
        built on first use from the building alone; points on different levels give ``inf``.
        """
        if self._grids is None:
            floors = floor_heights(self.scan)
            world = build_world(self.scan, _with_collision(WorldOptions(), self.collision))
            self._grids = list(zip(floors, build_navgrids(world, floors), strict=True))
        if not self._grids or abs(start[2] - goal[2]) > LEVEL_GAP:
            return math.inf
        floor, grid = min(self._grids, key=lambda fg: abs(fg[0] - goal[2]))
        if abs(floor - goal[2]) > LEVEL_GAP:
            return math.inf
        return grid.distance(start[:2], goal[:2])


CHASE_CAMERA = PREFIX + "chase"


def _add_chase_camera(spec: mujoco.MjSpec, trunk: str) -> None:
    """A camera riding 1 m behind and 1.5 m above the trunk, looking ahead and down at 45°.

    Close enough that the walls of a corridor rarely come between it and the robot.
    """
    # Camera axes in the trunk frame (x forward, y left, z up): it looks along −z.
    axes = np.column_stack([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])
    tilt = math.radians(45.0)
    down = np.array(
        [[1, 0, 0], [0, math.cos(tilt), -math.sin(tilt)], [0, math.sin(tilt), math.cos(tilt)]]
    )
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, (axes @ down.T).ravel())
    spec.body(trunk).add_camera(name=CHASE_CAMERA, pos=(-1.0, 0.0, 1.5), quat=quat, fovy=60.0)


def _with_collision(options: WorldOptions, collision: str) -> WorldOptions:
    return dataclasses.replace(options, collision=collision)


class LeggedAgent:
    """One batch element's GO1: its own physics state in a :class:`LeggedWorld`."""

    def __init__(self, world: LeggedWorld) -> None:
        self.world = world
        self.data = mujoco.MjData(world.model)
        options = world.options
        self.body = Go1Body(
            world.model, self.data, PREFIX, options.estimate, controller=options.controller
        )
        self.people = PeopleWriter(world.model, len(world.crowd.shapes))
        self.fell = False
        self.diverged = False
        self._last_good: tuple[np.ndarray, float] | None = None  # frozen once diverged

    # --------------------------------------------------------------------- state

    def position(self) -> np.ndarray:
        """True trunk position ``(x, y, z)`` (after diverged physics: the last one trusted)."""
        if self._last_good is not None:
            return self._last_good[0].copy()
        p = self.body.true_pose()
        return np.array([p.x, p.y, p.z])

    def heading(self) -> float:
        """True heading (radians, from +y turning right; after divergence the last trusted)."""
        if self._last_good is not None:
            return self._last_good[1]
        return self.body.true_pose().heading

    def place(self, position: np.ndarray, floor_z: float, heading: float, t: float) -> None:
        """Stands the robot at a viewpoint's floor point, facing ``heading``, at time ``t``.

        Physics that diverges while the robot settles there ends the episode as in an action
        (``diverged``; the pose reported is the floor point's).
        """
        self.pose_people(t)
        warnings0 = warning_counts(self.data)
        x, y = float(position[0]), float(position[1])
        self.body.reset(x, y, float(floor_z), heading)
        self.diverged = warning_counts(self.data) != warnings0
        self.fell = self.body.fallen or self.diverged
        stand = np.array([x, y, float(floor_z) + STAND_HEIGHT])
        self._last_good = (stand, heading) if self.diverged else None

    def pose_people(self, t: float) -> None:
        """Writes the people's poses at simulated time ``t`` into this agent's data."""
        if self.people.n_people:
            self.people.write(self.data, *self.world.crowd.pose(t))

    # ------------------------------------------------------------------- actions

    def run(
        self, plan: list[tuple[str, float]], t0: float, on_tick: OnTick | None = None
    ) -> WalkResult:
        """Runs primitives ``("forward", m)``, ``("turn", rad)``, ``("stand", s)`` from ``t0``.

        ``on_tick(t)`` is called at every controller tick with the simulated time.
        """
        return self._execute(lambda do: [do(kind, amount) for kind, amount in plan], t0, on_tick)

    def go_to(
        self,
        target: np.ndarray,
        final_heading: float | None,
        t0: float,
        on_tick: OnTick | None = None,
    ) -> WalkResult:
        """Walks to a floor point, then turns to ``final_heading``.

        Turn to face the point, walk the distance, and once more if still too far; None as
        ``final_heading`` keeps the walking direction. When the scan walks this edge by a route
        (see :meth:`LeggedWorld.waypoints`), each of its stops is walked to in turn first.
        """
        retry = self.world.options.retry_m
        legs = [*self.world.waypoints(self.position(), np.asarray(target, float)), target]

        def script(do) -> list[PrimitiveResult]:
            done = []
            for point in legs:
                for attempt in range(3):
                    p = self.body.pose()
                    here = np.array([p.x, p.y])
                    gap = float(np.linalg.norm(point[:2] - here))
                    if attempt and gap <= retry:
                        break
                    if gap > 0.02:
                        bearing = heading_to(np.array([p.x, p.y, 0.0]), point)
                        # The crawl goes down a stair backwards (its knees point backwards).
                        down = point[2] < p.z - STAND_HEIGHT - DESCENT
                        back = down and self.body.crawls(gap, bearing)
                        bearing += math.pi if back else 0.0
                        done.append(do("turn", wrap_angle(bearing - p.heading)))
                        done.append(do("forward", -gap if back else gap))
                    if self.body.fallen:
                        return done
            if final_heading is not None:
                turn = wrap_angle(final_heading - self.body.pose().heading)
                if abs(turn) > math.radians(1.0):
                    done.append(do("turn", turn))
            return done

        return self._execute(script, t0, on_tick)

    def _execute(self, script, t0: float, on_tick: OnTick | None = None) -> WalkResult:
        crowd = self.world.crowd
        if self.fell or self.diverged:
            track = np.array([[t0, *self.position()]])
            return WalkResult(fell=self.fell, diverged=self.diverged, track=track, crowd=crowd)
        d = self.data
        start_time = d.time
        times, points, touches = [t0], [self.position()], [0]
        physical = self.world.options.physical_humans
        warnings0 = warning_counts(d)
        trusted = [self.position(), self.heading()]

        def tick(physics_time: float) -> None:
            if warning_counts(d) != warnings0:
                raise DivergedError
            trusted[:] = [self.position(), self.heading()]
            t = t0 + physics_time - start_time
            if physical:
                self.pose_people(t)  # solid people must move with the physics
            times.append(t)
            points.append(self.position())
            if physical:
                touches.append(self._human_contacts())
            if on_tick is not None:
                on_tick(t)

        def do(kind: str, amount: float) -> PrimitiveResult:
            if self.body.fallen:
                return None
            if kind == "forward":
                return self.body.forward(amount, on_tick=tick)
            if kind == "stand":
                return self.body.stand(amount, on_tick=tick)
            return self.body.turn(amount, on_tick=tick)

        done: list[PrimitiveResult] = []
        try:
            done = script(do)
            if warning_counts(d) != warnings0:
                raise DivergedError
            tick(d.time)
        except DivergedError:
            # MuJoCo has reset the state: the pose is no longer the robot's, keep the last.
            self.diverged = True
            self._last_good = (trusted[0], trusted[1])
        self.fell = self.body.fallen or self.diverged
        track = np.column_stack([np.array(times), np.array(points)])
        return WalkResult(
            d.time - start_time,
            self.fell,
            self.diverged,
            int(max(touches)),
            [r for r in done if r is not None],
            track,
            crowd,
        )

    def _human_contacts(self) -> int:
        """Robot–person contacts in the current physics state."""
        d = self.data
        if not d.ncon:
            return 0
        g1, g2 = d.contact.geom1[: d.ncon], d.contact.geom2[: d.ncon]
        human, robot = self.world.human_geoms, self.world.robot_geoms
        return int(
            np.sum(
                (np.isin(g1, human) & np.isin(g2, robot))
                | (np.isin(g2, human) & np.isin(g1, robot))
            )
        )
