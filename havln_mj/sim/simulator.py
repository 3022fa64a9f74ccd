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
  gives everyone's state.
* **Clock**: every action advances the element's simulated time (``state.time``) by its
  duration: the move at ``speed`` m/s, then the turn at ``turn_rate`` rad/s (the larger of
  the heading and elevation change); an action that neither moves nor turns is a wait of
  :data:`WAIT_S`. People are a function of that time. In a graph proxy the point body walks
  an edge stored with a route (a line of sight across a stairwell) along that route, through
  its viewpoints: the move lasts the route's length at ``speed``, and the collision signal is
  sampled along it (with rendering off a real scan id has no proxy, and every edge is
  straight, as in MatterSim).
* **Egocentric actions** (HA-VLN): ``makeEgoAction`` (see :mod:`havln_mj.sim.egocentric`).
* **Images**: BGR ``uint8`` and ``uint16`` depth in 0.25 mm units, as MatterSim; RGB and
  ``float32`` metres on request (``set_color_order``, ``set_depth_units``). Every image comes
  from the frame pipeline (:mod:`havln_mj.sim.frame`); :meth:`Simulator.set_film` also draws
  frames during actions (videos).

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
import zlib
from collections.abc import Callable, Sequence
from pathlib import Path

import mujoco
import numpy as np

from havln_mj.errors import (
    InvalidArgumentError,
    NotInitializedError,
)
from havln_mj.frames import TWO_PI
from havln_mj.robot.point_body import DEFAULT_SPEED, DEFAULT_TURN_RATE
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.scan import Scan
from havln_mj.sim.actions import (
    check_delta,
    check_index,
    check_robot_action,
    parse_mixed,
    per_element,
)
from havln_mj.sim.batch import WAIT_S, Batch, Element, FilmCallback
from havln_mj.sim.body import BODY_KINDS, ROBOT_ACTIONS, BodyKind, make_kind
from havln_mj.sim.crowd import COLLISION_DISTANCE, NO_CROWD, Crowd
from havln_mj.sim.egocentric import DEFAULT_TURN, EgoAction, ego_to_mattersim, parse_ego_action
from havln_mj.sim.images import ImageFormat
from havln_mj.sim.navigation import NavTable
from havln_mj.sim.scenes import SceneLibrary
from havln_mj.sim.settings import SimulatorSettings, _check_angle
from havln_mj.sim.state import SimState

__all__ = ["BODIES", "ROBOT_ACTIONS", "WAIT_S", "Simulator"]

BODIES = BODY_KINDS

CrowdFactory = Callable[[str, NavGraph, np.random.Generator], Crowd]


