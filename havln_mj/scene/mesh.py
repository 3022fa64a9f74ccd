"""Visual meshes of scans: writing parts as glb, and reading glb/obj split into parts.

MuJoCo colours or textures a mesh geom as a whole, so a building's mesh is handled as parts,
one per material: vertices, triangles, an rgba colour and, for textured materials, one UV per
vertex and the texture image. A ``.glb`` written by :func:`write_glb` marks itself (glTF
scene extras ``{"havln_mj": {"parts": "node"}}``) so that it reads back one part per glTF
node, as written: procedural houses keep each object's pieces apart (for instance
segmentation) while sharing materials and images between them. Other files are split per
material.

Conventions of :class:`MeshPart`:

- ``vertices`` are in the z-up world frame (Matterport's frame: metres, +z up).
- ``uv`` follows the OBJ convention: ``(0, 0)`` is the bottom-left corner of the image and
  ``v`` grows upwards (glTF's top-left origin is converted on load).
- ``texture`` is an H×W×3 ``uint8`` RGB (or H×W×4 RGBA, for blended overlays) image stored
  top row first (as PIL and image files store it). :func:`havln_mj.sim.visual.add_visual_parts`
  converts to MuJoCo's convention.
- ``shine`` and ``emission`` travel through glTF as ``1 − roughnessFactor`` and
  ``emissiveFactor``; an alpha below 1 in ``rgba`` as ``alphaMode: BLEND``.

Up axis: no axis conversion is applied when reading glTF, so a ``.glb`` comes back in the
frame its vertices were written in. The meshes this project writes and the Matterport3D
meshes (raw ``.obj`` and habitat ``.glb``, which habitat-sim reads as "gravity −z") are all
z-up, the default ``up="z"``. A file exported y-up (glTF's own convention, e.g. by Blender)
is read with ``up="y"``, which maps ``(x, y, z) -> (x, -z, y)``: a +90° rotation about x that
takes the file's +y (up) to +z.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from havln_mj.cache import atomic_write_bytes
from havln_mj.errors import CorruptMeshError, InvalidArgumentError, MissingDataError
from havln_mj.scene.boxes import BoxSet
from havln_mj.scene.glb import Piece, first_alike, read_own_glb
from havln_mj.scene.materials import finish_of, image_array, image_of, rgba_of

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
        texture: H×W×3 uint8 RGB (or H×W×4 RGBA) image, top row first, or None. Parts
            sharing one material image share one array.
        shine: Gloss in [0, 1] (0: matt).
        emission: Self-lit share in [0, 1] (0: lit only by the scene's lights).
    """

    name: str
    vertices: np.ndarray  # (V, 3) float64
    faces: np.ndarray  # (F, 3) int32
    rgba: tuple[float, float, float, float]
    uv: np.ndarray | None = None  # (V, 2) float32
    texture: np.ndarray | None = None  # (H, W, 3 or 4) uint8
    shine: float = 0.0
    emission: float = 0.0

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


def _pil_image(texture: np.ndarray) -> Any:
    """A PIL image of a texture: JPEG-coded when opaque (far quicker to write than PNG)."""
    from PIL import Image

    image = Image.fromarray(texture)
    if texture.shape[2] == 4:
        return image
    buffer = io.BytesIO()
    image.save(buffer, format="JPEG", quality=92)
    return Image.open(buffer)


def _glb_material(part: MeshPart, name: str, images: dict[int, Any]) -> Any:
    import trimesh  # a large import: only when meshes are written

    colour = np.round(np.array(part.rgba) * 255).astype(np.uint8)
    extra: dict[str, Any] = {}
    if part.textured:
        assert part.texture is not None
        image = images.get(id(part.texture))
        if image is None:
            image = images[id(part.texture)] = _pil_image(part.texture)
        extra["baseColorTexture"] = image
    if part.rgba[3] < 1.0 or (part.texture is not None and part.texture.shape[2] == 4):
        extra["alphaMode"] = "BLEND"
    if part.emission > 0.0:
        extra["emissiveFactor"] = [part.emission] * 3
    return trimesh.visual.material.PBRMaterial(
        name=name,
        baseColorFactor=colour,
        metallicFactor=0.0,
        roughnessFactor=1.0 - part.shine,
        **extra,
    )


