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
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from havln_mj import groups
from havln_mj.errors import HavlnError, RenderingUnavailableError
from havln_mj.scene.rooms import RoomPlan
from havln_mj.sim.crowd import Crowd

if TYPE_CHECKING:
    from havln_mj.render.camera import Camera


@dataclass(frozen=True)
class ViewSettings:
    """What each rendered frame looks like.

    Attributes:
        width: Image width in pixels.
        height: Image height in pixels.
        vfov: Vertical field of view in radians.
        depth: Whether depth is rendered.
        human_mask: Whether the human mask is rendered (a second, segmentation pass).
        labels: Whether semantic and instance labels are rendered (the same second pass:
            :func:`~havln_mj.render.labels.render_labels`).
        bgr: Whether colour comes in BGR order (MatterSim's), read so from the renderer.
    """

    width: int
    height: int
    vfov: float
    depth: bool = False
    human_mask: bool = False
    labels: bool = False
    bgr: bool = False


@dataclass(frozen=True)
class View:
    """One rendered view.

    Attributes:
        rgb: H×W×3 ``uint8`` colour (in BGR order when the settings asked for it).
        depth: H×W ``float32`` planar depth in metres, or None.
        human_mask: H×W ``bool``, True where a person is seen, or None.
        semantic: H×W ``uint8`` mpcat40 class (42: a person), or None.
        instance: H×W ``int32`` object instance (people from
            :data:`~havln_mj.render.labels.PERSON_INSTANCE_BASE`), or None.
    """

    rgb: np.ndarray
    depth: np.ndarray | None
    human_mask: np.ndarray | None
    semantic: np.ndarray | None = None
    instance: np.ndarray | None = None


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
        rooms: The building's room plan, its visual geoms split by room
            (:func:`~havln_mj.sim.world.visual_parts`): rooms a camera cannot see are left
            out of its frames. None draws every room.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        crowd: Crowd,
        style: str = "pieces",
        rooms: RoomPlan | None = None,
    ) -> None:
        self.model = model
        self.crowd = crowd
        # Drawing people and cameras: imported when a world is rendered, not with the simulator.
        from havln_mj.humans.drawing import PeopleDrawing
        from havln_mj.render.culling import RoomCulling

        self._poser = PeopleDrawing(crowd, style).poser(model)
        self._rooms = None if rooms is None else RoomCulling(model, rooms)
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
        """The camera ``name`` set up for ``settings`` (remade only when the size changes).

        A new size gets a new camera before the old one is closed, so when the new one cannot
        be made the old one keeps rendering.

        Raises:
            RenderingUnavailableError: No camera of that size can be made here (the message
                says so and what still works).
        """
        entry = self._cameras.get(name)
        if entry is not None:
            cam, old = entry
            if (old.width, old.height) == (settings.width, settings.height):
                if old.vfov != settings.vfov:
                    cam.set_vfov(math.degrees(settings.vfov))
                self._cameras[name] = (cam, settings)
                return cam
        cam = self._new_camera(name, settings)
        if entry is not None:
            entry[0].close()
        self._cameras[name] = (cam, settings)
        return cam

    def _new_camera(self, name: str, settings: ViewSettings) -> Camera:
        from havln_mj.render.camera import Camera  # rendering: not imported with the simulator

        vis = self.model.vis.global_
        buffer = (int(vis.offwidth), int(vis.offheight))
        try:
            return Camera(
                self.model, name, settings.width, settings.height, math.degrees(settings.vfov)
            )
        except BaseException as exc:
            # Camera enlarges the model's offscreen buffer first: a size that failed must not
            # carry over to the cameras made after it.
            vis.offwidth, vis.offheight = buffer
            if isinstance(exc, HavlnError) or not isinstance(exc, Exception):
                raise
            raise RenderingUnavailableError(
                f"cannot render {settings.width}×{settings.height} images from camera {name!r} "
                f"here ({type(exc).__name__}: {exc}); set a smaller resolution (rendering at the "
                "sizes that worked before is unaffected)"
            ) from exc

    def render(
        self,
        data: mujoco.MjData,
        t: float,
        camera: str,
        settings: ViewSettings,
        pitch: float = 0.0,
        skybox: tuple | None = None,
    ) -> View:
        """Poses the people at ``t`` and renders ``camera``'s view of ``data``.

        Args:
            data: The state, with the agent's pose already written into it.
            t: Simulated seconds (the people's clock).
            camera: Name of a camera of the model.
            settings: Image size, field of view, and whether depth and the mask are wanted.
            pitch: Radians the camera is tilted up from its place in the model (a robot's
                head camera looking up or down).
            skybox: ``(skybox, rotation)`` to show a viewpoint's photographs with the people
                composited over them (:func:`~havln_mj.render.skybox.render_skybox_frame`;
                the camera stands at that viewpoint), or None for the model's own building.
        """
        cam = self.camera(camera, settings)
        meshes = self.pose(data, t, camera, pitch)
        for mesh in meshes:
            cam.upload_mesh(mesh)
        semantic = instance = mask = None
        if skybox is not None:
            from havln_mj.render.skybox import render_skybox_frame

            shot = render_skybox_frame(self.model, data, cam, *skybox)
            rgb, depth, mask = shot.rgb, shot.depth, shot.people
            if settings.bgr:
                rgb = np.ascontiguousarray(rgb[..., ::-1])
            depth = depth if settings.depth else None
            hidden = culled = False
        else:
            # People out of this camera's view, and rooms it cannot see, are left out of its
            # scene (the same image).
            cam_id, aspect = self.model.camera(camera).id, settings.width / settings.height
            rooms = self._rooms
            culled = rooms is not None and rooms.hide_unseen(data, cam_id, settings.vfov, aspect)
            walled = None if rooms is None else rooms.walled
            hidden = self._poser.hide_unseen(data, cam_id, aspect, walled)
        try:
            if skybox is None:
                frame = cam.render(data, rgb=True, depth=settings.depth, bgr=settings.bgr)
                rgb, depth = frame.rgb, frame.depth
            if settings.labels:
                from havln_mj.render.labels import PERSON, render_labels

                labels = render_labels(self.model, data, cam)
                semantic, instance = labels.semantic, labels.instance
                mask = semantic == PERSON if mask is None else mask
            elif settings.human_mask and mask is None:
                ids = cam.render_geom_ids(data)
                mask = (ids >= 0) & self._human_geoms[np.maximum(ids, 0)]
        finally:
            if hidden:
                self._poser.show_all()
            if culled:
                self._rooms.show_all()
        return View(rgb, depth, mask if settings.human_mask else None, semantic, instance)

    def close(self) -> None:
        """Releases the cameras' GL resources (the frames can render again afterwards)."""
        for cam, _ in self._cameras.values():
            cam.close()
        self._cameras.clear()
