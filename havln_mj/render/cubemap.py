"""Cube maps in Matterport's skybox convention: lookup, sampling and rendering of the faces.

Which face and texel a direction falls on, reading faces along directions, and rendering
the six faces of a viewpoint with MuJoCo.

Facts from Matterport3DSimulator (``NavGraph.cpp``, ``MatterSim.cpp``, its shaders):

- A panorama's skybox is six square faces, files ``<pano>_skybox<k>_sami.jpg`` (k = 0..5,
  1024²), which MatterSim's scripts shrink to 512² and put side by side in
  ``<pano>_skybox_small.jpg`` (face k in columns ``k·S .. (k+1)·S``).
- MatterSim uploads them to an OpenGL cube map, image rows top first: ``+X`` ← face 2,
  ``-X`` ← face 4, ``+Y`` ← face 0, ``-Y`` ← face 5, ``+Z`` ← face 1, ``-Z`` ← face 3; and
  samples it with the position on a cube drawn around the camera, in the cube's own frame:
  the skybox frame, which the connectivity ``pose`` rotation ``R`` carries to the world.
  OpenGL picks the face by the largest component and reads ``s, t`` from the other two
  (:data:`GL_FACES`); RGB is filtered bilinearly, depth nearest, both clamped to the face.
- Its views are physically right (heading 0 looks along world +y and turns right, up is up,
  images upright), and the cube map's faces are mirrored like every OpenGL cube map: the
  texel at skybox direction ``d`` shows the world direction ``-R d``. (Checked against the
  literal MatterSim pipeline in the tests.)

So a world direction ``w`` reads the texel at skybox direction ``-Rᵀ w``.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.render.camera import Camera

# OpenGL cube map faces: (axis, sign) -> (file face, (sc axis, sc sign), (tc axis, tc sign)).
GL_FACES = {
    (0, +1): (2, (2, -1), (1, -1)),
    (0, -1): (4, (2, +1), (1, -1)),
    (1, +1): (0, (0, +1), (2, +1)),
    (1, -1): (5, (0, +1), (2, -1)),
    (2, +1): (1, (0, +1), (1, -1)),
    (2, -1): (3, (0, -1), (1, -1)),
}
"""OpenGL's cube map rule with MatterSim's face order.

For the largest component ``ma`` of a direction along ``axis`` with ``sign``: the file face,
and ``s = (sc/|ma| + 1)/2``, ``t = (tc/|ma| + 1)/2`` where ``sc``, ``tc`` are the given
components times their signs."""


def lookup(directions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The file face (0..5) and ``(s, t)`` in [0, 1] of skybox-frame directions ``(..., 3)``.

    ``s`` runs along a face image's columns, ``t`` down its rows (row 0 at ``t = 0``). This
    is :data:`GL_FACES` written out (ties go to x, then y, like ``argmax``).
    """
    d = np.asarray(directions, dtype=np.float32)
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    ax, ay, az = np.abs(x), np.abs(y), np.abs(z)
    on_x = (ax >= ay) & (ax >= az)
    on_y = ~on_x & (ay >= az)
    ma = np.where(on_x, ax, np.where(on_y, ay, az))
    sc = np.where(on_x, -np.sign(x) * z, np.where(on_y, x, np.sign(z) * x))
    tc = np.where(on_y, np.sign(y) * z, -y)
    face = np.where(
        on_x, np.where(x > 0, 2, 4), np.where(on_y, np.where(y > 0, 0, 5), np.where(z > 0, 1, 3))
    )
    half = 0.5 / ma
    return face, sc * half + 0.5, tc * half + 0.5


