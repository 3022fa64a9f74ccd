"""The discrete HA-VLN simulator, a drop-in for ``MatterSim.Simulator`` and HA3D's simulator.

Agent code written for MatterSim runs with ``import havln_mj as MatterSim``: the same
setters, batched list arguments, ``initialize``/``newEpisode``/``makeAction``/``getState``,
navigable-location rules, discretised views and exception types (see
``reference/mattersim_api.md`` for the rules). On top of MatterSim:

* **People** (HA3D): with ``Simulator(humans=True)`` every scan is populated (see
  :mod:`havln_mj.sim.people`); people move with simulated time and are drawn in RGB, depth and
  an optional human mask. ``state.isCrushed`` is 1 when the agent came within the collision
  distance of a person at any time during the last action, in every mode (HA3D computed it
  only with rendering off); ``getHumanState()`` gives everyone's state.
* **Clock**: every action advances the element's simulated time (``state.time``) by its
  duration: the move at ``speed`` m/s, then the turn at ``turn_rate`` rad/s (the larger of
  the heading and elevation change); an action that neither moves nor turns is a wait of
  :data:`WAIT_S`. People are a function of that time. In a graph proxy the point body walks
  an edge stored with a route (a line of sight across a stairwell) along that route, through
  its viewpoints: the move lasts the route's length at ``speed``, and the collision signal is
  sampled along it (with rendering off a real scan id has no proxy, and every edge is
  straight, as in MatterSim).
* **Egocentric actions** (HA-VLN): ``makeEgoAction`` (see :mod:`havln_mj.sim.egocentric`).
* **A legged robot**: ``Simulator(body="go1")`` executes every action with a physically
  simulated Unitree GO1 (see :mod:`havln_mj.sim.legged`): graph actions become turn-then-walk
  primitives, ``makeRobotAction`` takes the real robot's continuous actions (forward 0.5 m,
  turn ±45°, stop), states report the snapped viewpoint with the true pose in ``state.pose``,
  the clock advances by physics time, and a fall ends the episode (``state.fell``).
* **Images**: BGR ``uint8`` and ``uint16`` depth in 0.25 mm units, as MatterSim; RGB and
  ``float32`` metres on request (``set_color_order``, ``set_depth_units``).

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
import warnings
import zlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from havln_mj.errors import (
    BatchSizeError,
    InvalidActionError,
    InvalidArgumentError,
    NotInitializedError,
)
from havln_mj.frames import TWO_PI, wrap_angle
from havln_mj.robot.point_body import DEFAULT_SPEED, DEFAULT_TURN_RATE
from havln_mj.scene.navgraph import NavGraph
from havln_mj.sim.crowd import (
    COLLISION_DISTANCE,
    NO_CROWD,
    NO_PROXIMITY,
    Crowd,
    Proximity,
    proximity,
)
from havln_mj.sim.egocentric import DEFAULT_TURN, EgoAction, ego_to_mattersim, parse_ego_action
from havln_mj.sim.legged import LeggedAgent, LeggedOptions, LeggedView, LeggedWorld, Outcome
from havln_mj.sim.navigation import NavTable
from havln_mj.sim.rendering import ViewSettings, depth_to_mattersim
from havln_mj.sim.scenes import SceneLibrary
from havln_mj.sim.state import SimState, ViewPoint
from havln_mj.sim.viewing import (
    DEFAULT_ELEVATION_LIMITS,
    ELEVATION_INCREMENT,
    HEADING_INCREMENT,
    continuous_view,
    discrete_delta,
    discrete_view,
    valid_elevation_limits,
)
from havln_mj.sim.world import WorldOptions

WAIT_S = 1.0  # seconds a "stay" action without rotation lasts
COLOR_ORDERS = ("BGR", "RGB")
BODIES = ("point", "go1")
ROBOT_ACTIONS = ("stop", "forward", "turn_left", "turn_right")
DEPTH_UNITS = ("mattersim", "metres")

CrowdFactory = Callable[[str, NavGraph, np.random.Generator], Crowd]
# The public setter of each locked setting, for the warning when it is called too late.
_SETTERS = {
    "dataset_path": "setDatasetPath",
    "nav_graph_path": "setNavGraphPath",
    "rendering": "setRenderingEnabled",
    "discretized": "setDiscretizedViewingAngles",
    "restricted": "setRestrictedNavigation",
    "preloading": "setPreloadingEnabled",
    "depth": "setDepthEnabled",
    "batch_size": "setBatchSize",
    "cache_size": "setCacheSize",
    "seed": "setSeed",
    "color_order": "set_color_order",
    "depth_units": "set_depth_units",
    "human_mask": "set_human_mask_enabled",
    "world_options": "set_world_options",
}


@dataclass
class _Settings:
    """MatterSim's settings with its defaults (paths default to the environment variables)."""

    dataset_path: str | None = None
    nav_graph_path: str | None = None
    rendering: bool = True
    width: int = 320
    height: int = 240
    vfov: float = 0.8
    elevation_limits: tuple[float, float] = DEFAULT_ELEVATION_LIMITS
    discretized: bool = False
    restricted: bool = True
    preloading: bool = False
    depth: bool = False
    batch_size: int = 1
    cache_size: int = 200
    seed: int = 1
    color_order: str = "BGR"
    depth_units: str = "mattersim"
    human_mask: bool = False
    world_options: WorldOptions = field(default_factory=lambda: WorldOptions(collision="none"))


