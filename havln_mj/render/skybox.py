"""Skybox mode: a viewpoint's Matterport3D photographs as MatterSim renders them, plus people.

The people MuJoCo draws are composited on top.

Users who hold Matterport3D's ``matterport_skybox_images`` get, at any heading and elevation,
the image MatterSim would give (same pinhole camera, vertical field of view, upright rows
top first, heading from +y turning right; see :mod:`havln_mj.render.cubemap` for the cube
map facts), so features computed on MatterSim images stay valid. People come from a MuJoCo
render of the same camera: a pixel shows a person where the person's geom is what the
segmentation pass sees there, i.e. where the person is nearer than the scan's mesh (its
label geoms, or its visual mesh when it has none), HA3D's depth test with the mesh's depth.

Files, per viewpoint ``<vp>`` in ``<scan>/matterport_skybox_images/``:

- ``<vp>_skybox_small.jpg``: MatterSim's input, six 512² faces side by side (preferred);
- else ``<vp>_skybox<k>_sami.jpg``, k = 0..5: the release's 1024² faces, shrunk to
  ``face_size`` (512 by default, as MatterSim's ``downsize_skybox.py`` does: area filter);
- optional ``<vp>_skybox_depth_small.png``: 16-bit Euclidean depth, 0.25 mm per unit, six
  faces side by side (MatterSim's ``depth_to_skybox.py``).

Colour is returned RGB (MatterSim hands out BGR) and depth as planar metres.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import mujoco
import numpy as np

from havln_mj import groups
from havln_mj.errors import InvalidArgumentError, MissingDataError
from havln_mj.render.camera import Camera
from havln_mj.render.cubemap import (
    CubeAtlas,
    camera_rays,
    heading_xmat,
    lookup,
    ray_lengths,
    world_to_skybox,
)
from havln_mj.render.labels import segmentation_groups
from havln_mj.scene.matterport.layout import skybox_folders

log = logging.getLogger(__name__)

DEPTH_UNITS_PER_M = 4000.0  # Matterport depth: 0.25 mm per unit


@dataclass(frozen=True)
class Skybox:
    """The six faces of one viewpoint, file order 0..5.

    Attributes:
        rgb: (6, S, S, 3) ``uint8`` RGB, rows top first.
        depth: (6, S, S) ``float32`` Euclidean metres (0: no reading), or None.
    """

    rgb: np.ndarray
    depth: np.ndarray | None

    @cached_property
    def rgb_atlas(self) -> CubeAtlas:
        """The colour faces ready for sampling."""
        return CubeAtlas(self.rgb)

    @cached_property
    def depth_atlas(self) -> CubeAtlas | None:
        """The depth faces ready for sampling (None without depth)."""
        return None if self.depth is None else CubeAtlas(self.depth)


@dataclass(frozen=True)
class SkyboxFrame:
    """A skybox view with people composited: RGB, planar depth (metres), person pixels."""

    rgb: np.ndarray
    depth: np.ndarray
    people: np.ndarray


def _read(path: Path, flags: int) -> np.ndarray:
    import cv2

    image = cv2.imread(str(path), flags)
    if image is None:
        raise MissingDataError(f"cannot read skybox image {path}")
    return image


def _strip(image: np.ndarray, path: Path) -> np.ndarray:
    """Six square faces side by side -> (6, S, S, ...)."""
    height, width = image.shape[:2]
    if width != 6 * height:
        raise MissingDataError(
            f"{path}: expected six square faces side by side, got {width}x{height}"
        )
    return np.stack([image[:, k * height : (k + 1) * height] for k in range(6)])


def skybox_files(folder: Path, viewpoint: str) -> dict[str, Path | list[Path]]:
    """The files a viewpoint's skybox is read from, found or not."""
    return {
        "small": folder / f"{viewpoint}_skybox_small.jpg",
        "faces": [folder / f"{viewpoint}_skybox{k}_sami.jpg" for k in range(6)],
        "depth": folder / f"{viewpoint}_skybox_depth_small.png",
    }


def load_skybox(folder: Path | str, viewpoint: str, face_size: int = 512) -> Skybox:
    """Reads a viewpoint's skybox from a ``matterport_skybox_images`` folder.

    Raises:
        MissingDataError: Neither ``<vp>_skybox_small.jpg`` nor all six
            ``<vp>_skybox<k>_sami.jpg`` exist; the message names the files looked for.
    """
    import cv2

    files = skybox_files(Path(folder), viewpoint)
    small, faces = files["small"], files["faces"]
    if small.is_file():
        rgb = _strip(_read(small, cv2.IMREAD_COLOR), small)
    elif all(f.is_file() for f in faces):
        size = (face_size, face_size)
        rgb = np.stack(
            [
                cv2.resize(_read(f, cv2.IMREAD_COLOR), size, interpolation=cv2.INTER_AREA)
                for f in faces
            ]
        )
    else:
        missing = [str(f) for f in faces if not f.is_file()]
        raise MissingDataError(
            f"skybox of viewpoint {viewpoint!r} not found: no {small} and missing "
            f"{', '.join(missing)}"
        )
    depth = None
    if files["depth"].is_file():
        raw = _strip(_read(files["depth"], cv2.IMREAD_ANYDEPTH), files["depth"])
        depth = (raw.astype(np.float32) / DEPTH_UNITS_PER_M).astype(np.float32)
    return Skybox(np.ascontiguousarray(rgb[..., ::-1]), depth)


