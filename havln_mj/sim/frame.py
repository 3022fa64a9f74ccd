"""The frame pipeline: people posed at simulated time t, then images from any camera.

Every picture the package makes goes through :class:`Frames`: the simulator's states (point
body and GO1), the demo run's videos, the gym and ``dm_env`` adapters and the viewer. One
:class:`Frames` serves one compiled world (a building with its people, and the bodies in it);
each call to :meth:`Frames.render` poses the people of that world at ``t`` in the given
``MjData`` (capsule bodies and, for people with a skin, their meshes), runs kinematics, and
renders colour, depth and the human mask from a named camera. The caller has written the
agent's own pose into ``data`` (a mocap rig, or a robot's physics state).

People are drawn as :mod:`havln_mj.humans.drawing` builds them (dressed rigid pieces,
skinned bodies or capsules). Skinned meshes live in the model, not the data, so their vertices
are rewritten for ``t`` and re-sent to the rendering camera's GL context before each frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from havln_mj import groups
from havln_mj.humans.drawing import PeopleDrawing
from havln_mj.render.camera import Camera
from havln_mj.sim.crowd import Crowd


@dataclass(frozen=True)
class ViewSettings:
    """What each rendered frame looks like.

    Attributes:
        width: Image width in pixels.
        height: Image height in pixels.
        vfov: Vertical field of view in radians.
        depth: Whether depth is rendered.
        human_mask: Whether the human mask is rendered (a second, segmentation pass).
    """

    width: int
    height: int
    vfov: float
    depth: bool = False
    human_mask: bool = False


@dataclass(frozen=True)
class View:
    """One rendered view: colour, depth in metres (or None) and the human mask (or None)."""

    rgb: np.ndarray
    depth: np.ndarray | None
    human_mask: np.ndarray | None


def _pitch_quat(base: np.ndarray, pitch: float) -> np.ndarray:
    # A MuJoCo camera looks along its −z with +y up: pitching up turns it about its +x.
    turn = np.array([math.cos(pitch / 2), math.sin(pitch / 2), 0.0, 0.0])
    quat = np.empty(4)
    mujoco.mju_mulQuat(quat, base, turn)
    return quat


class Frames:
    """Renders one compiled world: people at time t, seen from any of its cameras.

    Args:
        model: The compiled world (people added in ``style``, as
            :class:`~havln_mj.humans.drawing.PeopleDrawing` adds them).
        crowd: The people in it, in the order they were added.
        style: How they were drawn (:data:`~havln_mj.humans.mujoco_people.DRAW_STYLES`).
    """

    def __init__(self, model: mujoco.MjModel, crowd: Crowd, style: str = "pieces") -> None:
        self.model = model
        self.crowd = crowd
        self._poser = PeopleDrawing(crowd, style).poser(model)
        self._human_geoms = model.geom_group == groups.HUMANS
        self._cameras: dict[str, tuple[Camera, ViewSettings]] = {}
        self._base_quat: dict[int, np.ndarray] = {}

    def pose_people(self, data: mujoco.MjData, t: float) -> list[int]:
        """Writes everyone's pose at ``t`` into ``data``; returns the skin meshes rewritten.

        Kinematics is left to the caller (:meth:`render` runs it).
        """
        return list(self._poser.pose(data, t))

    def pose(self, data: mujoco.MjData, t: float, camera: str, pitch: float = 0.0) -> list[int]:
        """Poses the people at ``t`` and ``camera`` at ``pitch``, then runs kinematics.

        Returns the skin meshes rewritten (to upload before rendering).
        """
        meshes = self.pose_people(data, t)
        cam_id = self.model.camera(camera).id
        base = self._base_quat.setdefault(cam_id, self.model.cam_quat[cam_id].copy())
        self.model.cam_quat[cam_id] = _pitch_quat(base, pitch)
        mujoco.mj_kinematics(self.model, data)
        mujoco.mj_camlight(self.model, data)
        return meshes

    def camera(self, name: str, settings: ViewSettings) -> Camera:
        """The camera ``name`` set up for ``settings`` (remade only when the size changes)."""
        entry = self._cameras.get(name)
        if entry is not None:
            cam, old = entry
            if (old.width, old.height) == (settings.width, settings.height):
                if old.vfov != settings.vfov:
                    cam.set_vfov(math.degrees(settings.vfov))
                self._cameras[name] = (cam, settings)
                return cam
            cam.close()
            del self._cameras[name]
        cam = Camera(self.model, name, settings.width, settings.height, math.degrees(settings.vfov))
        self._cameras[name] = (cam, settings)
        return cam

    def render(
        self,
        data: mujoco.MjData,
        t: float,
        camera: str,
        settings: ViewSettings,
        pitch: float = 0.0,
    ) -> View:
        """Poses the people at ``t`` and renders ``camera``'s view of ``data``.

        Args:
            data: The state, with the agent's pose already written into it.
            t: Simulated seconds (the people's clock).
            camera: Name of a camera of the model.
            settings: Image size, field of view, and whether depth and the mask are wanted.
            pitch: Radians the camera is tilted up from its place in the model (a robot's
                head camera looking up or down).
        """
        cam = self.camera(camera, settings)
        meshes = self.pose(data, t, camera, pitch)
        for mesh in meshes:
            cam.upload_mesh(mesh)
        frame = cam.render(data, rgb=True, depth=settings.depth)
        mask = None
        if settings.human_mask:
            ids = cam.render_geom_ids(data)
            mask = (ids >= 0) & self._human_geoms[np.maximum(ids, 0)]
        return View(frame.rgb, frame.depth, mask)

    def close(self) -> None:
        """Releases the cameras' GL resources (the frames can render again afterwards)."""
        for cam, _ in self._cameras.values():
            cam.close()
        self._cameras.clear()
