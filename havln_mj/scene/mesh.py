"""Visual meshes of scans: writing box geometry as glb, and reading glb/obj split per material.

MuJoCo colours or textures a mesh geom as a whole, so a building's mesh is handled as parts,
one per material: vertices, triangles, an rgba colour and, for textured materials, one UV per
vertex and the texture image.

Conventions of :class:`MeshPart`:

- ``vertices`` are in the z-up world frame (Matterport's frame: metres, +z up).
- ``uv`` follows the OBJ convention: ``(0, 0)`` is the bottom-left corner of the image and
  ``v`` grows upwards. trimesh already converts glTF's top-left origin to this on load.
- ``texture`` is an H×W×3 ``uint8`` RGB image stored top row first (as PIL and image files
  store it). :func:`havln_mj.sim.visual.add_visual_parts` converts to MuJoCo's convention.

Up axis: trimesh applies no axis conversion when reading glTF, so a ``.glb`` comes back in the
frame its vertices were written in. The meshes this project writes and the Matterport3D
meshes (raw ``.obj`` and habitat ``.glb``, which habitat-sim reads as "gravity −z") are all
z-up, the default ``up="z"``. A file exported y-up (glTF's own convention, e.g. by Blender)
is read with ``up="y"``, which maps ``(x, y, z) -> (x, -z, y)``: a +90° rotation about x that
takes the file's +y (up) to +z.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from havln_mj.cache import atomic_write_bytes
from havln_mj.errors import CorruptMeshError, InvalidArgumentError, MissingDataError
from havln_mj.scene.boxes import BoxSet

if TYPE_CHECKING:
    import trimesh

# Corner order and the two triangles of each face, counter-clockwise seen from outside.
_CORNERS = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float)
_QUADS = np.array(
    [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
)


UP_AXES = ("z", "y")
"""Accepted ``up`` values of :func:`load_mesh_parts`."""

# y-up file -> z-up world: (x, y, z) -> (x, -z, y), a +90° rotation about x.
_Y_UP_TO_Z_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


@dataclass(frozen=True)
class MeshPart:
    """One material's triangles.

    Attributes:
        name: The material's name (not necessarily unique among a mesh's parts).
        vertices: (V, 3) float64 positions in the z-up world frame.
        faces: (F, 3) int32 vertex indices, counter-clockwise seen from outside.
        rgba: The material's colour, used when the part has no texture.
        uv: (V, 2) float32 texture coordinates, one per vertex (OBJ convention: origin at the
            image's bottom left), or None for an untextured part.
        texture: H×W×3 uint8 RGB image, top row first, or None. Parts sharing one material
            image share one array.
    """

    name: str
    vertices: np.ndarray  # (V, 3) float64
    faces: np.ndarray  # (F, 3) int32
    rgba: tuple[float, float, float, float]
    uv: np.ndarray | None = None  # (V, 2) float32
    texture: np.ndarray | None = None  # (H, W, 3) uint8

    @property
    def textured(self) -> bool:
        """True when the part has both UVs and a texture image."""
        return self.uv is not None and self.texture is not None


def boxes_to_triangles(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Triangles of boxes, 4 unshared vertices per face so normals stay flat.

    Returns:
        (vertices (24·N, 3), faces (12·N, 3)).
    """
    corners = lo[:, None, :] + _CORNERS[None] * (hi - lo)[:, None, :]  # (N, 8, 3)
    verts = corners[:, _QUADS.ravel()].reshape(-1, 3)  # 24 per box
    base = (np.arange(len(lo)) * 24)[:, None, None] + (np.arange(6) * 4)[None, :, None]
    tri = np.array([[0, 1, 2], [0, 2, 3]])
    faces = (base[:, :, None, :] + tri[None, None]).reshape(-1, 3)
    return verts, faces.astype(np.int32)


def boxes_to_parts(boxes: BoxSet) -> list[MeshPart]:
    """One mesh part per material of a box set, in first-appearance order."""
    parts = []
    for name in dict.fromkeys(boxes.material):
        sel = boxes.select(np.array([m == name for m in boxes.material]))
        verts, faces = boxes_to_triangles(sel.lo, sel.hi)
        parts.append(MeshPart(name, verts, faces, tuple(float(c) for c in sel.rgba[0])))
    return parts


def write_glb(parts: list[MeshPart], path: Path) -> None:
    """Writes mesh parts as a binary glTF, one mesh and one PBR material per part."""
    import trimesh  # a large import: only when meshes are read or written

    scene = trimesh.Scene()
    for part in parts:
        colour = np.round(np.array(part.rgba) * 255).astype(np.uint8)
        material = trimesh.visual.material.PBRMaterial(
            name=part.name, baseColorFactor=colour, metallicFactor=0.0, roughnessFactor=0.9
        )
        mesh = trimesh.Trimesh(
            part.vertices,
            part.faces,
            visual=trimesh.visual.TextureVisuals(material=material),
            process=False,
        )
        scene.add_geometry(mesh, geom_name=part.name, node_name=part.name)
    atomic_write_bytes(path, scene.export(file_type="glb"))


def _rgba_of(geom: trimesh.Trimesh) -> tuple[float, float, float, float]:
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


def _image_of(geom: trimesh.Trimesh) -> Any:
    """The material's colour image (a PIL image) when the geometry has one and UVs."""
    visual = geom.visual
    if getattr(visual, "kind", None) != "texture" or getattr(visual, "uv", None) is None:
        return None
    material = getattr(visual, "material", None)
    image = getattr(material, "image", None)
    if image is None:
        image = getattr(material, "baseColorTexture", None)
    return image


def _image_array(image: Any, path: Path, max_size: int | None) -> np.ndarray:
    """A PIL image as an H×W×3 uint8 RGB array (top row first), at most ``max_size`` wide/high."""
    try:
        size = max(image.size)
        if max_size is not None and size > max_size:
            image = image.reduce(-(-size // max_size))
        if getattr(image, "mode", "RGB") != "RGB":
            image = image.convert("RGB")
        array = np.asarray(image, dtype=np.uint8)
    except Exception as exc:  # PIL raises many types for bad images
        raise CorruptMeshError(
            f"{path}: cannot read a texture image ({type(exc).__name__}: {exc})"
        ) from exc
    if array.ndim != 3 or array.shape[2] != 3 or min(array.shape[:2]) < 1:
        raise CorruptMeshError(f"{path}: texture image has shape {array.shape}, expected H×W×3")
    array.flags.writeable = False
    return array


def load_mesh_parts(
    path: Path, *, up: str = "z", max_texture_size: int | None = None
) -> list[MeshPart]:
    """Reads a ``.glb`` / ``.gltf`` / ``.obj`` mesh as world-space parts, one per material.

    Textured materials (an OBJ ``map_Kd`` or a glTF base colour texture) give parts with
    per-vertex UVs and the image as an array; reading images needs Pillow. Each image is
    converted once, however many pieces of the file use it.

    Args:
        path: The mesh file (an OBJ finds its ``.mtl`` and textures next to it).
        up: The file's up axis: ``"z"`` (vertices already z-up, the default) or ``"y"``
            (y-up file, mapped to z-up by ``(x, y, z) -> (x, -z, y)``).
        max_texture_size: When given, larger images are shrunk by an integer factor (box
            filter) until neither side exceeds it: less memory in the model and on the GPU.

    Raises:
        InvalidArgumentError: ``up`` is not ``"z"`` or ``"y"``, or ``max_texture_size`` < 1.
        MissingDataError: The file does not exist.
        CorruptMeshError: The file or a texture cannot be parsed, or it holds no triangles.
    """
    import trimesh  # a large import: only when meshes are read or written

    if up not in UP_AXES:
        raise InvalidArgumentError(f"up must be one of {UP_AXES}, got {up!r}")
    if max_texture_size is not None and not (
        isinstance(max_texture_size, int) and max_texture_size >= 1
    ):
        raise InvalidArgumentError(
            f"max_texture_size must be a positive int or None, got {max_texture_size!r}"
        )
    if not path.is_file():
        raise MissingDataError(f"mesh not found: {path}")
    try:
        scene = trimesh.load(path, force="scene", process=False)
    except Exception as exc:  # trimesh raises many types for bad files
        raise CorruptMeshError(f"{path}: cannot read mesh ({type(exc).__name__}: {exc})") from exc
    images: dict[int, np.ndarray] = {}  # id(PIL image) -> array, so shared images convert once
    parts: dict[tuple[str, int], list] = {}
    for node in scene.graph.nodes_geometry:
        transform, geom_name = scene.graph[node]
        geom = scene.geometry[geom_name]
        if not isinstance(geom, trimesh.Trimesh) or len(geom.faces) == 0:
            continue
        verts = trimesh.transformations.transform_points(geom.vertices, transform)
        if up == "y":
            verts = verts @ _Y_UP_TO_Z_UP.T
        material = getattr(geom.visual, "material", None)
        name = getattr(material, "name", None) or geom_name
        image = _image_of(geom)
        uv = None
        texture = None
        if image is not None:
            uv = np.asarray(geom.visual.uv, dtype=np.float32)
            if uv.shape != (len(verts), 2):
                raise CorruptMeshError(
                    f"{path}: {name!r} has {len(uv)} texture coordinates for {len(verts)} vertices"
                )
            texture = images.get(id(image))
            if texture is None:
                texture = images[id(image)] = _image_array(image, path, max_texture_size)
        key = (name, id(texture) if texture is not None else 0)
        parts.setdefault(key, []).append((verts, np.asarray(geom.faces), uv, texture, geom))
    out = []
    for (name, _), chunks in parts.items():
        offsets = np.cumsum([0] + [len(c[0]) for c in chunks[:-1]])
        verts = np.concatenate([c[0] for c in chunks])
        faces = np.concatenate([c[1] + o for c, o in zip(chunks, offsets, strict=True)])
        texture = chunks[0][3]
        uv = None if texture is None else np.concatenate([c[2] for c in chunks])
        rgba = _rgba_of(chunks[0][4])
        verts = verts.astype(float, copy=False)
        out.append(MeshPart(name, verts, faces.astype(np.int32, copy=False), rgba, uv, texture))
    if not out:
        raise CorruptMeshError(f"{path}: the mesh holds no triangles")
    for part in out:
        if not np.all(np.isfinite(part.vertices)):
            raise CorruptMeshError(f"{path}: part {part.name!r} has non-finite vertices")
        if part.uv is not None and not np.all(np.isfinite(part.uv)):
            raise CorruptMeshError(f"{path}: part {part.name!r} has non-finite UVs")
    return out


def parts_to_trimesh(parts: list[MeshPart]) -> trimesh.Trimesh:
    """All parts merged into one mesh (for collision decomposition and ray casts)."""
    import trimesh  # a large import: only when meshes are read or written

    offsets = np.cumsum([0] + [len(p.vertices) for p in parts[:-1]])
    verts = np.concatenate([p.vertices for p in parts])
    faces = np.concatenate([p.faces + o for p, o in zip(parts, offsets, strict=True)])
    return trimesh.Trimesh(verts, faces, process=False)