class CubeAtlas:
    """Six faces ``(6, S, S[, C])`` stacked, each with a one-texel border copied from its edges.

    One ``cv2.remap`` then samples them as OpenGL samples a cube map: bilinearly between
    texel centres or from the nearest texel, clamped to each face's edge.

    Channels: 1-4 of ``uint8``, ``uint16`` or ``float32`` (labels and ids as ``float32``).
    """

    def __init__(self, faces: np.ndarray) -> None:
        self.size = faces.shape[1]
        self.dtype = faces.dtype
        padded = np.pad(faces, [(0, 0), (1, 1), (1, 1)] + [(0, 0)] * (faces.ndim - 3), mode="edge")
        self.atlas = np.ascontiguousarray(padded.reshape(6 * (self.size + 2), *padded.shape[2:]))

    def sample(self, face: np.ndarray, s: np.ndarray, t: np.ndarray, linear: bool) -> np.ndarray:
        """Reads the faces at :func:`lookup` coordinates."""
        import cv2

        n = self.size
        map_x = (s * n + 0.5).astype(np.float32)  # + 1 for the border, - 0.5 to texel centres
        map_y = (t * n + 0.5 + face * (n + 2)).astype(np.float32)
        if not linear:  # texel floor(s·n) has its centre at floor(s·n) + 1 in the atlas
            map_x, map_y = np.floor(map_x + 0.5), np.floor(map_y + 0.5)
        flag = cv2.INTER_LINEAR if linear else cv2.INTER_NEAREST
        return cv2.remap(self.atlas, map_x, map_y, flag, borderMode=cv2.BORDER_REPLICATE)


def sample(faces: np.ndarray, directions: np.ndarray, linear: bool = True) -> np.ndarray:
    """Reads cube faces ``(6, S, S[, C])`` along skybox-frame directions ``(..., 3)``.

    ``linear`` filters bilinearly between texel centres (OpenGL's ``GL_LINEAR``), otherwise
    takes the nearest texel (``GL_NEAREST``); both clamp to the face's edge. Integer labels
    are read through ``float32``, exact below 2²⁴.
    """
    integer = faces.dtype.kind in "iu" and faces.dtype not in (np.uint8, np.uint16)
    atlas = CubeAtlas(faces.astype(np.float32) if integer else faces)
    out = atlas.sample(*lookup(directions), linear=linear)
    return np.rint(out).astype(faces.dtype) if integer else out


