"""Offscreen RGB-D camera: one MuJoCo camera rendered through the shared GL context.

Conventions:

- **RGB** is ``uint8`` H×W×3, top image row first (row 0 is the top of the view).
- **Depth** is ``float32`` H×W in metres: *planar* z-depth along the camera's viewing axis
  (what MatterSim depth means), not the Euclidean ray length. A flat wall facing the camera
  has the same depth in every pixel. Pixels where nothing was hit within the far plane
  (:data:`FAR_M`) are ``0.0``, MatterSim's "no depth" value.
- **Clipping**: near :data:`NEAR_M`, far :data:`FAR_M` (metres), written into the model as
  ``model.vis.map.znear/zfar`` relative to ``model.stat.extent``. MuJoCo renders with
  reversed z; the error grows with distance squared (measured on Mesa llvmpipe: 0.03 mm at
  7 m, 1.6 mm at 50 m). Geometry nearer than the near plane is clipped.
- **Transparency**: geoms with alpha < 1 are drawn in RGB but do not occlude in depth
  (MuJoCo draws them without depth writes); alpha 0 geoms are not drawn.
- **Field of view** is vertical (``vfov``); the horizontal one follows from the aspect ratio:
  ``hfov = 2·atan(tan(vfov/2)·W/H)``. The camera pose is the model camera's
  (``data.cam_xpos/cam_xmat``; see :mod:`havln_mj.frames` for the heading/elevation frame:
  a MuJoCo camera looks along its local -z with +y up).
- **What is drawn**: static and dynamic geoms of the visible geom groups (MuJoCo's defaults
  0, 1, 2 unless ``geom_groups`` is given); decorations (contact points, rangefinder rays,
  frames, labels) are never drawn. Shadows and reflections are off unless asked for.
- **One pass**: a single ``mjr_render`` and a single ``mjr_readPixels`` that reads colour and
  depth together (``mujoco.Renderer`` renders twice for RGB then depth).
- **Anti-aliasing** is off by default (``msaa_samples=0``): on CPU rendering 4× MSAA about
  doubles the frame time.
- **Memory**: each :class:`Frame` holds fresh arrays; consecutive frames never share memory.

Model side effects (needed because MuJoCo reads these from the model): ``offwidth``/
``offheight`` are enlarged to fit the image, ``znear``/``zfar`` are set as above, and the
camera's ``fovy`` is set to this camera's ``vfov`` before every render (so two
:class:`Camera` objects on one model camera may use different fields of view); a camera
defined by ``sensorsize``/intrinsics is switched to ``fovy``.

Renderers share one GL context per process (:mod:`havln_mj.render.gl`); use them from one
thread at a time.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from havln_mj.errors import ClosedError, InvalidArgumentError
from havln_mj.render import gl
from havln_mj.render.camera_checks import (
    MAX_SIZE,
    camera_id,
    check_groups,
    check_msaa,
    check_size,
    check_vfov,
)

__all__ = ["FAR_M", "MAX_SIZE", "NEAR_M", "Camera", "Frame"]

NEAR_M = 0.04
"""Near clipping distance in metres."""

FAR_M = 100.0
"""Far clipping distance in metres; nothing farther is drawn and its depth reads 0."""

_CATMASK = int(mujoco.mjtCatBit.mjCAT_STATIC) | int(mujoco.mjtCatBit.mjCAT_DYNAMIC)
_OFFSCREEN = int(mujoco.mjtFramebuffer.mjFB_OFFSCREEN)
_GL_RGB, _GL_BGR = 0x1907, 0x80E0  # OpenGL's pixel formats (MjrContext.readPixelFormat)


@dataclass(frozen=True)
class Frame:
    """One rendered view.

    Attributes:
        rgb: H×W×3 ``uint8`` colour, top row first; None if not requested.
        depth: H×W ``float32`` planar depth in metres, 0 where nothing was hit; None if not
            requested.
    """

    rgb: np.ndarray | None
    depth: np.ndarray | None


class Camera:
    """Renders RGB and planar depth from a named model camera, offscreen, in one pass.

    Example:
        >>> with Camera(model, "agent_cam", width=320, height=240) as cam:  # doctest: +SKIP
        ...     mujoco.mj_forward(model, data)
        ...     frame = cam.render(data)
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        camera: str = "agent_cam",
        width: int = 640,
        height: int = 480,
        vfov_deg: float = 60.0,
        shadows: bool = False,
        reflections: bool = False,
        geom_groups: Sequence[int] | None = None,
        *,
        msaa_samples: int = 0,
    ) -> None:
        """Creates the camera's scene and MuJoCo render context on the shared GL context.

        Args:
            model: The compiled model. Modified as the module docstring describes.
            camera: Name of a camera in ``model``.
            width: Image width in pixels, in [1, :data:`~havln_mj.render.camera_checks.MAX_SIZE`].
            height: Image height in pixels, in [1, :data:`~havln_mj.render.camera_checks.MAX_SIZE`].
            vfov_deg: Vertical field of view in degrees, in (0, 180).
            shadows: Whether lights cast shadows.
            reflections: Whether reflective materials reflect.
            geom_groups: Geom groups to draw (0–5); None keeps MuJoCo's default (0, 1, 2).
            msaa_samples: Multisamples of the offscreen buffer (0–16). 0, the default, turns
                anti-aliasing off: with CPU rendering (Mesa llvmpipe) 4 samples costs about
                twice the frame time. The model's ``offsamples`` is left unchanged.

        Raises:
            InvalidArgumentError: If an argument is out of range or the camera is unknown
                (the message lists the model's cameras) or orthographic.
            RenderingUnavailableError: If no OpenGL backend can be started.
        """
        # Set first so close()/__del__ are safe if validation or GL setup fails below.
        self._closed = True
        self._handle: gl.GLHandle | None = None
        self._ctx: mujoco.MjrContext | None = None

        if not isinstance(model, mujoco.MjModel):
            raise InvalidArgumentError(f"model must be a mujoco.MjModel, got {type(model)!r}")
        self._width = check_size("width", width)
        self._height = check_size("height", height)
        self._vfov = check_vfov(vfov_deg)
        self._cam_id = camera_id(model, camera)
        if int(model.cam_projection[self._cam_id]) != int(mujoco.mjtProjection.mjPROJ_PERSPECTIVE):
            raise InvalidArgumentError(f"camera {camera!r} is orthographic; need perspective")
        groups = check_groups(geom_groups)
        msaa_samples = check_msaa(msaa_samples)
        self._model = model
        self._camera_name = camera

        self._fit_model()

        self._option = mujoco.MjvOption()
        if groups is not None:
            self._option.geomgroup[:] = 0
            self._option.geomgroup[groups] = 1
        self._mjv_cam = mujoco.MjvCamera()
        self._mjv_cam.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self._mjv_cam.fixedcamid = self._cam_id
        self._scene = mujoco.MjvScene(model, maxgeom=max(1000, model.ngeom + 500))
        self._scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = bool(shadows)
        self._scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = bool(reflections)
        self._rect = mujoco.MjrRect(0, 0, self._width, self._height)
        self._rgb_raw = np.empty((self._height, self._width, 3), dtype=np.uint8)
        self._depth_raw = np.empty((self._height, self._width), dtype=np.float32)
        self._depth_coef: tuple[float, float, np.float32, np.float32] | None = None

        self._handle = gl.acquire(self._width, self._height, on_exit=self.close)
        self._closed = False
        try:
            self._make_context(msaa_samples)
        except BaseException:
            self.close()
            raise

    def _fit_model(self) -> None:
        """Model-level settings MuJoCo reads when making the context and the scene."""
        model, vis = self._model, self._model.vis
        vis.global_.offwidth = max(int(vis.global_.offwidth), self._width)
        vis.global_.offheight = max(int(vis.global_.offheight), self._height)
        extent = float(model.stat.extent) or 1.0
        vis.map.znear = NEAR_M / extent
        vis.map.zfar = FAR_M / extent
        model.cam_sensorsize[self._cam_id] = 0.0  # Use fovy, not intrinsics.
        model.cam_fovy[self._cam_id] = self._vfov

    def _make_context(self, msaa_samples: int) -> None:
        """The MuJoCo render context on the shared GL context, reading depth 0 at far."""
        vis = self._model.vis
        self._handle.make_current()
        samples = int(vis.quality.offsamples)
        vis.quality.offsamples = msaa_samples
        try:
            self._ctx = mujoco.MjrContext(self._model, int(mujoco.mjtFontScale.mjFONTSCALE_50))
        finally:
            vis.quality.offsamples = samples
        mujoco.mjr_setBuffer(_OFFSCREEN, self._ctx)
        self._ctx.readDepthMap = int(mujoco.mjtDepthMap.mjDEPTH_ZEROFAR)

    # ------------------------------------------------------------------ properties

    @property
    def width(self) -> int:
        """Image width in pixels."""
        return self._width

    @property
    def height(self) -> int:
        """Image height in pixels."""
        return self._height

    @property
    def vfov(self) -> float:
        """Vertical field of view in degrees."""
        return self._vfov

    @property
    def hfov(self) -> float:
        """Horizontal field of view in degrees (from ``vfov`` and the aspect ratio)."""
        half = math.atan(math.tan(math.radians(self._vfov) / 2) * self._width / self._height)
        return math.degrees(2 * half)

    @property
    def camera_name(self) -> str:
        """Name of the model camera rendered."""
        return self._camera_name

    @property
    def camera_id(self) -> int:
        """Id of the model camera rendered."""
        return self._cam_id

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` has been called."""
        return self._closed

    @property
    def gl_session(self) -> gl.GLSession | None:
        """The shared GL session this camera renders through (None once closed)."""
        return None if self._closed or self._handle is None else self._handle.session

    def set_vfov(self, deg: float) -> None:
        """Sets the vertical field of view for later renders.

        Args:
            deg: Degrees, in (0, 180).

        Raises:
            InvalidArgumentError: If ``deg`` is out of range.
        """
        self._vfov = check_vfov(deg)

    # ------------------------------------------------------------------ rendering

    def render(
        self, data: mujoco.MjData, *, rgb: bool = True, depth: bool = True, bgr: bool = False
    ) -> Frame:
        """Renders the camera's view of ``data`` in one pass.

        The caller has already run kinematics (``mj_forward``/``mj_kinematics`` and
        ``mj_camlight``), so ``data.cam_xpos/cam_xmat`` are valid.

        Args:
            data: State to render.
            rgb: Whether to return colour.
            depth: Whether to return depth.
            bgr: Colour in BGR order (read so from OpenGL: no conversion afterwards).

        Returns:
            A :class:`Frame` with fresh arrays (fields not requested are None).

        Raises:
            InvalidArgumentError: If neither ``rgb`` nor ``depth`` is requested.
            RuntimeError: If the camera is closed.
        """
        if self._closed or self._ctx is None or self._handle is None:
            raise ClosedError("render() called on a closed Camera")
        if not (rgb or depth):
            raise InvalidArgumentError("render() needs rgb=True or depth=True (both are False)")
        self._handle.make_current()
        self._model.cam_fovy[self._cam_id] = self._vfov
        mujoco.mjv_updateScene(
            self._model, data, self._option, None, self._mjv_cam, _CATMASK, self._scene
        )
        mujoco.mjr_setBuffer(_OFFSCREEN, self._ctx)
        mujoco.mjr_render(self._rect, self._scene, self._ctx)
        if bgr:
            self._ctx.readPixelFormat = _GL_BGR
        try:
            mujoco.mjr_readPixels(
                self._rgb_raw if rgb else None,
                self._depth_raw if depth else None,
                self._rect,
                self._ctx,
            )
        finally:
            if bgr:
                self._ctx.readPixelFormat = _GL_RGB  # MuJoCo's, which other passes read
        # OpenGL rows run bottom-up; flipping while copying gives fresh, top-first arrays.
        rgb_out = self._rgb_raw[::-1].copy() if rgb else None
        depth_out = self._linear_depth() if depth else None
        return Frame(rgb=rgb_out, depth=depth_out)

    def upload_mesh(self, mesh_id: int) -> None:
        """Re-sends a mesh whose vertices changed in the model to this camera's GL context."""
        if self._closed or self._ctx is None or self._handle is None:
            raise ClosedError("upload_mesh() called on a closed Camera")
        self._handle.make_current()
        mujoco.mjr_uploadMesh(self._model, self._ctx, int(mesh_id))

    def render_geom_ids(
        self, data: mujoco.MjData, geom_groups: Sequence[int] | None = None
    ) -> np.ndarray:
        """Which model geom each pixel shows: ``(H, W)`` ``int32``, −1 where none.

        A second pass with MuJoCo's segmentation colouring (each drawn geom in a unique flat
        colour), decoded back to geom ids. Same preconditions as :meth:`render`.

        Args:
            data: State to render.
            geom_groups: Geom groups this pass draws (0–5); None draws the camera's own.
        """
        if self._closed or self._ctx is None or self._handle is None:
            raise ClosedError("render_geom_ids() called on a closed Camera")
        option = self._option
        chosen = check_groups(geom_groups)
        if chosen is not None:
            option = mujoco.MjvOption()
            option.geomgroup[:] = 0
            option.geomgroup[chosen] = 1
        self._handle.make_current()
        self._model.cam_fovy[self._cam_id] = self._vfov
        mujoco.mjv_updateScene(
            self._model, data, option, None, self._mjv_cam, _CATMASK, self._scene
        )
        flags = self._scene.flags
        segment, idcolor = (
            int(mujoco.mjtRndFlag.mjRND_SEGMENT),
            int(mujoco.mjtRndFlag.mjRND_IDCOLOR),
        )
        flags[segment] = flags[idcolor] = 1
        try:
            mujoco.mjr_setBuffer(_OFFSCREEN, self._ctx)
            mujoco.mjr_render(self._rect, self._scene, self._ctx)
            mujoco.mjr_readPixels(self._rgb_raw, None, self._rect, self._ctx)
        finally:
            flags[segment] = flags[idcolor] = 0
        rgb = self._rgb_raw[::-1].astype(np.int32)
        seg = rgb[..., 0] + (rgb[..., 1] << 8) + (rgb[..., 2] << 16) - 1  # scene geom index
        geom = int(mujoco.mjtObj.mjOBJ_GEOM)
        lookup = np.array(
            [g.objid if g.objtype == geom else -1 for g in self._scene.geoms[: self._scene.ngeom]]
            + [-1],
            dtype=np.int32,
        )
        return lookup[np.where((seg >= 0) & (seg < len(lookup) - 1), seg, -1)]

    def _linear_depth(self) -> np.ndarray:
        """Converts the reversed-z buffer (1 near, 0 far) to planar metres; 0 where empty."""
        cam = self._scene.camera[0]
        near, far = float(cam.frustum_near), float(cam.frustum_far)
        coef = self._depth_coef
        if coef is None or coef[0] != near or coef[1] != far:
            # Reversed-z perspective: raw = n (f / z - 1) / (f - n)  =>  z = d / (raw + c).
            c = np.float32(near / (far - near))
            d = np.float32(far * near / (far - near))
            coef = self._depth_coef = (near, far, c, d)
        raw = self._depth_raw[::-1]
        out = np.add(raw, coef[2], dtype=np.float32)
        np.divide(coef[3], out, out=out)
        # Empty pixels read 0: out is finite there, so a product is exact (and faster than a
        # masked write).
        np.multiply(out, raw > 0.0, out=out)
        return out

    # ------------------------------------------------------------------ lifetime

    def close(self) -> None:
        """Frees the render context and releases the shared GL context. Idempotent."""
        if self._closed:
            return
        self._closed = True
        ctx, self._ctx = self._ctx, None
        handle, self._handle = self._handle, None
        try:
            if ctx is not None and handle is not None:
                with contextlib.suppress(Exception):  # Context gone: its objects went with it.
                    handle.make_current()
                    ctx.free()
        finally:
            if handle is not None:
                gl.release(handle)

    def __enter__(self) -> Camera:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def __del__(self) -> None:
        with contextlib.suppress(Exception):
            self.close()

    def __repr__(self) -> str:
        state = "closed" if self._closed else "open"
        return (
            f"Camera({self._camera_name!r}, {self._width}x{self._height}, "
            f"vfov={self._vfov:g}, {state})"
        )
