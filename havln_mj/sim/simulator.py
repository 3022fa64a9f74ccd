"""The discrete HA-VLN simulator, a drop-in for ``MatterSim.Simulator`` and HA3D's simulator.

Agent code written for MatterSim runs with ``import havln_mj as MatterSim``: the same
setters, batched list arguments, ``initialize``/``newEpisode``/``makeAction``/``getState``,
navigable-location rules, discretised views and exception types (those of the
Matterport3DSimulator's ``MatterSim.Simulator``). On top of MatterSim:

* **People** (HA3D): with ``Simulator(humans=True)`` every scan is populated (see
  :mod:`havln_mj.sim.people`); people move with simulated time and are drawn in RGB, depth and
  an optional human mask. ``state.isCrushed`` is 1 when the agent came within the collision
  distance of a person at any time during the last action (for the start state: at the
  start), in every mode (HA3D computed it only with rendering off); ``getHumanState()``
  gives everyone's state. ``collision_rule="ha3d"`` and ``human_clock="ha3d"`` measure it
  as HA3D's code did instead (only in each state, 3-D from the camera, people on one shared
  frame counter; see :mod:`havln_mj.sim.rules`).
* **Clock**: every action advances the element's simulated time (``state.time``) by its
  duration: the move at ``speed`` m/s, then the turn at ``turn_rate`` rad/s (the larger of
  the heading and elevation change); an action that neither moves nor turns is a wait of
  :data:`~havln_mj.sim.batch.WAIT_S`. People are a function of that time. In a graph proxy
  the point body walks an edge stored with a route (a line of sight across a stairwell) along
  that route, through its viewpoints: the move lasts the route's length at ``speed``, and the
  collision signal is sampled along it (with rendering off a real scan id has no proxy, and every
  edge is straight, as in MatterSim).
* **Egocentric actions** (HA-VLN): ``makeEgoAction`` (see :mod:`havln_mj.sim.egocentric`).
* **Images**: BGR ``uint8`` and ``uint16`` depth in 0.25 mm units, as MatterSim; RGB and
  ``float32`` metres on request (``set_color_order``, ``set_depth_units``). Every image comes
  from the frame pipeline (:mod:`havln_mj.sim.frame`);
  :meth:`~havln_mj.sim.extensions.SimulatorExtensions.set_film` also draws frames during
  actions (videos).

Differences from MatterSim, on purpose: setters called after ``initialize`` are ignored as
MatterSim does, but with a warning; a list argument of the wrong length raises even when too
long; the batch is checked whole before anything changes, so a bad element leaves every state
as it was; ``newRandomEpisode`` draws the viewpoint uniformly over included viewpoints and the
heading from the simulator's seeded generator (MatterSim re-seeds its heading generator on every
call). A viewpoint id of ``""`` in ``newEpisode`` starts at a random viewpoint, as in MatterSim.
"""

from __future__ import annotations

import math
import numbers
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from havln_mj.errors import (
    InvalidArgumentError,
    NotInitializedError,
)
from havln_mj.frames import TWO_PI
from havln_mj.robot.point_body import DEFAULT_SPEED, DEFAULT_TURN_RATE
from havln_mj.scene.navgraph import NavGraph
from havln_mj.sim.actions import (
    check_graph_steps,
    check_robot_action,
    per_element,
)
from havln_mj.sim.batch import WAIT_S, Batch, Element, FilmCallback
from havln_mj.sim.bodies import BODY_KINDS, make_kind
from havln_mj.sim.body import ROBOT_ACTIONS, BodyKind
from havln_mj.sim.crowd import COLLISION_DISTANCE, Crowd
from havln_mj.sim.crowds import CrowdBook, CrowdFactory
from havln_mj.sim.egocentric import DEFAULT_TURN, EgoAction, ego_to_mattersim, parse_ego_action
from havln_mj.sim.extensions import SimulatorExtensions
from havln_mj.sim.images import ImageFormat
from havln_mj.sim.navigation import NavTable
from havln_mj.sim.reports import SimulatorReports
from havln_mj.sim.rules import (
    CollisionRule,
    HumanClock,
)
from havln_mj.sim.scenes import SceneLibrary
from havln_mj.sim.settings import SimulatorSettings, _check_angle
from havln_mj.sim.state import SimState

_now = time.perf_counter  # the process timer, read twice per call (hot)