def write_glb(parts: list[MeshPart], path: Path) -> None:
    """Writes mesh parts as a binary glTF: one node per part, named after it.

    Parts with the same look (texture image, colour, shine, emission) share one glTF
    material, and every image is stored once: opaque ones as JPEG, with alpha as PNG. The
    file reads back into the same parts (up to the JPEG coding of the images).
    """
    import trimesh  # a large import: only when meshes are read or written

    scene = trimesh.Scene()
    scene.metadata["havln_mj"] = {"parts": "node"}
    images: dict[int, Any] = {}  # id(texture array) -> PIL image
    materials: dict[tuple, Any] = {}
    for part in parts:
        look = (id(part.texture) if part.textured else 0, part.rgba, part.shine, part.emission)
        material = materials.get(look)
        if material is None:
            material = materials[look] = _glb_material(part, f"m{len(materials)}", images)
        uv = part.uv if part.textured else None
        mesh = trimesh.Trimesh(
            part.vertices,
            part.faces,
            visual=trimesh.visual.TextureVisuals(uv=uv, material=material),
            process=False,
        )
        scene.add_geometry(mesh, geom_name=part.name, node_name=part.name)
    atomic_write_bytes(path, scene.export(file_type="glb"))


def load_mesh_parts(
    path: Path, *, up: str = "z", max_texture_size: int | None = None
) -> list[MeshPart]:
    """Reads a ``.glb`` / ``.gltf`` / ``.obj`` mesh as world-space parts.

    A file written by :func:`write_glb` gives one part per node, named after it (read by
    :func:`havln_mj.scene.glb.read_own_glb`, without trimesh); any other file one part per
    material. Textured materials (an OBJ ``map_Kd`` or a glTF base colour texture) give parts
    with per-vertex UVs and the image as an array; reading images needs Pillow. Each image is
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
    _check_arguments(path, up, max_texture_size)
    pieces = read_own_glb(path, max_texture_size) if path.suffix.lower() == ".glb" else None
    if pieces is None:
        pieces = _trimesh_pieces(path, max_texture_size)
    if up == "y":
        pieces = [p._replace(vertices=p.vertices @ _Y_UP_TO_Z_UP.T) for p in pieces]
    groups: dict[tuple[str, int], list[Piece]] = {}
    for piece in pieces:
        key = (piece.name, id(piece.texture) if piece.texture is not None else 0)
        groups.setdefault(key, []).append(piece)
    out = [_merged(name, group) for (name, _), group in groups.items()]
    if not out:
        raise CorruptMeshError(f"{path}: the mesh holds no triangles")
    for part in out:
        if not np.all(np.isfinite(part.vertices)):
            raise CorruptMeshError(f"{path}: part {part.name!r} has non-finite vertices")
        if part.uv is not None and not np.all(np.isfinite(part.uv)):
            raise CorruptMeshError(f"{path}: part {part.name!r} has non-finite UVs")
    return out


def _check_arguments(path: Path, up: str, max_texture_size: int | None) -> None:
    """Raises the errors :func:`load_mesh_parts` documents for its arguments."""
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


def _trimesh_pieces(path: Path, max_texture_size: int | None) -> list[Piece]:
    """A file's triangles in world space, one piece per node geometry, read by trimesh."""
    import trimesh  # a large import: only for meshes this package did not write

    try:
        scene = trimesh.load(path, force="scene", process=False)
    except Exception as exc:  # trimesh raises many types for bad files
        raise CorruptMeshError(f"{path}: cannot read mesh ({type(exc).__name__}: {exc})") from exc
    by_node = scene.metadata.get("havln_mj", {}).get("parts") == "node"
    images: dict[int, np.ndarray] = {}  # id(PIL image) -> array, so shared images convert once
    same_image: dict[tuple, np.ndarray] = {}
    pieces = []
    for node in scene.graph.nodes_geometry:
        transform, geom_name = scene.graph[node]
        geom = scene.geometry[geom_name]
        if not isinstance(geom, trimesh.Trimesh) or len(geom.faces) == 0:
            continue
        verts = trimesh.transformations.transform_points(geom.vertices, transform)
        material = getattr(geom.visual, "material", None)
        name = geom_name if by_node else getattr(material, "name", None) or geom_name
        image = image_of(geom)
        uv = None
        texture = None
        rgba = rgba_of(geom)
        if image is not None:
            uv = np.asarray(geom.visual.uv, dtype=np.float32)
            if uv.shape != (len(verts), 2):
                raise CorruptMeshError(
                    f"{path}: {name!r} has {len(uv)} texture coordinates for {len(verts)} vertices"
                )
            texture = images.get(id(image))
            if texture is None:
                texture = images[id(image)] = image_array(image, path, max_texture_size)
                if by_node:  # glTF materials sharing an image each get their own PIL copy
                    texture = images[id(image)] = first_alike(texture, same_image)
            if not isinstance(material, trimesh.visual.material.PBRMaterial):
                rgba = (1.0, 1.0, 1.0, rgba[3])  # an OBJ's Kd does not tint its map_Kd here
        shine, emission = finish_of(geom)
        pieces.append(
            Piece(name, verts, np.asarray(geom.faces), uv, texture, rgba, shine, emission)
        )
    return pieces