class _Agent:
    """One batch element's mutable episode state."""

    __slots__ = (
        "contacts",
        "crowd",
        "elevation",
        "heading",
        "legged",
        "navigable",
        "state",
        "step",
        "table",
        "time",
        "view_index",
    )

    def __init__(self, table: NavTable, crowd: Crowd) -> None:
        self.table = table
        self.crowd = crowd
        self.heading = 0.0
        self.elevation = 0.0
        self.view_index = 0
        self.step = 0
        self.time = 0.0
        self.navigable: list[ViewPoint] = []
        self.state: SimState | None = None
        self.legged: LeggedAgent | None = None
        self.contacts = 0


def _check_bool(name: str, value: object) -> bool:
    if not isinstance(value, bool | np.bool_):
        raise InvalidArgumentError(f"{name} takes a bool, got {value!r}")
    return bool(value)


def _check_int(name: str, value: object, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < low:
        raise InvalidArgumentError(f"{name} takes an integer ≥ {low}, got {value!r}")
    return int(value)


def _check_angle(what: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise InvalidArgumentError(f"{what} must be a finite number of radians, got {value!r}")
    return float(value)


class Simulator:
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
        legged: LeggedOptions | None = None,
    ) -> None:
        """Creates an uninitialised simulator with MatterSim's default settings.

        Args:
            humans: Whether scans have people (HA3D's placement rule), or a function making
                a scan's crowd from ``(scan id, graph, generator)``.
            human_placements: HA3D placement file for the real scans (default
                ``$HAVLN_HA3D_PLACEMENTS``); used when ``humans`` is True, as are:
            human_motions: HAPS motion folder (default ``$HAVLN_HAPS_DIR``).
            smpl_model: SMPL model file for skinned people (default ``$HAVLN_SMPL_MODEL``).
            speed: Agent speed for the clock (m/s).
            turn_rate: Agent turning rate for the clock (rad/s).
            collision_distance: HA-VLN's collision threshold (metres, horizontal).
            body: ``"point"`` (kinematic camera rig) or ``"go1"`` (the simulated quadruped).
            legged: How the GO1 is set up and driven (default :class:`LeggedOptions`).
        """
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
        self._humans = humans
        self._body = body
        self._legged_options = legged or LeggedOptions()
        self._legged_worlds: dict[str, tuple[LeggedWorld, LeggedView]] = {}
        self._human_files = (human_placements, human_motions, smpl_model)
        self._crowds: CrowdFactory | None = None
        self._speed = float(speed)
        self._turn_rate = float(turn_rate)
        self._collision_distance = float(collision_distance)
        self._cfg = _Settings()
        self._initialized = False
        self._library: SceneLibrary | None = None
        self._rng = np.random.default_rng(self._cfg.seed)
        self._agents: list[_Agent] = []
        self._crowd_of: dict[str, Crowd] = {}
        self._blank: tuple[np.ndarray, np.ndarray] | None = None
        self._timers = {"process": 0.0, "render": 0.0, "frames": 0}

    # ------------------------------------------------------------------ settings

    def _set(self, name: str, value: object, *, locked: bool = True) -> None:
        if locked and self._initialized:
            warnings.warn(
                f"{_SETTERS[name]}() is ignored after initialize(), as in MatterSim; "
                "call it before",
                stacklevel=3,
            )
            return
        setattr(self._cfg, name, value)

    def setDatasetPath(self, path: str | Path) -> None:  # noqa: N802 - MatterSim's names
        """Root of the user's Matterport3D data (raw or habitat layout), for real meshes."""
        self._set("dataset_path", str(path))

    def setNavGraphPath(self, path: str | Path) -> None:  # noqa: N802
        """Folder of ``<scan>_connectivity.json`` navigation graphs."""
        self._set("nav_graph_path", str(path))

    def setRenderingEnabled(self, value: bool) -> None:  # noqa: N802
        """Whether RGB (and depth) are rendered; off skips all GL work."""
        self._set("rendering", _check_bool("setRenderingEnabled", value))

    def setCameraResolution(self, width: int, height: int) -> None:  # noqa: N802
        """Image size in pixels (may change after ``initialize``)."""
        w = _check_int("setCameraResolution width", width, 1)
        h = _check_int("setCameraResolution height", height, 1)
        self._set("width", w, locked=False)
        self._set("height", h, locked=False)
        self._blank = None

    def setCameraVFOV(self, vfov: float) -> None:  # noqa: N802
        """Vertical field of view in radians, in (0, π) (may change after ``initialize``)."""
        v = _check_angle("setCameraVFOV", vfov)
        if not 0.0 < v < math.pi:
            raise InvalidArgumentError(f"setCameraVFOV takes radians in (0, π), got {vfov!r}")
        self._set("vfov", v, locked=False)

    def setElevationLimits(self, min: float, max: float) -> bool:  # noqa: N802
        """Continuous-mode elevation limits (may change after ``initialize``).

        Returns False, changing nothing, unless min ∈ (−π/2, 0) and max ∈ (0, π/2).
        """
        lo, hi = _check_angle("min elevation", min), _check_angle("max elevation", max)
        if not valid_elevation_limits(lo, hi):
            return False
        self._set("elevation_limits", (lo, hi), locked=False)
        return True

    def setDiscretizedViewingAngles(self, value: bool) -> None:  # noqa: N802
        """12 headings × 3 elevations, 30° apart, and ``viewIndex``."""
        self._set("discretized", _check_bool("setDiscretizedViewingAngles", value))

    def setRestrictedNavigation(self, value: bool) -> None:  # noqa: N802
        """Whether only neighbours within the horizontal field of view are navigable."""
        self._set("restricted", _check_bool("setRestrictedNavigation", value))

    def setPreloadingEnabled(self, value: bool) -> None:  # noqa: N802
        """Whether ``initialize`` loads every graph of the navigation-graph folder.

        With rendering on it also builds their worlds, up to the cache size.
        """
        self._set("preloading", _check_bool("setPreloadingEnabled", value))

    def setDepthEnabled(self, value: bool) -> None:  # noqa: N802
        """Whether depth is rendered."""
        self._set("depth", _check_bool("setDepthEnabled", value))

    def setBatchSize(self, size: int) -> None:  # noqa: N802
        """Number of agents stepped together."""
        self._set("batch_size", _check_int("setBatchSize", size, 1))

    def setCacheSize(self, size: int) -> None:  # noqa: N802
        """Number of built scan worlds kept for rendering."""
        self._set("cache_size", _check_int("setCacheSize", size, 1))

    def setSeed(self, seed: int) -> None:  # noqa: N802
        """Seed of the simulator's random generator (random episodes, crowds)."""
        self._set("seed", _check_int("setSeed", seed, 0))

    def set_color_order(self, order: str) -> None:
        """``"BGR"`` (MatterSim, the default) or ``"RGB"``."""
        if order not in COLOR_ORDERS:
            raise InvalidArgumentError(f"color order {order!r}; valid: {COLOR_ORDERS}")
        self._set("color_order", order)

    def set_depth_units(self, units: str) -> None:
        """Depth format: ``"mattersim"`` (the default) or ``"metres"``.

        MatterSim's is ``uint16`` H×W×1 in 0.25 mm units; metres are ``float32`` H×W×1.
        """
        if units not in DEPTH_UNITS:
            raise InvalidArgumentError(f"depth units {units!r}; valid: {DEPTH_UNITS}")
        self._set("depth_units", units)

    def set_human_mask_enabled(self, value: bool) -> None:
        """Whether states carry ``humanMask`` (a second, segmentation pass per frame)."""
        self._set("human_mask", _check_bool("set_human_mask_enabled", value))

    def set_world_options(self, options: WorldOptions) -> None:
        """How rendered worlds are built.

        The default builds no collision geometry, which the point body does not need.
        """
        if not isinstance(options, WorldOptions):
            raise InvalidArgumentError(f"expected WorldOptions, got {options!r}")
        self._set("world_options", options)

    # ------------------------------------------------------------------ lifecycle

    def initialize(self) -> None:
        """Fixes the settings and prepares the scene library (and preloads if asked)."""
        cfg = self._cfg
        self._library = SceneLibrary(
            cfg.nav_graph_path, cfg.dataset_path, cfg.rendering, cfg.cache_size, cfg.world_options
        )
        self._rng = np.random.default_rng(cfg.seed)
        self._agents = []
        self._crowd_of = {}
        if self._humans is True:
            from havln_mj.sim.people import HumanCrowds  # the humans package, only when used

            self._crowds = HumanCrowds(self._library.scan, *self._human_files)
        else:
            self._crowds = self._humans or None
        self._initialized = True
        if cfg.preloading:
            # Every graph of the folder; with rendering, worlds too, up to the cache size.
            for k, scan_id in enumerate(self._library.connectivity_ids()):
                table = self._library.table(scan_id)
                if cfg.rendering and k < cfg.cache_size:
                    self._library.view(scan_id, self._view_settings(), self._crowd(table))

    def close(self) -> None:
        """Releases renderers; the simulator can be initialised again."""
        if self._library is not None:
            self._library.close()
        for _, view in self._legged_worlds.values():
            view.close()
        self._legged_worlds = {}
        self._library = None
        self._agents = []
        self._initialized = False

    def __enter__(self) -> Simulator:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    # ------------------------------------------------------------------ episodes

    def _batch(self, name: str, values: object) -> list:
        n = self._cfg.batch_size
        if isinstance(values, str) or not isinstance(values, Sequence | np.ndarray):
            raise BatchSizeError(
                f"{name} takes a list with one entry per batch element (batch size {n}), "
                f"got {values!r}"
            )
        if len(values) != n:
            raise BatchSizeError(
                f"{name} has {len(values)} entries but the batch size is {n} (setBatchSize)"
            )
        return list(values)

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
        scans = self._batch("scanId", scanId)
        vps = self._batch("viewpointId", viewpointId)
        headings = self._batch("heading", heading)
        elevations = self._batch("elevation", elevation)
        starts = []
        for i, (scan, vp, h, e) in enumerate(zip(scans, vps, headings, elevations, strict=True)):
            table = self._library.table(scan)
            if vp == "":
                vp = self._random_viewpoint(table)
            table.location(vp)  # raises for an unknown or excluded viewpoint
            h = _check_angle(f"heading[{i}]", h)
            e = _check_angle(f"elevation[{i}]", e)
            starts.append((table, vp, h, e))
        self._start(starts)
        self._timers["process"] += time.perf_counter() - t0

    def newRandomEpisode(self, scanId: Sequence[str]) -> None:  # noqa: N802, N803
        """Starts each element at a random included viewpoint, random heading, elevation 0."""
        t0 = time.perf_counter()
        if not self._initialized:
            self.initialize()
        starts = []
        for scan in self._batch("scanId", scanId):
            table = self._library.table(scan)
            starts.append((table, self._random_viewpoint(table), self._rng.uniform(0, TWO_PI), 0.0))
        self._start(starts)
        self._timers["process"] += time.perf_counter() - t0

    def _random_viewpoint(self, table: NavTable) -> str:
        nodes = table.graph.nodes
        if not nodes:
            raise InvalidArgumentError(f"scan {table.scan_id} has no included viewpoints")
        return nodes[int(self._rng.integers(len(nodes)))]

    def _start(self, starts: list[tuple[NavTable, str, float, float]]) -> None:
        agents = []
        for table, vp, h, e in starts:
            a = _Agent(table, self._crowd(table))
            a.heading, a.elevation, a.view_index = self._view(h, e)
            if self._body == "go1":
                a.legged = LeggedAgent(self._legged_world(table.scan_id, a.crowd)[0])
                a.legged.place(table.graph.position(vp), table.graph.floor_z(vp), a.heading, 0.0)
                a.heading, a.elevation, a.view_index = self._view(a.legged.heading(), e)
            a.navigable = table.candidates(vp, a.heading, a.elevation, self._cos_half_hfov())
            agents.append(a)
        self._agents = agents
        self._publish(range(len(agents)), [NO_PROXIMITY] * len(agents))

    def _legged_world(self, scan_id: str, crowd: Crowd) -> tuple[LeggedWorld, LeggedView]:
        """The GO1 world of a scan (built once per scan)."""
        entry = self._legged_worlds.get(scan_id)
        if entry is None:
            world = LeggedWorld(
                self._library.scan(scan_id), self._cfg.world_options, crowd, self._legged_options
            )
            entry = self._legged_worlds[scan_id] = (world, LeggedView(world))
        return entry

    def _view(self, heading: float, elevation: float) -> tuple[float, float, int]:
        if self._cfg.discretized:
            return discrete_view(heading, elevation)
        return continuous_view(heading, elevation, self._cfg.elevation_limits)

    def _half_hfov(self) -> float:
        cfg = self._cfg
        return cfg.vfov * cfg.width / cfg.height / 2.0

    @property
    def batch_size(self) -> int:
        """The number of batch elements (``setBatchSize``)."""
        return self._cfg.batch_size

    @property
    def half_hfov(self) -> float:
        """Half the horizontal field of view (radians), as MatterSim approximates it.

        ``vfov · width / height / 2``; restricted navigation and FORWARD use it.
        """
        return self._half_hfov()

    def graph(self, scan_id: str) -> NavGraph:
        """The navigation graph the simulator uses for ``scan_id`` (loaded on first use).

        Raises:
            UnknownScanError: No graph can be found for ``scan_id``.
        """
        if not self._initialized:
            self.initialize()
        return self._library.table(scan_id).graph

    def _cos_half_hfov(self) -> float | None:
        return math.cos(self._half_hfov()) if self._cfg.restricted else None

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
        agents = self._running()
        indices = self._batch("index", index)
        dhs = self._batch("heading", heading)
        des = self._batch("elevation", elevation)
        actions = [
            (i, self._check_index(i, a, k), self._delta(i, dh), self._delta(i, de))
            for i, (a, k, dh, de) in enumerate(zip(agents, indices, dhs, des, strict=True))
        ]
        self._apply(actions)
        self._timers["process"] += time.perf_counter() - t0

    def makeEgoAction(self, action: Sequence[EgoAction | int | str]) -> None:  # noqa: N802
        """Takes one egocentric action per element (see :mod:`havln_mj.sim.egocentric`).

        Elements given ``STOP`` are left as they are (no step, no time).
        """
        t0 = time.perf_counter()
        agents = self._running()
        half = self._half_hfov()
        actions = []
        for i, (a, act) in enumerate(zip(agents, self._batch("action", action), strict=True)):
            args = ego_to_mattersim(parse_ego_action(act), a.state, half, DEFAULT_TURN)
            if args is not None:
                actions.append((i, *args))
        self._apply(actions)
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
        for i, s in enumerate(self._batch("seconds", seconds)):
            ok = isinstance(s, numbers.Real) and not isinstance(s, bool) and math.isfinite(s)
            if not ok or s < 0:
                raise InvalidArgumentError(
                    f"wait for batch element {i} must be a finite number of seconds ≥ 0, got {s!r}"
                )
            durations.append(float(s))
        self._apply([(i, 0, 0.0, 0.0) for i in range(len(durations))], durations)
        self._timers["process"] += time.perf_counter() - t0

    def _running(self) -> list[_Agent]:
        if not self._initialized:
            raise NotInitializedError("makeAction called before initialize()")
        if not self._agents:
            raise NotInitializedError("makeAction called before newEpisode()")
        return self._agents

    @staticmethod
    def _check_index(i: int, a: _Agent, k: object) -> int:
        n = len(a.navigable)
        if isinstance(k, bool) or not isinstance(k, numbers.Integral) or not 0 <= k < n:
            raise InvalidActionError(
                f"action index {k!r} for batch element {i} is out of range: "
                f"{n} navigable locations, valid 0–{n - 1}"
            )
        return int(k)

    @staticmethod
    def _delta(i: int, value: object) -> float:
        if isinstance(value, float) and math.isfinite(value):
            return value  # the common case, checked cheaply
        try:
            return _check_angle(f"turn for batch element {i}", value)
        except InvalidArgumentError as exc:
            raise InvalidActionError(str(exc)) from None

    def _apply(
        self, actions: list[tuple[int, int, float, float]], waits: Sequence[float] | None = None
    ) -> None:
        """Move, then rotate, then recompute candidates, for each (element, index, dh, de).

        ``waits`` (one per action, for index 0 without turns) overrides :data:`WAIT_S`.
        """
        cfg = self._cfg
        cos_half = self._cos_half_hfov()
        changed, near = [], []
        for n, (i, k, dh, de) in enumerate(actions):
            wait_s = WAIT_S if waits is None else waits[n]
            a = self._agents[i]
            here, target = a.navigable[0], a.navigable[k]
            if cfg.discretized:
                dh = discrete_delta(dh, HEADING_INCREMENT)
                de = discrete_delta(de, ELEVATION_INCREMENT)
                heading, elevation, view = discrete_view(a.heading + dh, a.elevation + de)
            else:
                heading, elevation, view = continuous_view(
                    a.heading + dh, a.elevation + de, cfg.elevation_limits
                )
            if a.legged is not None:
                outcome = self._legged_move(a, k, target, heading, wait_s)
                heading, elevation, view = self._view(a.legged.heading(), elevation)
                duration = outcome.duration
                contact = outcome.contact or NO_PROXIMITY
                a.contacts = outcome.human_contacts
            else:
                # An edge a graph proxy walks by a route takes the route, not the line.
                route = a.table.path(here.viewpointId, target.viewpointId) if k else None
                length = target.rel_distance if route is None else route[1]
                move_s = length / self._speed
                turn = max(abs(wrap_angle(heading - a.heading)), abs(elevation - a.elevation))
                duration = move_s + turn / self._turn_rate
                if duration == 0.0:
                    duration = wait_s
                contact = NO_PROXIMITY
                if len(a.crowd):
                    if route is None:
                        path = ((here.x, here.y, here.z), (target.x, target.y, target.z))
                    else:
                        path = route[0]
                    contact = proximity(
                        a.crowd, path, a.time, move_s, duration, self._collision_distance
                    )
            a.time += duration
            a.step += 1
            a.heading, a.elevation, a.view_index = heading, elevation, view
            a.navigable = a.table.candidates(target.viewpointId, heading, elevation, cos_half)
            changed.append(i)
            near.append(contact)
        self._publish(changed, near)

    def _legged_move(
        self, a: _Agent, k: int, target: ViewPoint, heading: float, wait_s: float
    ) -> Outcome:
        """A graph action with the GO1: walk to the target viewpoint, then face ``heading``."""
        legged = a.legged
        if k == 0:
            turn = wrap_angle(heading - legged.heading())
            if abs(turn) < 1e-9:
                return legged.run([("stand", wait_s)], a.time)
            return legged.run([("turn", turn)], a.time)
        floor = a.table.graph.floor_z(target.viewpointId)
        return legged.go_to(np.array([target.x, target.y, floor]), heading, a.time)

    def makeRobotAction(self, action: Sequence[str]) -> None:  # noqa: N802
        """The real robot's continuous actions, one per element (``body="go1"`` only).

        ``"forward"`` walks :attr:`LeggedOptions.forward_m`, ``"turn_left"``/``"turn_right"``
        turn by :attr:`LeggedOptions.turn_rad`, ``"stop"`` leaves the element alone. The
        state's location becomes the included viewpoint nearest the robot on its floor.

        Raises:
            InvalidActionError: An unknown action, or the simulator is not driving a GO1.
        """
        t0 = time.perf_counter()
        agents = self._running()
        if self._body != "go1":
            raise InvalidActionError(
                f'makeRobotAction needs Simulator(body="go1"); this one drives a {self._body} body'
            )
        opts = self._legged_options
        plans = {
            "forward": [("forward", opts.forward_m)],
            "turn_left": [("turn", -opts.turn_rad)],
            "turn_right": [("turn", opts.turn_rad)],
        }
        acts = self._batch("action", action)
        for act in acts:
            if act not in ROBOT_ACTIONS:
                raise InvalidActionError(
                    f"robot action {act!r} unknown; valid: {', '.join(ROBOT_ACTIONS)}"
                )
        changed, near = [], []
        cos_half = self._cos_half_hfov()
        for i, (a, act) in enumerate(zip(agents, acts, strict=True)):
            if act == "stop":
                continue
            outcome = a.legged.run(plans[act], a.time)
            a.time += outcome.duration
            a.step += 1
            a.contacts = outcome.human_contacts
            a.heading, a.elevation, a.view_index = self._view(a.legged.heading(), a.elevation)
            vp = self._nearest_viewpoint(a)
            a.navigable = a.table.candidates(vp, a.heading, a.elevation, cos_half)
            changed.append(i)
            near.append(outcome.contact or NO_PROXIMITY)
        self._publish(changed, near)
        self._timers["process"] += time.perf_counter() - t0

    def getGeodesicDistance(self, viewpointId: Sequence[str]) -> list[float]:  # noqa: N802, N803
        """Each element's walking distance to a viewpoint (metres, ``inf`` if unreachable).

        With the GO1 it is measured from the robot's true position on the level's
        navigability grid (falling back to the graph when the viewpoint is on another
        level); with the point body it is the graph's geodesic from the current viewpoint.

        Raises:
            UnknownViewpointError: A viewpoint is unknown or excluded.
        """
        agents = self._running()
        out = []
        for a, vp in zip(agents, self._batch("viewpointId", viewpointId), strict=True):
            graph = a.table.graph
            here = a.navigable[0].viewpointId
            d = graph.distance(here, vp)
            if a.legged is not None:
                goal = np.append(graph.position(vp)[:2], graph.floor_z(vp))
                p = a.legged.position()
                start = np.array([p[0], p[1], graph.floor_z(here)])
                world = self._legged_worlds[a.table.scan_id][0]
                on_grid = world.geodesic(start, goal)
                d = on_grid if math.isfinite(on_grid) else d
            out.append(float(d))
        return out

    @staticmethod
    def _nearest_viewpoint(a: _Agent) -> str:
        """The included viewpoint nearest the robot, preferring ones on its floor."""
        graph = a.table.graph
        pos = a.legged.position()
        floor = pos[2] - a.legged.body.gains.foot_depth

        def cost(vp: str) -> float:
            p = graph.position(vp)
            return float(np.hypot(*(p[:2] - pos[:2]))) + 10.0 * abs(graph.floor_z(vp) - floor)

        return min(graph.nodes, key=cost)

    # ------------------------------------------------------------------ state

    def _view_settings(self) -> ViewSettings:
        cfg = self._cfg
        return ViewSettings(cfg.width, cfg.height, cfg.vfov, cfg.depth, cfg.human_mask)

    def _blank_images(self) -> tuple[np.ndarray, np.ndarray]:
        """Shared read-only zero images for states that are not rendered."""
        cfg = self._cfg
        if self._blank is None or self._blank[0].shape[:2] != (cfg.height, cfg.width):
            rgb = np.zeros((cfg.height, cfg.width, 3), np.uint8)
            dtype = np.float32 if cfg.depth_units == "metres" else np.uint16
            depth = np.zeros((cfg.height, cfg.width, 1), dtype)
            rgb.flags.writeable = depth.flags.writeable = False
            self._blank = (rgb, depth)
        return self._blank

    def _images(self, a: _Agent) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        cfg = self._cfg
        if not cfg.rendering:
            return (*self._blank_images(), None)
        t0 = time.perf_counter()
        if a.legged is not None:
            view = self._legged_worlds[a.table.scan_id][1]
            frame = view.render(a.legged, self._view_settings(), a.elevation, a.time)
        else:
            view = self._library.view(a.table.scan_id, self._view_settings(), a.crowd)
            here = a.navigable[0]
            frame = view.render(np.array([here.x, here.y, here.z]), a.heading, a.elevation, a.time)
        rgb = frame.rgb if cfg.color_order == "RGB" else np.ascontiguousarray(frame.rgb[..., ::-1])
        if frame.depth is None:
            depth = self._blank_images()[1]
        elif cfg.depth_units == "metres":
            depth = frame.depth[..., None]
        else:
            depth = depth_to_mattersim(frame.depth)
        self._timers["render"] += time.perf_counter() - t0
        self._timers["frames"] += 1
        return rgb, depth, frame.human_mask

    def _publish(self, which: Sequence[int], near: Sequence[Proximity]) -> None:
        for i, contact in zip(which, near, strict=True):
            a = self._agents[i]
            rgb, depth, mask = self._images(a)
            a.state = SimState(
                a.table.scan_id,
                a.step,
                rgb,
                depth,
                a.navigable[0],
                a.heading,
                a.elevation,
                a.view_index,
                a.navigable,
                a.time,
                int(contact.crushed),
                contact.people,
                contact.min_distance,
                mask,
                None if a.legged is None else np.append(a.legged.position(), a.heading),
                a.legged is not None and a.legged.fell,
                a.contacts,
            )

    def getState(self) -> list[SimState]:  # noqa: N802
        """The current state of every batch element.

        Raises:
            NotInitializedError: No episode has been started.
        """
        if not self._agents:
            raise NotInitializedError("getState called before newEpisode()")
        return [a.state for a in self._agents]

    def getHumanState(self) -> list[list]:  # noqa: N802
        """Each element's people at the element's time: a list of states per element.

        A state (:class:`havln_mj.humans.crowd.PersonState`) has ``position`` (pelvis),
        ``heading``, ``velocity``, ``activity``, ``text`` and ``region``.
        """
        if not self._agents:
            raise NotInitializedError("getHumanState called before newEpisode()")
        return [a.crowd.states(a.time) for a in self._agents]

    def getHumanPositions(self) -> list[np.ndarray]:  # noqa: N802 - getHumanState's sibling
        """Each element's people's pelvis positions ``(K, 3)`` at the element's time.

        The ``position`` of every :meth:`getHumanState` entry, without computing the rest.
        """
        if not self._agents:
            raise NotInitializedError("getHumanPositions called before newEpisode()")
        out = []
        for a in self._agents:
            out.append(
                a.crowd.positions(np.array([a.time]))[0] if len(a.crowd) else np.zeros((0, 3))
            )
        return out

    # ------------------------------------------------------------------ timing

    def resetTimers(self) -> None:  # noqa: N802
        """Zeroes the timers ``timingInfo`` reports."""
        self._timers = {"process": 0.0, "render": 0.0, "frames": 0}

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
