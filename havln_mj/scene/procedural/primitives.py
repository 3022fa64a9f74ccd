"""Triangle meshes of primitive solids, with texture coordinates in metres.

Every builder returns a :class:`Solid`: vertices (V, 3), counter-clockwise faces (F, 3) seen
from outside, and one (u, v) per vertex in metres along the surface, ``v`` up on vertical
faces (the material divides them by its texture's repeat size). Boxes keep four vertices per
face so their edges shade sharp; rounded boxes, cylinders and ellipsoids share vertices so
they shade smooth.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from havln_mj.scene.mesh import boxes_to_triangles


@dataclass(frozen=True)
class Solid:
    """Triangles of one primitive."""

    vertices: np.ndarray  # (V, 3)
    faces: np.ndarray  # (F, 3) int32
    uv: np.ndarray  # (V, 2) metres

    def moved(self, rotation: np.ndarray, offset: np.ndarray) -> Solid:
        """The solid turned by ``rotation`` (3×3) about the origin, then shifted by ``offset``."""
        return Solid(self.vertices @ rotation.T + offset, self.faces, self.uv)


def merge(solids: list[Solid]) -> Solid:
    """One solid holding all of ``solids``."""
    offsets = np.cumsum([0] + [len(s.vertices) for s in solids[:-1]])
    return Solid(
        np.concatenate([s.vertices for s in solids]),
        np.concatenate([s.faces + o for s, o in zip(solids, offsets, strict=True)]).astype(
            np.int32
        ),
        np.concatenate([s.uv for s in solids]),
    )


def box(
    lo: np.ndarray | list, hi: np.ndarray | list, bottom: bool = True, top: bool = True
) -> Solid:
    """An axis-aligned box from corner ``lo`` to corner ``hi``, sharp edges, box-mapped UVs.

    ``bottom`` / ``top`` False leave out the face at ``lo[2]`` / ``hi[2]`` (a wall's faces
    against the floor and the ceiling: hidden, and they would flicker against them).
    """
    lo, hi = np.asarray(lo, float)[None], np.asarray(hi, float)[None]
    verts, faces = boxes_to_triangles(lo, hi)
    # Faces come in the order -z, +z, -y, +y, -x, +x (four vertices each); the texture runs
    # along the face's horizontal direction with v up (z) on walls.
    u_axis = np.repeat([0, 0, 0, 0, 1, 1], 4)
    v_axis = np.repeat([1, 1, 2, 2, 2, 2], 4)
    flip = np.repeat([1.0, 1.0, 1.0, -1.0, -1.0, 1.0], 4)  # reads left to right from outside
    rows = np.arange(24)
    uv = np.column_stack([verts[rows, u_axis] * flip, verts[rows, v_axis]])
    keep = np.array([bottom, top, True, True, True, True]).repeat(2)
    return Solid(verts, faces[keep], uv)


def _ring_faces(n_rings: int, n_seg: int, start: int = 0) -> np.ndarray:
    """Quads between consecutive rings of ``n_seg + 1`` vertices (the seam is duplicated)."""
    i, j = np.meshgrid(np.arange(n_rings - 1), np.arange(n_seg), indexing="ij")
    a = start + i * (n_seg + 1) + j
    b, c, d = a + 1, a + n_seg + 2, a + n_seg + 1
    return np.concatenate([np.stack([a, b, c], -1), np.stack([a, c, d], -1)]).reshape(-1, 3)


def lathe(profile: np.ndarray, segments: int = 12, caps: bool = True) -> Solid:
    """A solid of revolution about the z axis from a (radius, z) profile, bottom to top.

    With ``caps`` the first and last rings are closed by flat discs.
    """
    profile = np.asarray(profile, float)
    theta = np.linspace(0.0, 2 * np.pi, segments + 1)
    r, z = profile[:, :1], profile[:, 1:]
    verts = np.stack(
        [r * np.cos(theta), r * np.sin(theta), np.broadcast_to(z, (len(profile), segments + 1))],
        -1,
    ).reshape(-1, 3)
    # Arc length around at the widest ring and along the profile.
    along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(profile, axis=0).T))])
    uv = np.stack(
        np.broadcast_arrays(theta[None] * max(r.max(), 1e-3), along[:, None]), -1
    ).reshape(-1, 2)
    faces = [_ring_faces(len(profile), segments)]
    parts = [Solid(verts, np.concatenate(faces).astype(np.int32), uv)]
    if caps:
        for row, up in ((0, False), (len(profile) - 1, True)):
            if profile[row, 0] <= 1e-9:
                continue
            ring = verts[row * (segments + 1) : (row + 1) * (segments + 1) - 1]
            centre = np.array([[0.0, 0.0, profile[row, 1]]])
            k = np.arange(segments)
            tri = np.column_stack([np.zeros(segments), 1 + k, 1 + (k + 1) % segments])
            if not up:
                tri = tri[:, [0, 2, 1]]
            pts = np.concatenate([centre, ring])
            parts.append(Solid(pts, tri.astype(np.int32), pts[:, :2].copy()))
    return merge(parts)


def cylinder(radius: float, z0: float, z1: float, segments: int = 8) -> Solid:
    """A closed vertical cylinder on the z axis from height ``z0`` to ``z1``."""
    return lathe(np.array([[radius, z0], [radius, z1]]), segments)


def frustum(r0: float, r1: float, z0: float, z1: float, segments: int = 10) -> Solid:
    """A closed truncated cone: radius ``r0`` at ``z0``, ``r1`` at ``z1``."""
    return lathe(np.array([[r0, z0], [r1, z1]]), segments)


def ellipsoid(radii: np.ndarray | list, segments: int = 10, rings: int = 6) -> Solid:
    """An ellipsoid centred at the origin."""
    a, b, c = np.asarray(radii, float)
    phi = np.linspace(-np.pi / 2, np.pi / 2, rings)
    profile = np.column_stack([np.cos(phi), np.sin(phi)])
    unit = lathe(profile, segments, caps=False)
    return Solid(unit.vertices * [a, b, c], unit.faces, unit.uv * [max(a, b), c])


def rounded_box(lo: np.ndarray | list, hi: np.ndarray | list, radius: float, n: int = 2) -> Solid:
    """A box with edges and corners rounded by ``radius`` (cushions, mattresses, appliances).

    Built from a cube whose faces are ``n`` × ``n`` grids, each vertex pulled onto the rounded
    surface; vertices are shared, so the solid shades smooth.
    """
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    half, centre = (hi - lo) / 2, (hi + lo) / 2
    radius = float(min(radius, *half))
    t = np.linspace(-1.0, 1.0, n + 1)
    grid_a, grid_b = np.meshgrid(t, t, indexing="ij")
    pts, faces = [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            p = np.empty((*grid_a.shape, 3))
            p[..., axis] = sign
            p[..., (axis + 1) % 3] = grid_a
            p[..., (axis + 2) % 3] = grid_b
            base = len(pts) * (n + 1) ** 2
            quads = _ring_faces(n + 1, n, base)
            faces.append(quads[:, [0, 2, 1]] if sign > 0 else quads)
            pts.append(p.reshape(-1, 3))
    cube = np.concatenate(pts)
    # Weld the duplicated edge vertices so normals are shared across faces.
    keys, index = np.unique(np.round(cube, 6), axis=0, return_inverse=True)
    faces = index.ravel()[np.concatenate(faces)]
    scaled = keys * half
    inner = half - radius
    core = np.clip(scaled, -inner, inner)
    out = scaled - core
    norm = np.linalg.norm(out, axis=1, keepdims=True)
    verts = core + radius * np.divide(out, norm, out=np.zeros_like(out), where=norm > 1e-12)
    uv = np.column_stack([verts[:, 0] + verts[:, 1], verts[:, 2]])
    return Solid(verts + centre, faces.astype(np.int32), uv)


def quad(corner: np.ndarray, u_edge: np.ndarray, v_edge: np.ndarray) -> Solid:
    """A flat rectangle from ``corner`` along ``u_edge`` and ``v_edge``, facing u × v.

    Its texture coordinates span [0, 1] × [0, 1] (a decal or a picture, not tiled).
    """
    corner, u_edge, v_edge = (np.asarray(a, float) for a in (corner, u_edge, v_edge))
    verts = np.array([corner, corner + u_edge, corner + u_edge + v_edge, corner + v_edge])
    uv = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    return Solid(verts, np.array([[0, 1, 2], [0, 2, 3]], np.int32), uv)


def rotation_z(quarter_turns: int) -> np.ndarray:
    """The 3×3 rotation by ``quarter_turns`` × 90° counter-clockwise about z."""
    c, s = [(1, 0), (0, 1), (-1, 0), (0, -1)][quarter_turns % 4]
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