def world_to_skybox(directions: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """Skybox-frame directions ``-Rᵀ w`` of world directions ``w`` (see the module docstring)."""
    return -np.asarray(directions) @ np.asarray(rotation, dtype=np.float32)


def camera_rays(xmat: np.ndarray, width: int, height: int, vfov_deg: float) -> np.ndarray:
    """World directions ``(H, W, 3)`` through the pixel centres of a pinhole camera.

    ``xmat`` is the camera-to-world rotation of a MuJoCo camera (columns: right, up, back);
    row 0 is the top of the image, column 0 its left. The z component along the view axis
    is 1, so a distance along a ray is a planar depth.
    """
    x, y = _pixel_tangents(width, height, vfov_deg)
    cam = np.stack(np.broadcast_arrays(x[None, :], y[:, None], np.float32(-1.0)), axis=-1)
    return cam @ np.asarray(xmat, dtype=np.float32).reshape(3, 3).T


def _pixel_tangents(width: int, height: int, vfov_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """Tangents of the pixel centres' angles right of and above the view axis."""
    t = np.tan(np.radians(vfov_deg) / 2.0)
    x = (2.0 * (np.arange(width) + 0.5) / width - 1.0) * t * width / height
    y = (1.0 - 2.0 * (np.arange(height) + 0.5) / height) * t
    return x.astype(np.float32), y.astype(np.float32)


def ray_lengths(width: int, height: int, vfov_deg: float) -> np.ndarray:
    """Lengths ``(H, W)`` of :func:`camera_rays` (distance / planar depth of each pixel)."""
    x, y = _pixel_tangents(width, height, vfov_deg)
    return np.sqrt(1.0 + x[None, :] ** 2 + y[:, None] ** 2)


def heading_xmat(heading: float, elevation: float) -> np.ndarray:
    """The camera-to-world rotation of a view at MatterSim's ``heading`` and ``elevation``.

    Heading 0 looks along +y and grows turning right (toward +x); elevation is up-positive.
    """
    forward = np.array(
        [
            np.sin(heading) * np.cos(elevation),
            np.cos(heading) * np.cos(elevation),
            np.sin(elevation),
        ]
    )
    right = np.array([np.cos(heading), -np.sin(heading), 0.0])
    up = np.cross(right, forward)
    return np.column_stack([right, up, -forward])


def face_xmat(face: int, rotation: np.ndarray) -> np.ndarray:
    """Camera-to-world rotation of a 90° square camera whose image is skybox file face ``face``.

    Pixel (row i, column j) of that camera looks along the world direction ``-R d`` of the
    face's texel (i, j) at skybox direction ``d``.
    """
    for (axis, sign), (k, (sa, ss), (ta, ts)) in GL_FACES.items():
        if k != face:
            continue
        basis = np.zeros((3, 3))  # skybox direction = basis @ (sc, tc, 1)
        basis[sa, 0], basis[ta, 1], basis[axis, 2] = ss, ts, sign
        # MuJoCo camera coordinates of texel (s, t): (sc, -tc, -1) = flip @ (sc, tc, 1).
        flip = np.diag([1.0, -1.0, -1.0])
        return -np.asarray(rotation, dtype=np.float64) @ basis @ flip
    raise InvalidArgumentError(f"skybox face must be 0..5, got {face!r}")


@dataclass(frozen=True)
class CubeFaces:
    """Six rendered faces in Matterport's skybox layout (file face order 0..5).

    Attributes:
        rgb: (6, S, S, 3) ``uint8``.
        depth: (6, S, S) ``float32`` Euclidean distance from the centre in metres, 0 where
            nothing was hit (the skybox depth convention, not a camera's planar depth).
        geom_ids: (6, S, S) ``int32`` model geom per texel (-1 none), or None.
    """

    rgb: np.ndarray
    depth: np.ndarray
    geom_ids: np.ndarray | None


def render_faces(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    camera: Camera,
    position: np.ndarray,
    rotation: np.ndarray | None = None,
    geom_groups: tuple[int, ...] | None = None,
) -> CubeFaces:
    """Renders the six skybox faces seen from ``position`` (skybox frame ``rotation``).

    ``camera`` must be square; its field of view is set to 90° for the faces and restored
    after. The model camera's pose in ``data`` is overridden for the renders and restored, so
    the caller's state is unchanged. ``geom_groups`` asks for a geom-id pass per face too
    (e.g. :func:`havln_mj.render.labels.segmentation_groups`).

    Raises:
        InvalidArgumentError: The camera is not square.
    """
    if camera.width != camera.height:
        raise InvalidArgumentError(
            f"cube faces need a square camera, got {camera.width}x{camera.height}"
        )
    rotation = np.eye(3) if rotation is None else np.asarray(rotation, dtype=np.float64)
    cam_id, vfov = camera.camera_id, camera.vfov
    saved = data.cam_xpos[cam_id].copy(), data.cam_xmat[cam_id].copy()
    size = camera.width
    rgb = np.empty((6, size, size, 3), np.uint8)
    depth = np.empty((6, size, size), np.float32)
    ids = np.empty((6, size, size), np.int32) if geom_groups is not None else None
    # Planar depth to distance: the ray through texel (s, t) has length sqrt(1 + sc² + tc²).
    c = 2.0 * (np.arange(size) + 0.5) / size - 1.0
    stretch = np.sqrt(1.0 + c[None, :] ** 2 + c[:, None] ** 2).astype(np.float32)
    camera.set_vfov(90.0)
    try:
        for k in range(6):
            data.cam_xpos[cam_id] = position
            data.cam_xmat[cam_id] = face_xmat(k, rotation).ravel()
            frame = camera.render(data)
            rgb[k], depth[k] = frame.rgb, frame.depth * stretch
            if ids is not None:
                ids[k] = camera.render_geom_ids(data, geom_groups=geom_groups)
    finally:
        camera.set_vfov(vfov)
        data.cam_xpos[cam_id], data.cam_xmat[cam_id] = saved
    return CubeFaces(rgb, depth, ids)
