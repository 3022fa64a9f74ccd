"""360° equirectangular panoramas (RGB, depth, labels) at a viewpoint.

A panorama is rendered as six cube faces (:func:`havln_mj.render.cubemap.render_faces`) and
resampled: pixel (row r, column c) of an H × 2H panorama looks at

- heading ``heading + 2π ((c + 0.5) / 2H − 0.5)`` (MatterSim's: from +y, turning right),
  so the centre column looks along ``heading`` and the image reads left to right as a
  camera turning right would;
- elevation ``π/2 − π (r + 0.5) / H``: the top row looks up, the bottom row down.

Depth is the Euclidean distance from the viewpoint in metres (0 where nothing was hit), the
convention of panoramic depth, not a pinhole camera's planar depth. Colour is filtered
bilinearly from the faces, depth and labels are the nearest texel's.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.render.camera import Camera
from havln_mj.render.cubemap import CubeAtlas, lookup, render_faces, world_to_skybox
from havln_mj.render.labels import geom_labels, segmentation_groups


@dataclass(frozen=True)
class Panorama:
    """An equirectangular view (H × 2H, top row first).

    Attributes:
        rgb: ``uint8`` (H, 2H, 3).
        depth: ``float32`` (H, 2H), metres from the viewpoint, 0 where nothing was hit.
        semantic: ``uint8`` (H, 2H) classes, or None when labels were not asked for.
        instance: ``int32`` (H, 2H) instance ids, or None.
        heading: The heading of the centre column, radians.
    """

    rgb: np.ndarray
    depth: np.ndarray
    semantic: np.ndarray | None
    instance: np.ndarray | None
    heading: float


def panorama_directions(height: int, heading: float = 0.0) -> np.ndarray:
    """World directions ``(H, 2H, 3)`` of an equirectangular panorama's pixel centres."""
    width = 2 * height
    yaw = heading + 2.0 * np.pi * ((np.arange(width) + 0.5) / width - 0.5)
    pitch = np.pi / 2 - np.pi * (np.arange(height) + 0.5) / height
    yaw, pitch = np.meshgrid(yaw, pitch)
    return np.stack(
        [np.sin(yaw) * np.cos(pitch), np.cos(yaw) * np.cos(pitch), np.sin(pitch)], axis=-1
    )


def render_panorama(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    camera: Camera,
    position: np.ndarray,
    *,
    height: int = 256,
    heading: float = 0.0,
    labels: bool = True,
) -> Panorama:
    """Renders a 360° panorama from ``position`` with ``camera`` (square, any field of view).

    The camera's face size sets the detail: about ``height / 2`` pixels matches the
    panorama's resolution at the faces' centres. ``data`` must hold the posed state
    (kinematics done); it is left as it was.

    Raises:
        InvalidArgumentError: ``height`` is not a positive int, or the camera is not square.
    """
    if isinstance(height, bool) or not isinstance(height, int) or height < 1:
        raise InvalidArgumentError(f"panorama height must be a positive int, got {height!r}")
    groups = segmentation_groups(model) if labels else None
    faces = render_faces(model, data, camera, np.asarray(position, float), None, groups)
    where = lookup(world_to_skybox(panorama_directions(height, heading), np.eye(3)))
    semantic = instance = None
    if faces.geom_ids is not None:
        ids = np.rint(CubeAtlas(faces.geom_ids.astype(np.float32)).sample(*where, False)).astype(
            int
        )
        sem, inst = geom_labels(model)
        hit = ids >= 0
        semantic = np.where(hit, sem[np.maximum(ids, 0)], 0).astype(np.uint8)
        instance = np.where(hit, inst[np.maximum(ids, 0)], 0).astype(np.int32)
    return Panorama(
        CubeAtlas(faces.rgb).sample(*where, linear=True),
        CubeAtlas(faces.depth).sample(*where, linear=False),
        semantic,
        instance,
        float(heading),
    )