def _merged(name: str, pieces: list[Piece]) -> MeshPart:
    """One part from the pieces of one name and texture (the first piece's look)."""
    first = pieces[0]
    offsets = np.cumsum([0] + [len(p.vertices) for p in pieces[:-1]])
    verts = np.concatenate([p.vertices for p in pieces]).astype(float, copy=False)
    faces = np.concatenate([p.faces + o for p, o in zip(pieces, offsets, strict=True)])
    uv = None if first.texture is None else np.concatenate([p.uv for p in pieces])
    faces = faces.astype(np.int32, copy=False)
    return MeshPart(name, verts, faces, first.rgba, uv, first.texture, first.shine, first.emission)


def merge_parts(parts: list[MeshPart], name: str) -> MeshPart:
    """Parts that look alike (one texture, colour, shine, emission) as one part."""
    first = parts[0]
    offsets = np.cumsum([0] + [len(p.vertices) for p in parts[:-1]])
    return MeshPart(
        name,
        np.concatenate([p.vertices for p in parts]),
        np.concatenate([p.faces + o for p, o in zip(parts, offsets, strict=True)]).astype(np.int32),
        first.rgba,
        None if first.uv is None else np.concatenate([p.uv for p in parts]),
        first.texture,
        first.shine,
        first.emission,
    )


def merge_by_look(parts: list[MeshPart]) -> list[MeshPart]:
    """One part per distinct look (texture image, colour, shine, emission), in first order.

    A renderer pays per drawn geom, so a building is drawn fastest as few large parts; a
    merged part is named after its first part's material (the text after ``":"``).
    """
    groups: dict[tuple, list[MeshPart]] = {}
    for part in parts:
        look = (id(part.texture) if part.textured else 0, part.rgba, part.shine, part.emission)
        groups.setdefault(look, []).append(part)
    return [merge_parts(group, group[0].name.split(":", 1)[-1]) for group in groups.values()]


def parts_to_trimesh(parts: list[MeshPart]) -> trimesh.Trimesh:
    """All parts merged into one mesh (for collision decomposition and ray casts)."""
    import trimesh  # a large import: only when meshes are read or written

    offsets = np.cumsum([0] + [len(p.vertices) for p in parts[:-1]])
    verts = np.concatenate([p.vertices for p in parts])
    faces = np.concatenate([p.faces + o for p, o in zip(parts, offsets, strict=True)])
    return trimesh.Trimesh(verts, faces, process=False)