__all__ = ["BODIES", "ROBOT_ACTIONS", "WAIT_S", "Simulator"]

BODIES = BODY_KINDS


class Simulator(SimulatorSettings, SimulatorExtensions, SimulatorReports):
    """A batch of agents navigating scans, MatterSim-style.

    Example:
        >>> import havln_mj as MatterSim  # doctest: +SKIP
        >>> sim = MatterSim.Simulator()
        >>> sim.setNavGraphPath("connectivity")
        >>> sim.setRenderingEnabled(False)
        >>> sim.initialize()
        >>> sim.newEpisode(["17DRP5sb8fy"], ["5b9b2794954e4694a45fc424a8643081"], [0.0], [0.0])
        >>> state = sim.getState()[0]
        >>> sim.makeAction([1], [0.0], [0.0])
    """

    def __init__(
        self,
        *,
        humans: bool | CrowdFactory = False,
        human_placements: Path | str | None = None,
        human_motions: Path | str | None = None,
        smpl_model: Path | str | None = None,
        speed: float = DEFAULT_SPEED,
        turn_rate: float = DEFAULT_TURN_RATE,
        collision_distance: float = COLLISION_DISTANCE,
        body: str = "point",
        legged: object | None = None,
        together: float = 0.0,
        reactions: bool | object = False,
        collision_rule: str | CollisionRule = "strict",
        human_clock: str | HumanClock = "continuous",
        pinned_people: bool = False,
    ) -> None:
        """Creates an uninitialised simulator with MatterSim's default settings.

        Args:
            humans: Whether scans have people (HA3D's placement rule), or a function making
                a scan's crowd from ``(scan id, graph, generator)``.
            human_placements: HA3D placement file for the real scans (default
                ``$HAVLN_HA3D_PLACEMENTS``); used when ``humans`` is True, as are:
            human_motions: HAPS motion folder (default ``$HAVLN_HAPS_DIR``).
            smpl_model: SMPL model file for skinned people (default ``$HAVLN_SMPL_MODEL``).
            speed: Point-body speed for the clock (m/s).
            turn_rate: Point-body turning rate for the clock (rad/s).
            collision_distance: HA-VLN's collision threshold (metres, horizontal).
            body: ``"point"`` (kinematic camera rig) or ``"go1"`` (the simulated quadruped).
            legged: How the GO1 is set up and driven
                (:class:`~havln_mj.sim.legged.LeggedOptions`; default its defaults).
            together: With ``humans=True``: the chance that a placed person is joined by
                others (conversations, a handover, walking side by side); 0 keeps HA3D's
                one person per spot.
            reactions: Whether people notice the agent (walkers yield, others glance), or
                a :class:`~havln_mj.humans.reactions.Reactions` saying how; each batch
                element's people react to that element alone.
            collision_rule: ``"strict"`` (along every action, horizontally; the default),
                ``"ha3d"`` (in each state, 3-D from the camera) or a
                :class:`~havln_mj.sim.rules.CollisionRule`; a name uses
                ``collision_distance`` as the threshold.
            human_clock: ``"continuous"`` (each element's simulated time), ``"ha3d"``
                (HA3D's shared frame counter) or a :class:`~havln_mj.sim.rules.HumanClock`.
            pinned_people: People play their motions on the floor points they were placed
                at, never leaving them (:class:`~havln_mj.sim.people.PinnedCrowd`; HA3D's
                people barely leave their viewpoints). Not with ``reactions``.
        """
        super().__init__()
        for name, value in (
            ("speed", speed),
            ("turn_rate", turn_rate),
            ("collision_distance", collision_distance),
        ):
            if not (isinstance(value, numbers.Real) and math.isfinite(value) and value > 0):
                raise InvalidArgumentError(f"{name} must be a positive number, got {value!r}")
        if body not in BODIES:
            raise InvalidArgumentError(f"body {body!r} unknown; valid: {', '.join(BODIES)}")
        files = (human_placements, human_motions, smpl_model)
        self._people = CrowdBook(humans, files, together, reactions, pinned_people)
        self._body_name = body
        self._legged_options = legged
        self._speed = float(speed)
        self._turn_rate = float(turn_rate)
        self._collision_distance = float(collision_distance)
        self._library: SceneLibrary | None = None
        self._kind: BodyKind | None = None
        self._batch: Batch | None = None
        self._rule = CollisionRule.strict(self._collision_distance)
        self._clock, self._frame = HumanClock.continuous(), 0
        self.set_rules(collision_rule, human_clock)
        self._rng = np.random.default_rng(self._cfg.seed)
        self._film: tuple[float, FilmCallback, tuple[str, ...]] | None = None
        self._timers = {"process": 0.0, "render": 0.0, "frames": 0}

    # ------------------------------------------------------------------ lifecycle

    def initialize(self) -> None:
        """Fixes the settings and prepares the scenes and bodies (and preloads if asked)."""
        cfg = self._cfg
        self._library = SceneLibrary(cfg.nav_graph_path, cfg.dataset_path)
        self._kind = make_kind(
            self._body_name,
            self._library.scan,
            cfg,
            self._speed,
            self._turn_rate,
            self._legged_options,
        )
        image_format = ImageFormat(cfg.color_order, cfg.depth_units)
        self._batch = Batch(cfg, self._kind, image_format, self._rule, self._timers)
        self._batch.clock, self._batch.frame = self._clock, self._frame
        self._batch.film = self._film
        self._batch.reactions = self._people.reactions
        self._rng = np.random.default_rng(cfg.seed)
        self._people.start(self._library.scan, cfg.seed, cfg.dataset_path)
        self._initialized = True
        if cfg.preloading:
            # Every graph of the folder; with rendering, worlds too, up to the cache size.
            for k, scan_id in enumerate(self._library.connectivity_ids()):
                table = self._library.table(scan_id)
                if cfg.rendering and k < cfg.cache_size:
                    self._kind.prepare(scan_id, self._crowd(table), True)

    def close(self) -> None:
        """Releases renderers; the simulator can be initialised again."""
        if self._kind is not None:
            self._kind.close()
        self._kind = None
        self._library = None
        self._batch = None
        self._initialized = False

    def __enter__(self) -> Simulator:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def _per_element(self, name: str, values: object) -> list:
        return per_element(name, values, self._cfg.batch_size)

    def _crowd(self, table: NavTable) -> Crowd:
        return self._people.crowd(table.scan_id, table.graph)

    def newEpisode(  # noqa: N802
        self,
        scanId: Sequence[str],  # noqa: N803
        viewpointId: Sequence[str],  # noqa: N803
        heading: Sequence[float],
        elevation: Sequence[float],
    ) -> None:
        """Starts an episode per batch element (initialising first if needed).

        Raises:
            BatchSizeError: A list's length is not the batch size (an ``IndexError``).
            UnknownScanError: A scan has no graph (an ``IndexError``).
            UnknownViewpointError: A viewpoint is unknown or excluded (a ``ValueError``).
            InvalidArgumentError: A heading or elevation is not finite.
        """
        t0 = _now()
        if not self._initialized:
            self.initialize()
        scans = self._per_element("scanId", scanId)
        vps = self._per_element("viewpointId", viewpointId)
        headings = self._per_element("heading", heading)
        elevations = self._per_element("elevation", elevation)
        starts = []
        for i, (scan, vp, h, e) in enumerate(zip(scans, vps, headings, elevations, strict=True)):
            table = self._library.table(scan)
            if vp == "":
                vp = self._random_viewpoint(table)
            table.location(vp)  # raises for an unknown or excluded viewpoint
            h = _check_angle(f"heading[{i}]", h)
            e = _check_angle(f"elevation[{i}]", e)
            starts.append((table, self._crowd(table), vp, h, e))
        self._batch.start(starts)
        self._timers["process"] += _now() - t0

    def newRandomEpisode(self, scanId: Sequence[str]) -> None:  # noqa: N802, N803
        """Starts each element at a random included viewpoint, random heading, elevation 0."""
        t0 = _now()
        if not self._initialized:
            self.initialize()
        starts = []
        for scan in self._per_element("scanId", scanId):
            table = self._library.table(scan)
            vp, heading = self._random_viewpoint(table), self._rng.uniform(0, TWO_PI)
            starts.append((table, self._crowd(table), vp, heading, 0.0))
        self._batch.start(starts)
        self._timers["process"] += _now() - t0

    def _random_viewpoint(self, table: NavTable) -> str:
        nodes = table.graph.nodes
        if not nodes:
            raise InvalidArgumentError(f"scan {table.scan_id} has no included viewpoints")
        return nodes[int(self._rng.integers(len(nodes)))]

    def graph(self, scan_id: str) -> NavGraph:
        """The navigation graph the simulator uses for ``scan_id`` (loaded on first use).

        Raises:
            UnknownScanError: No graph can be found for ``scan_id``.
        """
        if not self._initialized:
            self.initialize()
        return self._library.table(scan_id).graph

    # ------------------------------------------------------------------ actions

    def makeAction(  # noqa: N802
        self, index: Sequence[int], heading: Sequence[float], elevation: Sequence[float]
    ) -> None:
        """Moves each element to ``navigableLocations[index]``, then turns by the deltas.

        Raises:
            NotInitializedError: No episode has been started (a ``RuntimeError``).
            BatchSizeError: A list's length is not the batch size (an ``IndexError``).
            InvalidActionError: An index is out of range or a delta is not finite (a
                ``ValueError``).
        """
        t0 = _now()
        batch = self._batch
        if batch is None or not batch.elements:
            self._running()  # raises
        if not batch.apply_one(index, heading, elevation):  # a batch of one, plain values (hot)
            batch.apply(check_graph_steps(batch.elements, index, heading, elevation))
        self._timers["process"] += _now() - t0

    def makeEgoAction(self, action: Sequence[EgoAction | int | str]) -> None:  # noqa: N802
        """Takes one egocentric action per element (see :mod:`havln_mj.sim.egocentric`).

        Elements given ``STOP`` are left as they are (no step, no time).
        """
        t0 = _now()
        elements = self._running()
        half = self._cfg.half_hfov()
        acts = [parse_ego_action(act) for act in self._per_element("action", action)]
        actions = []
        for i, (el, act) in enumerate(zip(elements, acts, strict=True)):
            args = ego_to_mattersim(act, el.state, half, DEFAULT_TURN)
            if args is not None:
                actions.append((i, *args))
        self._batch.apply(actions)
        self._timers["process"] += _now() - t0

    def makeRobotAction(self, action: Sequence[str]) -> None:  # noqa: N802
        """One robot action per element, of :data:`~havln_mj.sim.body.ROBOT_ACTIONS`.

        With the GO1, ``"forward"`` walks :attr:`~havln_mj.sim.legged.LeggedOptions.forward_m`,
        ``"turn_left"``/``"turn_right"`` turn by ``turn_rad``, ``"stop"`` leaves the element
        alone. The state's location becomes the included viewpoint nearest the robot on its
        floor.

        Raises:
            InvalidActionError: An unknown action, or a body without robot actions.
        """
        t0 = _now()
        self._running()
        acts = [
            check_robot_action(act, self._kind.robot_actions)
            for act in self._per_element("action", action)
        ]
        self._batch.robot(acts)
        self._timers["process"] += _now() - t0

    def _running(self) -> list[Element]:
        if not self._initialized:
            raise NotInitializedError("makeAction called before initialize()")
        if not self._batch.elements:
            raise NotInitializedError("makeAction called before newEpisode()")
        return self._batch.elements

    def getGeodesicDistance(self, viewpointId: Sequence[str]) -> list[float]:  # noqa: N802, N803
        """Each element's walking distance to a viewpoint (metres, ``inf`` if unreachable).

        Measured from where the body truly is: the point body's viewpoint on the graph; the
        GO1's trunk on its level's navigability grid (see
        :meth:`~havln_mj.sim.legged_body.LeggedBody.goal_distance`).

        Raises:
            UnknownViewpointError: A viewpoint is unknown or excluded.
        """
        elements = self._running()
        out = []
        for el, vp in zip(elements, self._per_element("viewpointId", viewpointId), strict=True):
            el.table.location(vp)  # raises for an unknown or excluded viewpoint
            out.append(float(el.body.goal_distance(vp)))
        return out

    # ------------------------------------------------------------------ state

    def getState(self) -> list[SimState]:  # noqa: N802
        """The current state of every batch element.

        Raises:
            NotInitializedError: No episode has been started.
        """
        batch = self._batch
        if batch is None or not batch.elements:
            self._started("getState")  # raises
        elements = batch.elements
        if len(elements) == 1:  # a batch of one (hot): no comprehension
            return [elements[0].state]
        return [el.state for el in elements]

    # Pythonic aliases; the MatterSim names above are the reference.
    new_episode = newEpisode
    new_random_episode = newRandomEpisode
    make_action = makeAction
    make_ego_action = makeEgoAction
    make_robot_action = makeRobotAction
    get_geodesic_distance = getGeodesicDistance
    get_state = getState
