"""Visual meshes of scans: writing box geometry as glb, and reading glb/obj split per material.

MuJoCo colours or textures a mesh geom as a whole, so a building's mesh is handled as parts,
one per material: vertices, triangles, an rgba colour (and, for textured scans, UVs and an
image; see the Matterport loader).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from havln_mj.cache import atomic_write_bytes
from havln_mj.errors import CorruptMeshError, MissingDataError
from havln_mj.scene.boxes import BoxSet

# Corner order and the two triangles of each face, counter-clockwise seen from outside.
_CORNERS = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float)
_QUADS = np.array(
    [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
)


@dataclass(frozen=True)
class MeshPart:
    """One material's triangles."""

    name: str
    vertices: np.ndarray  # (V, 3) float64
    faces: np.ndarray  # (F, 3) int32
    rgba: tuple[float, float, float, float]


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


def load_mesh_parts(path: Path) -> list[MeshPart]:
    """Reads a ``.glb`` / ``.gltf`` / ``.obj`` mesh as world-space parts, one per material.

    Raises:
        MissingDataError: The file does not exist.
        CorruptMeshError: The file cannot be parsed or holds no triangles.
    """
    if not path.is_file():
        raise MissingDataError(f"mesh not found: {path}")
    try:
        scene = trimesh.load(path, force="scene", process=False)
    except Exception as exc:  # trimesh raises many types for bad files
        raise CorruptMeshError(f"{path}: cannot read mesh ({type(exc).__name__}: {exc})") from exc
    parts: dict[str, list] = {}
    for node in scene.graph.nodes_geometry:
        transform, geom_name = scene.graph[node]
        geom = scene.geometry[geom_name]
        if not isinstance(geom, trimesh.Trimesh) or len(geom.faces) == 0:
            continue
        verts = trimesh.transformations.transform_points(geom.vertices, transform)
        material = getattr(geom.visual, "material", None)
        name = getattr(material, "name", None) or geom_name
        parts.setdefault(name, []).append((verts, np.asarray(geom.faces), _rgba_of(geom)))
    out = []
    for name, chunks in parts.items():
        offsets = np.cumsum([0] + [len(v) for v, _, _ in chunks[:-1]])
        verts = np.concatenate([v for v, _, _ in chunks])
        faces = np.concatenate([f + o for (_, f, _), o in zip(chunks, offsets, strict=True)])
        out.append(MeshPart(name, verts.astype(float), faces.astype(np.int32), chunks[0][2]))
    if not out:
        raise CorruptMeshError(f"{path}: the mesh holds no triangles")
    for part in out:
        if not np.all(np.isfinite(part.vertices)):
            raise CorruptMeshError(f"{path}: part {part.name!r} has non-finite vertices")
    return out


def parts_to_trimesh(parts: list[MeshPart]) -> trimesh.Trimesh:
    """All parts merged into one mesh (for collision decomposition and ray casts)."""
    offsets = np.cumsum([0] + [len(p.vertices) for p in parts[:-1]])
    verts = np.concatenate([p.vertices for p in parts])
    faces = np.concatenate([p.faces + o for p, o in zip(parts, offsets, strict=True)])
    return trimesh.Trimesh(verts, faces, process=False)
