"""The point body: a kinematic camera rig on the navigation graph (MatterSim's agent).

Every edge is a straight move between the two viewpoints' camera positions, in every mode
(rendering on or off, bare graph or graph proxy), as in MatterSim: the move lasts its 3-D
length at ``speed`` and the turn that follows the larger of the heading and elevation
changes at ``turn_rate``; an action that neither moves nor turns is a wait. The body always
arrives. Worlds for rendering are built per scan on first use (the building, its people and
the rig) and kept in a least-recently-used cache.
"""

from __future__ import annotations

import logging
import math
from collections import OrderedDict
from collections.abc import Callable

import mujoco
import numpy as np

from havln_mj.errors import InvalidActionError
from havln_mj.frames import wrap_angle
from havln_mj.robot.point_body import CAMERA, PointBody
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.scan import Scan
from havln_mj.sim.body import Film, Outcome, ignore
from havln_mj.sim.crowd import Crowd
from havln_mj.sim.frame import Frames, View, ViewSettings
from havln_mj.sim.memory import release_free_memory
from havln_mj.sim.navigation import camera_positions
from havln_mj.sim.world import WorldOptions, build_world

log = logging.getLogger(__name__)
_PI = math.pi
_TWO_PI = 2.0 * math.pi
_outcome = tuple.__new__  # an Outcome without its Python-level constructor (every move)
_dist, _fmod = math.dist, math.fmod  # (every move)


class Stage:
    """A scan's rendering world: the building, its people and the point rig, with its frames.

    For views from any camera pose: the point body's, and tools that look around a scan.
    """

    def __init__(
        self, scan: Scan, options: WorldOptions, crowd: Crowd, skybox_root: str | None = None
    ) -> None:
        self.world = build_world(scan, options, crowd.shapes, crowd.skins)
        # The compiled model holds the building now: the scan's loaded mesh (tens of MB of
        # vertices and texture arrays) is let go, read again if a world is ever rebuilt.
        for loaded in ("mesh_parts", "mesh"):
            scan.__dict__.pop(loaded, None)
        self.skybox = _skybox_source(scan, skybox_root)
        self.data = mujoco.MjData(self.world.model)
        self.frames = Frames(self.world.model, crowd, options.people_style, scan.room_plan)
        self.rig = PointBody(np.zeros(3))
        release_free_memory()  # what compiling the world allocated and freed

    def place(self, pose: tuple) -> None:
        """Writes the rig's pose ``(position, heading, elevation)`` into the data."""
        position, heading, elevation = pose
        self.rig.set_pose(position, heading, elevation)
        self.rig.write(self.world.model, self.data)

    def render(
        self,
        pose: tuple,
        settings: ViewSettings,
        t: float,
        camera: str | None = None,
        skybox: tuple | None = None,
    ) -> View:
        """The view from the rig at ``pose`` (or from ``camera``) at simulated time ``t``.

        ``skybox``: ``(skybox, rotation)`` of the viewpoint the rig stands at, to show its
        photographs (see :meth:`~havln_mj.sim.frame.Frames.render`).
        """
        self.place(pose)
        return self.frames.render(self.data, t, camera or CAMERA, settings, skybox=skybox)

    def close(self) -> None:
        """Releases the cameras' GL resources."""
        self.frames.close()


