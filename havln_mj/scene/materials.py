"""What a mesh file's materials say about a part's look: colour, finish and texture image.

Read from trimesh geometries (OBJ materials, glTF PBR materials or plain face colours) by
:func:`havln_mj.scene.mesh.load_mesh_parts`.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from havln_mj.errors import CorruptMeshError

if TYPE_CHECKING:
    import trimesh


def rgba_of(geom: trimesh.Trimesh) -> tuple[float, float, float, float]:
    """The geometry's RGBA in 0..1.

    Its material's base or diffuse colour, else its mean face colour, else light grey.
    """
    visual = geom.visual
    material = getattr(visual, "material", None)
    colour = None
    if material is not None:
        colour = getattr(material, "baseColorFactor", None)
        if colour is None:
            colour = getattr(material, "diffuse", None)
    elif getattr(visual, "kind", None) in ("face", "vertex"):
        colour = np.asarray(visual.face_colors, dtype=float).mean(axis=0)
    if colour is None:
        return (0.7, 0.7, 0.7, 1.0)
    c = np.asarray(colour, dtype=float).ravel()
    if c.max() > 1.0:
        c = c / 255.0
    if len(c) == 3:
        c = np.append(c, 1.0)
    return tuple(float(v) for v in c[:4])


def finish_of(geom: trimesh.Trimesh) -> tuple[float, float]:
    """(shine, emission) of a glTF material (both 0 for other materials)."""
    material = getattr(geom.visual, "material", None)
    roughness = getattr(material, "roughnessFactor", None)
    emissive = getattr(material, "emissiveFactor", None)
    shine = 0.0 if roughness is None else float(np.clip(1.0 - roughness, 0.0, 1.0))
    emission = 0.0 if emissive is None else float(np.clip(np.max(emissive), 0.0, 1.0))
    return shine, emission


def image_of(geom: trimesh.Trimesh) -> Any:
    """The material's colour image (a PIL image) when the geometry has one and UVs."""
    visual = geom.visual
    if getattr(visual, "kind", None) != "texture" or getattr(visual, "uv", None) is None:
        return None
    material = getattr(visual, "material", None)
    image = getattr(material, "image", None)
    if image is None:
        image = getattr(material, "baseColorTexture", None)
    return image


def image_array(image: Any, path: Path, max_size: int | None) -> np.ndarray:
    """A PIL image as an H×W×3 uint8 RGB (or H×W×4 RGBA) array, top row first.

    Images larger than ``max_size`` are shrunk by an integer factor to fit.
    """
    try:
        size = max(image.size)
        if max_size is not None and size > max_size:
            image = image.reduce(-(-size // max_size))
        mode = getattr(image, "mode", "RGB")
        if mode not in ("RGB", "RGBA"):
            image = image.convert("RGBA" if "A" in mode else "RGB")
        array = np.asarray(image, dtype=np.uint8)
    except Exception as exc:  # PIL raises many types for bad images
        raise CorruptMeshError(
            f"{path}: cannot read a texture image ({type(exc).__name__}: {exc})"
        ) from exc
    if array.ndim != 3 or array.shape[2] not in (3, 4) or min(array.shape[:2]) < 1:
        raise CorruptMeshError(
            f"{path}: texture image has shape {array.shape}, expected H×W×3 or H×W×4"
        )
    array.flags.writeable = False
    return array
