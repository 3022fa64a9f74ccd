"""Rendering the agent's view through the simulator API, in MatterSim's image formats.

MatterSim hands out BGR ``uint8`` colour and ``uint16`` depth in 0.25 mm units (planar
z-distance, 0 = no reading, so anything beyond 16.38 m reads 0). Users who prefer RGB or
``float32`` metres ask the simulator for them. People are posed at the element's simulated
time before each frame, so they appear in colour and depth; the human mask (which pixels
show a person) takes a second, segmentation pass and is drawn only when asked for.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from havln_mj import groups
from havln_mj.humans.mujoco_people import PeopleWriter
from havln_mj.humans.skinned import SkinWriter
from havln_mj.render.camera import Camera
from havln_mj.robot.point_body import CAMERA, PointBody
from havln_mj.scene.scan import Scan
from havln_mj.sim.crowd import NO_CROWD, Crowd
from havln_mj.sim.world import WorldOptions, build_world

DEPTH_UNITS_PER_M = 4000.0  # MatterSim / Matterport depth: 0.25 mm per unit
_UINT16_MAX = 65535


@dataclass(frozen=True)
class ViewSettings:
    """What each rendered frame looks like.

    Attributes:
        width: Image width in pixels.
        height: Image height in pixels.
        vfov: Vertical field of view in radians.
        depth: Whether depth is rendered.
    """

    width: int
    height: int
    vfov: float
    depth: bool
    human_mask: bool = False


def depth_to_mattersim(depth_m: np.ndarray) -> np.ndarray:
    """Metres to MatterSim's H×W×1 ``uint16`` in 0.25 mm units (out of range reads 0)."""
    units = np.rint(depth_m * DEPTH_UNITS_PER_M)
    units[units > _UINT16_MAX] = 0
    return units.astype(np.uint16)[..., None]


@dataclass(frozen=True)
class View:
    """One rendered view: colour, depth in metres (or None) and the human mask (or None)."""

    rgb: np.ndarray
    depth: np.ndarray | None
    human_mask: np.ndarray | None


def shoot(
    camera: Camera, data: mujoco.MjData, settings: ViewSettings, human_geoms: np.ndarray
) -> View:
    """Renders ``data`` (kinematics done) with ``camera``; the human mask when asked for.

    Args:
        camera: The camera.
        data: The posed state.
        settings: Whether depth and the mask are wanted.
        human_geoms: Per model geom, whether it belongs to a person.
    """
    frame = camera.render(data, rgb=True, depth=settings.depth)
    mask = None
    if settings.human_mask:
        ids = camera.render_geom_ids(data)
        mask = (ids >= 0) & human_geoms[np.maximum(ids, 0)]
    return View(frame.rgb, frame.depth, mask)


class SceneView:
    """A scan's world with its people and the point-body camera, rendered one pose at a time."""

    def __init__(self, scan: Scan, options: WorldOptions, crowd: Crowd = NO_CROWD) -> None:
        self.crowd = crowd
        shapes = crowd.shapes
        skins = crowd.skins
        self.world = build_world(scan, options, shapes, skins)
        self.data = mujoco.MjData(self.world.model)
        self._people = PeopleWriter(self.world.model, len(shapes))
        skinned = [k for k, s in enumerate(skins) if s is not None]
        self._skins = SkinWriter(self.world.model, skinned) if skinned else None
        self._human_geoms = self.world.model.geom_group == groups.HUMANS
        self._body = PointBody(np.zeros(3))
        self._camera: Camera | None = None
        self._settings: ViewSettings | None = None

    def configure(self, settings: ViewSettings) -> None:
        """Makes the camera match ``settings`` (recreated only when the size changes)."""
        if settings == self._settings:
            return
        old = self._settings
        if (
            self._camera is None
            or old is None
            or (old.width, old.height)
            != (
                settings.width,
                settings.height,
            )
        ):
            if self._camera is not None:
                self._camera.close()
            self._camera = Camera(
                self.world.model,
                CAMERA,
                settings.width,
                settings.height,
                math.degrees(settings.vfov),
            )
        else:
            self._camera.set_vfov(math.degrees(settings.vfov))
        self._settings = settings

    def render(self, position: np.ndarray, heading: float, elevation: float, t: float) -> View:
        """Renders the view from a camera pose (metres, radians) at simulated time ``t``."""
        assert self._camera is not None and self._settings is not None, "configure() first"
        if self._people.n_people:
            self._people.write(self.data, *self.crowd.pose(t))
        if self._skins is not None:
            verts = self.crowd.skin_vertices(t)
            for mesh in self._skins.write(self.world.model, self.data, verts):
                self._camera.upload_mesh(mesh)
        self._body.set_pose(position, heading, elevation)
        self._body.write(self.world.model, self.data)  # runs kinematics for everything
        return shoot(self._camera, self.data, self._settings, self._human_geoms)

    def close(self) -> None:
        """Releases the camera's GL resources."""
        if self._camera is not None:
            self._camera.close()
            self._camera = None
            self._settings = None