def find_skybox_folder(scan_id: str, root: Path | str) -> Path:
    """A scan's ``matterport_skybox_images`` folder under a Matterport3D root.

    Raises:
        MissingDataError: No candidate folder exists; the message lists them.
    """
    candidates = skybox_folders(scan_id, root)
    for folder in candidates:
        if folder.is_dir():
            return folder
    raise MissingDataError(
        f"skybox images of scan {scan_id!r} not found; looked for "
        + ", ".join(str(c) for c in candidates)
        + " (the matterport_skybox_images download of Matterport3D, unzipped)"
    )


def skybox_view(
    skybox: Skybox,
    rotation: np.ndarray,
    heading: float,
    elevation: float,
    width: int,
    height: int,
    vfov_deg: float,
) -> tuple[np.ndarray, np.ndarray | None]:
    """MatterSim's view of a skybox: RGB ``(H, W, 3)`` and planar depth in metres (or None).

    Args:
        skybox: The viewpoint's faces.
        rotation: The skybox-to-world rotation (the connectivity ``pose``'s upper 3×3).
        heading: Radians from +y, turning right.
        elevation: Radians, up positive.
        width: Image width in pixels.
        height: Image height in pixels.
        vfov_deg: Vertical field of view in degrees.
    """
    if width < 1 or height < 1 or not 0.0 < vfov_deg < 180.0:
        raise InvalidArgumentError(
            "need width, height >= 1 and vfov in (0, 180) degrees; "
            f"got {width}, {height}, {vfov_deg}"
        )
    return _sample_view(skybox, rotation, heading_xmat(heading, elevation), width, height, vfov_deg)


def _sample_view(
    skybox: Skybox, rotation: np.ndarray, xmat: np.ndarray, width: int, height: int, vfov: float
) -> tuple[np.ndarray, np.ndarray | None]:
    """The skybox through a pinhole camera of orientation ``xmat``: RGB and planar depth."""
    where = lookup(world_to_skybox(camera_rays(xmat, width, height, vfov), rotation))
    rgb = skybox.rgb_atlas.sample(*where, linear=True)
    if skybox.depth_atlas is None:
        return rgb, None
    # Euclidean to planar depth.
    return rgb, skybox.depth_atlas.sample(*where, linear=False) / ray_lengths(width, height, vfov)


def composite(
    background: np.ndarray,
    background_depth: np.ndarray | None,
    rgb: np.ndarray,
    depth: np.ndarray,
    people: np.ndarray,
) -> SkyboxFrame:
    """Puts the ``people`` pixels of a rendered frame over a background view."""
    mask = np.asarray(people, bool)
    out_depth = depth if background_depth is None else np.where(mask, depth, background_depth)
    return SkyboxFrame(
        np.where(mask[..., None], rgb, background).astype(np.uint8),
        out_depth.astype(np.float32),
        mask,
    )


def render_skybox_frame(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    camera: Camera,
    skybox: Skybox,
    rotation: np.ndarray,
) -> SkyboxFrame:
    """The skybox seen through ``camera``'s pose, with MuJoCo's people on top.

    The camera must stand at the skybox's viewpoint (the connectivity position); ``data``
    holds the posed state (kinematics done, people posed), as for ``Camera.render``.
    """
    frame = camera.render(data)
    ids = camera.render_geom_ids(data, geom_groups=segmentation_groups(model))
    people = (ids >= 0) & (model.geom_group[np.maximum(ids, 0)] == groups.HUMANS)
    xmat = data.cam_xmat[camera.camera_id]
    background, background_depth = _sample_view(
        skybox, rotation, xmat, camera.width, camera.height, camera.vfov
    )
    assert frame.rgb is not None and frame.depth is not None
    return composite(background, background_depth, frame.rgb, frame.depth, people)


class SkyboxSource:
    """A scan's skyboxes, loaded on demand (a few kept), or None where the files are missing.

    A missing skybox is logged once per viewpoint with the files looked for; the caller then
    renders the mesh instead.
    """

    def __init__(self, scan_id: str, root: Path | str, face_size: int = 512, keep: int = 8):
        self.folder = find_skybox_folder(scan_id, root)
        self._face_size, self._keep = face_size, keep
        self._loaded: dict[str, Skybox] = {}
        self._missing: set[str] = set()

    def get(self, viewpoint: str) -> Skybox | None:
        """The viewpoint's skybox, or None (logged) when its files are missing."""
        if viewpoint in self._loaded:
            return self._loaded[viewpoint]
        if viewpoint in self._missing:
            return None
        try:
            skybox = load_skybox(self.folder, viewpoint, self._face_size)
        except MissingDataError as exc:
            log.warning("%s; rendering the mesh instead", exc)
            self._missing.add(viewpoint)
            return None
        if len(self._loaded) >= self._keep:
            self._loaded.pop(next(iter(self._loaded)))
        self._loaded[viewpoint] = skybox
        return skybox