class Simulator(SimulatorSettings):
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
        """
        super().__init__()
        for name, value in (
            ("speed", speed),
            ("turn_rate", turn_rate),
            ("collision_distance", collision_distance),
        ):
            if not (isinstance(value, numbers.Real) and math.isfinite(value) and value > 0):
                raise InvalidArgumentError(f"{name} must be a positive number, got {value!r}")
        if not (isinstance(humans, bool) or callable(humans)):
            raise InvalidArgumentError(f"humans must be a bool or a crowd factory, got {humans!r}")
        if body not in BODIES:
            raise InvalidArgumentError(f"body {body!r} unknown; valid: {', '.join(BODIES)}")
        if not (isinstance(together, numbers.Real) and 0.0 <= together <= 1.0):
            raise InvalidArgumentError(f"together must be a chance in [0, 1], got {together!r}")
        self._together = float(together)
        self._reactions = _reactions(reactions)
        self._humans = humans
        self._body_name = body
        self._legged_options = legged
        self._human_files = (human_placements, human_motions, smpl_model)
        self._crowds: CrowdFactory | None = None
        self._speed = float(speed)
        self._turn_rate = float(turn_rate)
        self._collision_distance = float(collision_distance)
        self._library: SceneLibrary | None = None
        self._kind: BodyKind | None = None
        self._batch: Batch | None = None
        self._rng = np.random.default_rng(self._cfg.seed)
        self._crowd_of: dict[str, Crowd] = {}
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
        self._batch = Batch(cfg, self._kind, image_format, self._collision_distance, self._timers)
        self._batch.film = self._film
        self._batch.reactions = self._reactions
        self._rng = np.random.default_rng(cfg.seed)
        self._crowd_of = {}
        if self._humans is True:
            from havln_mj.sim.people import HumanCrowds  # the humans package, only when used

            self._crowds = HumanCrowds(
                self._library.scan, *self._human_files, together=self._together
            )
        else:
            self._crowds = self._humans or None
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

    def set_film(
        self, fps: float | None, callback: FilmCallback | None = None, cameras: Sequence[str] = ()
    ) -> None:
        """Draws frames during actions, at ``fps`` per simulated second (None stops).

        ``callback(element, t, views, pose)`` receives the element's index, the simulated
        time, the views of its body camera then of each of ``cameras`` (other cameras of the
        body's world, e.g. the GO1's chase camera ``"go1/chase"``), with the people and the
        body as they were at ``t``, and the body's pose ``(x, y, z, heading)`` then. The
        first frame of an episode is its start state.

        Raises:
            InvalidArgumentError: ``fps`` is not positive, or no callback is given.
        """
        if fps is None:
            self._film = None
            if self._batch is not None:
                self._batch.film = None
            return
        ok = isinstance(fps, numbers.Real) and math.isfinite(fps) and 0 < fps <= 1000
        if not ok or callback is None:
            raise InvalidArgumentError(
                f"set_film takes fps in (0, 1000] and a callback, got {fps!r}"
            )
        self._film = (float(fps), callback, tuple(cameras))
        if self._batch is not None:
            self._batch.film = self._film

    # ------------------------------------------------------------------ episodes

    def _per_element(self, name: str, values: object) -> list:
        return per_element(name, values, self._cfg.batch_size)

    def _crowd(self, table: NavTable) -> Crowd:
        crowd = self._crowd_of.get(table.scan_id)
        if crowd is None:
            crowd = NO_CROWD
            if self._crowds is not None:
                # Each scan's people depend on the seed and the scan, not on visiting order.
                rng = np.random.default_rng([self._cfg.seed, zlib.crc32(table.scan_id.encode())])
                crowd = self._crowds(table.scan_id, table.graph, rng)
            self._crowd_of[table.scan_id] = crowd
        return crowd

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
        t0 = time.perf_counter()
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
        self._timers["process"] += time.perf_counter() - t0

    def newRandomEpisode(self, scanId: Sequence[str]) -> None:  # noqa: N802, N803
        """Starts each element at a random included viewpoint, random heading, elevation 0."""
        t0 = time.perf_counter()
        if not self._initialized:
            self.initialize()
        starts = []
        for scan in self._per_element("scanId", scanId):
            table = self._library.table(scan)
            vp, heading = self._random_viewpoint(table), self._rng.uniform(0, TWO_PI)
            starts.append((table, self._crowd(table), vp, heading, 0.0))
        self._batch.start(starts)
        self._timers["process"] += time.perf_counter() - t0

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

    @property
    def robot_actions(self) -> tuple[str, ...]:
        """The robot actions the body takes besides ``"stop"`` (none for the point body)."""
        if not self._initialized:
            self.initialize()
        return self._kind.robot_actions

    def scan(self, scan_id: str) -> Scan:
        """The scan the simulator uses for ``scan_id`` with its geometry (loaded on first use).

        Raises:
            UnknownScanError: No scan or graph can be found for ``scan_id``.
        """
        if not self._initialized:
            self.initialize()
        return self._library.scan(scan_id)

    def people(self, element: int = 0) -> Crowd:
        """The people element ``element`` shares its episode with (reacting to it, if set).

        Raises:
            NotInitializedError: No episode has been started.
        """
        self._started("people")
        return self._batch.elements[element].crowd

    def crowd(self, scan_id: str) -> Crowd:
        """The people of ``scan_id`` (made on first use from the seed and the scan)."""
        if not self._initialized:
            self.initialize()
        return self._crowd(self._library.table(scan_id))

    def draw(self, element: int = 0) -> tuple[mujoco.MjModel, mujoco.MjData]:
        """Element ``element``'s world posed at its time: the people, the body, its camera.

        The model and data a live viewer shows (kinematics done); it shares them with the
        simulator, so re-draw after every action.

        Raises:
            NotInitializedError: No episode has been started.
            InvalidArgumentError: ``element`` is not a batch index.
        """
        self._started("draw")
        n = len(self._batch.elements)
        if (
            isinstance(element, bool)
            or not isinstance(element, numbers.Integral)
            or not 0 <= element < n
        ):
            raise InvalidArgumentError(f"element {element!r} out of range; valid 0–{n - 1}")
        el = self._batch.elements[element]
        return el.body.scene(el.elevation, el.time)

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
        t0 = time.perf_counter()
        elements = self._running()
        indices = self._per_element("index", index)
        dhs = self._per_element("heading", heading)
        des = self._per_element("elevation", elevation)
        actions = [
            (i, check_index(i, el.navigable, k), check_delta(i, dh), check_delta(i, de))
            for i, (el, k, dh, de) in enumerate(zip(elements, indices, dhs, des, strict=True))
        ]
        self._batch.apply(actions)
        self._timers["process"] += time.perf_counter() - t0

    def makeEgoAction(self, action: Sequence[EgoAction | int | str]) -> None:  # noqa: N802
        """Takes one egocentric action per element (see :mod:`havln_mj.sim.egocentric`).

        Elements given ``STOP`` are left as they are (no step, no time).
        """
        t0 = time.perf_counter()
        elements = self._running()
        half = self._cfg.half_hfov()
        acts = [parse_ego_action(act) for act in self._per_element("action", action)]
        actions = []
        for i, (el, act) in enumerate(zip(elements, acts, strict=True)):
            args = ego_to_mattersim(act, el.state, half, DEFAULT_TURN)
            if args is not None:
                actions.append((i, *args))
        self._batch.apply(actions)
        self._timers["process"] += time.perf_counter() - t0

    def wait(self, seconds: Sequence[float]) -> None:
        """Each element stays where it is, looking where it looks, for ``seconds`` (≥ 0).

        An extension of MatterSim (HA3D's frame counter, made explicit): people go on moving,
        the collision signal covers the whole wait, and the state (images included) is that
        at the end. ``makeAction`` with index 0 and no turn is the same with :data:`WAIT_S`.

        Raises:
            NotInitializedError: No episode has been started.
            BatchSizeError: ``seconds`` does not have one entry per batch element.
            InvalidArgumentError: A duration is negative or not finite.
        """
        t0 = time.perf_counter()
        self._running()
        durations = []
        for i, s in enumerate(self._per_element("seconds", seconds)):
            ok = isinstance(s, numbers.Real) and not isinstance(s, bool) and math.isfinite(s)
            if not ok or s < 0:
                raise InvalidArgumentError(
                    f"wait for batch element {i} must be a finite number of seconds ≥ 0, got {s!r}"
                )
            durations.append(float(s))
        self._batch.apply([(i, 0, 0.0, 0.0) for i in range(len(durations))], durations)
        self._timers["process"] += time.perf_counter() - t0

    def makeRobotAction(self, action: Sequence[str]) -> None:  # noqa: N802
        """A robot's continuous actions, one per element (:data:`ROBOT_ACTIONS`).

        With the GO1, ``"forward"`` walks :attr:`~havln_mj.sim.legged.LeggedOptions.forward_m`,
        ``"turn_left"``/``"turn_right"`` turn by ``turn_rad``, ``"stop"`` leaves the element
        alone. The state's location becomes the included viewpoint nearest the robot on its
        floor.

        Raises:
            InvalidActionError: An unknown action, or a body without robot actions.
        """
        t0 = time.perf_counter()
        self._running()
        acts = [
            check_robot_action(act, self._kind.robot_actions)
            for act in self._per_element("action", action)
        ]
        self._batch.robot(acts)
        self._timers["process"] += time.perf_counter() - t0

    def step(self, actions: Sequence[object]) -> None:
        """One action per element, of any kind; None leaves the element alone.

        An extension of MatterSim for task code that steps elements independently: a graph
        action is a tuple ``(index, dHeading, dElevation)`` (as ``makeAction``), an
        :class:`~havln_mj.sim.egocentric.EgoAction` member an egocentric action (STOP leaves
        the element alone), a string a robot action of :data:`ROBOT_ACTIONS` (``"stop"``
        leaves it alone). The whole batch is checked before anything moves.

        Raises:
            NotInitializedError: No episode has been started.
            BatchSizeError: ``actions`` does not have one entry per batch element.
            InvalidActionError: An action of no kind, or invalid for its element.
        """
        t0 = time.perf_counter()
        elements = self._running()
        graph, robot = parse_mixed(
            elements,
            self._per_element("actions", actions),
            self._cfg.half_hfov(),
            self._kind.robot_actions,
        )
        if graph:
            self._batch.apply(graph)
        if any(r != "stop" for r in robot):
            self._batch.robot(robot)
        self._timers["process"] += time.perf_counter() - t0

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
        self._started("getState")
        return [el.state for el in self._batch.elements]

    def getHumanState(self) -> list[list]:  # noqa: N802
        """Each element's people at the element's time: a list of states per element.

        A state (:class:`havln_mj.humans.crowd.PersonState`) has ``position`` (pelvis),
        ``heading``, ``velocity``, ``activity``, ``text`` and ``region``.
        """
        self._started("getHumanState")
        return [el.crowd.states(el.time) for el in self._batch.elements]

    def getHumanPositions(self) -> list[np.ndarray]:  # noqa: N802 - getHumanState's sibling
        """Each element's people's pelvis positions ``(K, 3)`` at the element's time.

        The ``position`` of every :meth:`getHumanState` entry, without computing the rest.
        """
        self._started("getHumanPositions")
        return [el.crowd.positions(np.array([el.time]))[0] for el in self._batch.elements]

    def _started(self, what: str) -> None:
        if self._batch is None or not self._batch.elements:
            raise NotInitializedError(f"{what} called before newEpisode()")

    # ------------------------------------------------------------------ timing

    def resetTimers(self) -> None:  # noqa: N802
        """Zeroes the timers ``timingInfo`` reports."""
        self._timers = {"process": 0.0, "render": 0.0, "frames": 0}

    def timing(self) -> dict[str, float]:
        """Seconds in simulator calls and in rendering, and frames rendered, since the reset."""
        t = self._timers
        return {"process_s": t["process"], "render_s": t["render"], "frames": t["frames"]}

    def timingInfo(self) -> str:  # noqa: N802
        """Time spent in simulator calls and in rendering since the last reset."""
        t = self._timers
        frames = t["frames"]
        fps = f"{frames / t['render']:.1f} fps" if t["render"] > 0 else "n/a"
        return (
            f"Rendered {frames} frames\n"
            f"Process time: {t['process'] * 1e3:.1f} ms\n"
            f"\tRendering: {t['render'] * 1e3:.1f} ms ({fps})\n"
        )

    # Pythonic aliases; the MatterSim names above are the reference.
    new_episode = newEpisode
    new_random_episode = newRandomEpisode
    make_action = makeAction
    make_ego_action = makeEgoAction
    make_robot_action = makeRobotAction
    get_geodesic_distance = getGeodesicDistance
    get_state = getState
    get_human_state = getHumanState


def _reactions(value: object) -> object | None:
    """The reactions of ``reactions=`` (None when people do not react)."""
    if value is False:
        return None
    from havln_mj.humans.reactions import Reactions  # the humans package, only when used

    if value is True:
        return Reactions()
    if isinstance(value, Reactions):
        return value if value.enabled else None
    raise InvalidArgumentError(f"reactions takes a bool or a Reactions, got {value!r}")