class PointKind:
    """Makes point bodies; keeps their rendering worlds per scan.

    Args:
        scan: Loads a scan by id (for rendering).
        world_options: How rendering worlds are built.
        cache_size: How many rendering worlds are kept.
        speed: Walking speed (m/s) for the clock.
        turn_rate: Turning rate (rad/s) for the clock.
        skybox_root: The user's Matterport3D root, to show real scans' skybox photographs
            at viewpoints (None: the mesh).
    """

    name = "point"
    robot_actions = ()

    def __init__(
        self,
        scan: Callable[[str], Scan],
        world_options: WorldOptions,
        cache_size: int,
        speed: float,
        turn_rate: float,
        skybox_root: str | None = None,
    ) -> None:
        self._scan = scan
        self._skybox_root = skybox_root
        self._options = world_options
        self._cache_size = max(1, cache_size)
        self.speed, self.turn_rate = speed, turn_rate
        self._stages: OrderedDict[str, Stage] = OrderedDict()

    def body(self, scan_id: str, graph: NavGraph, crowd: Crowd) -> GraphPointBody:
        """A new point body on ``scan_id``."""
        return GraphPointBody(self, scan_id, graph, crowd)

    def prepare(self, scan_id: str, crowd: Crowd, rendering: bool) -> None:
        """Builds the scan's rendering world ahead of use (nothing without rendering)."""
        if rendering:
            self.stage(scan_id, crowd)

    def stage(self, scan_id: str, crowd: Crowd) -> Stage:
        """The rendering world of ``scan_id`` (built on first use, least recently used out)."""
        stage = self._stages.get(scan_id)
        if stage is None:
            stage = self._stages[scan_id] = Stage(
                self._scan(scan_id), self._options, crowd, self._skybox_root
            )
            while len(self._stages) > self._cache_size:
                _, old = self._stages.popitem(last=False)
                old.close()
        else:
            self._stages.move_to_end(scan_id)
        return stage

    def close(self) -> None:
        """Releases every world's renderer."""
        for stage in self._stages.values():
            stage.close()
        self._stages.clear()


class GraphPointBody:
    """One element's point body: at a viewpoint's camera position, heading and elevation."""

    __slots__ = (
        "_drawn",
        "_kind",
        "_xyz",
        "crowd",
        "elevation",
        "graph",
        "heading",
        "observe",
        "scan_id",
        "viewpoint",
        "xyz",
    )

    def __init__(self, kind: PointKind, scan_id: str, graph: NavGraph, crowd: Crowd) -> None:
        self._kind = kind
        self.scan_id, self.graph, self.crowd = scan_id, graph, crowd
        self._xyz = camera_positions(graph)
        self.viewpoint = ""
        self.xyz = (0.0, 0.0, 0.0)
        self.heading = self.elevation = 0.0
        self._drawn: tuple | None = None
        self.observe = ignore

    def start(self, viewpoint: str, heading: float, elevation: float, t: float) -> Outcome:
        """Places the rig at ``viewpoint`` (an instant)."""
        self.viewpoint = viewpoint
        self.xyz = self._xyz[viewpoint]
        self.heading, self.elevation = heading, elevation
        self._drawn = None
        knots = ((t, *self.xyz),)
        if self.observe is not ignore:
            self.observe(knots)
        return Outcome(0.0, knots, viewpoint, heading)

    def move(
        self,
        target: str,
        heading: float,
        elevation: float,
        t: float,
        wait_s: float,
        film: Film | None = None,
    ) -> Outcome:
        """Moves straight to ``target``, then turns to ``heading``/``elevation``."""
        here = self.xyz
        kind = self._kind
        if target == self.viewpoint:
            there, move_s = here, 0.0
        else:
            there = self._xyz[target]
            move_s = _dist(here, there) / kind.speed
        dh = _fmod(heading - self.heading + _PI, _TWO_PI)  # wrap_angle, inlined (hot)
        if dh <= 0.0:
            dh += _TWO_PI
        dh -= _PI
        turn = dh if dh >= 0.0 else -dh  # max(|dh|, |de|) without builtin calls (hot)
        de = elevation - self.elevation
        if de > turn or -de > turn:
            turn = de if de >= 0.0 else -de
        duration = move_s + turn / kind.turn_rate
        if duration == 0.0:
            duration = wait_s
        (x0, y0, z0), (x1, y1, z1) = here, there
        if move_s > 0.0 and duration > move_s:
            knots = ((t, x0, y0, z0), (t + move_s, x1, y1, z1), (t + duration, x1, y1, z1))
        elif move_s > 0.0 or duration > 0.0:
            knots = ((t, x0, y0, z0), (t + duration, x1, y1, z1))
        else:
            knots = ((t, x0, y0, z0),)
        if self.observe is not ignore:
            self.observe(knots)  # people react to the move they see coming, frames included
        if film is not None:
            self._film(film, t, move_s, duration, here, there, heading, elevation)
        self.viewpoint, self.xyz = target, there
        self.heading, self.elevation = heading, elevation
        self._drawn = None
        return _outcome(Outcome, (duration, knots, target, heading, True, False, False, 0, None))

    def _film(self, film, t0, move_s, duration, here, there, heading, elevation) -> None:
        """Draws the action's frames: along the move, then through the turn."""
        h0, e0 = self.heading, self.elevation
        dh = wrap_angle(heading - h0)
        turn_s = duration - move_s
        a, b = np.asarray(here), np.asarray(there)
        for t in film.times(t0, t0 + duration):
            s = t - t0
            f = min(s / move_s, 1.0) if move_s > 0 else 1.0
            g = min(max((s - move_s) / turn_s, 0.0), 1.0) if turn_s > 0 else 1.0
            self._drawn = (a + f * (b - a), h0 + g * dh, e0 + g * (elevation - e0))
            film.draw(t)

    def robot_action(self, action: str, t: float, film: Film | None = None) -> Outcome:
        """The point body has no robot actions.

        Raises:
            InvalidActionError: Always.
        """
        raise InvalidActionError(
            f'robot action {action!r} needs Simulator(body="go1"); this one drives a point body'
        )

    def pose(self) -> tuple[float, float, float, float]:
        """``(x, y, z, heading)`` of the camera (mid-action while filming: the drawn one)."""
        if self._drawn is not None:
            (x, y, z), heading, _ = self._drawn
            return (float(x), float(y), float(z), float(heading))
        return (*self.xyz, self.heading)

    def goal_distance(self, goal: str) -> float:
        """Geodesic distance on the graph from the current viewpoint."""
        return self.graph.distance(self.viewpoint, goal)

    def scene(self, elevation: float, t: float) -> tuple[mujoco.MjModel, mujoco.MjData]:
        """The scan's rendering world with the rig and the people at ``t``."""
        stage = self._kind.stage(self.scan_id, self.crowd)
        stage.place((np.asarray(self.xyz), self.heading, elevation))
        stage.frames.pose(stage.data, t, CAMERA)
        return stage.world.model, stage.data

    def render(
        self, settings: ViewSettings, elevation: float, t: float, camera: str | None = None
    ) -> View:
        """The rig camera's view at ``t`` (mid-action while filming).

        At a viewpoint of a scan with skybox photographs (skybox mode), those photographs
        with the people over them; between viewpoints, and elsewhere, the mesh.
        """
        stage = self._kind.stage(self.scan_id, self.crowd)
        if self._drawn is not None:
            return stage.render(self._drawn, settings, t, camera)
        sky = None
        if stage.skybox is not None and camera is None:
            photos = stage.skybox.get(self.viewpoint)
            if photos is not None:
                rotation = self.graph.connectivity.poses[self.graph.index(self.viewpoint)][:3, :3]
                sky = (photos, rotation)
        pose = (np.asarray(self.xyz), self.heading, elevation)
        return stage.render(pose, settings, t, camera, sky)


def _skybox_source(scan: Scan, root: str | None):
    """The scan's skybox photographs (None without a root, or when the scan has none)."""
    if root is None:
        return None
    from havln_mj.errors import MissingDataError
    from havln_mj.render.skybox import SkyboxSource

    try:
        return SkyboxSource(scan.scene_id, root)
    except MissingDataError as exc:
        log.warning("%s; %s is rendered from its mesh", exc, scan.scene_id)
        return None
