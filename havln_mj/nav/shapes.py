"""Collision geometry of a compiled MuJoCo model as convex solids, and their footprints in a slab.

Every collision geom (group ``groups.COLLISION``) is posed at the model's reference
configuration and turned into a convex point set: boxes exactly (batched), meshes as their
convex hulls (as MuJoCo collides them), spheres, capsules, cylinders and ellipsoids as
enclosing polyhedra at most about 5 % larger; planes, height fields and SDF geoms are left
out. ``Shapes.footprints`` clips each solid to a horizontal slab and gives the points whose
2-D hull is the clipped part's plan-view footprint.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import mujoco
import numpy as np
from scipy.spatial import ConvexHull, QhullError

from havln_mj import groups
from havln_mj.errors import InvalidArgumentError

_ROUND_SEGMENTS = 16  # polygon sides used for spheres, capsules, cylinders, ellipsoids
_ALL_PAIRS_MAX = 64  # up to this many vertices a hull is clipped along every vertex pair

_BOX_SIGNS = np.array(
    [[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float
)
# The 12 edges of a box: corner pairs that differ in exactly one sign.
_BOX_EDGES = np.array(
    [(i, j) for i in range(8) for j in range(i + 1, 8) if bin(i ^ j).count("1") == 1]
)


@dataclass(frozen=True)
class Convex:
    """A convex solid in world coordinates: the hull of ``points``, with hull ``edges``."""

    points: np.ndarray  # (n, 3)
    edges: np.ndarray  # (m, 2) vertex index pairs including every hull edge


@dataclass(frozen=True)
class Shapes:
    """The collision geoms of a model: boxes batched, other convex geoms one by one."""

    boxes: np.ndarray  # (B, 8, 3) world corners
    others: tuple[Convex, ...]

    def bounds(self, margin: float) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of every solid's points, grown by ``margin`` metres.

        Raises:
            InvalidArgumentError: There is no solid (the model has no collision geoms).
        """
        allp = np.concatenate([self.boxes.reshape(-1, 3)] + [c.points for c in self.others])
        if not len(allp):
            raise InvalidArgumentError(
                "the model has no collision geoms (group COLLISION); pass bounds explicitly"
            )
        lo, hi = allp[:, :2].min(axis=0), allp[:, :2].max(axis=0)
        return (
            float(lo[0]) - margin,
            float(lo[1]) - margin,
            float(hi[0]) + margin,
            float(hi[1]) + margin,
        )

    def footprints(self, lo: float, hi: float) -> Iterator[np.ndarray]:
        """Plan-view points whose 2-D hull is one solid's footprint in the slab [lo, hi].

        Yields one (k, 2) array (possibly empty) per solid that reaches into the slab.
        """
        if len(self.boxes):
            z = self.boxes[..., 2]
            near = (z.max(axis=1) > lo) & (z.min(axis=1) < hi)
            if near.any():
                xy, ok = _clip_to_slab(self.boxes[near], _BOX_EDGES, lo, hi)
                for pts, mask in zip(xy, ok, strict=True):
                    yield pts[mask]
        for c in self.others:
            z = c.points[:, 2]
            if z.max() > lo and z.min() < hi:
                xy, ok = _clip_to_slab(c.points[None], c.edges, lo, hi)
                yield xy[0][ok[0]]


def _unit_sphere_points() -> np.ndarray:
    """Vertices of a polyhedron enclosing the unit sphere (at most ~5 % larger)."""
    n = _ROUND_SEGMENTS
    lon = np.arange(n) * 2 * np.pi / n
    lat = np.linspace(-np.pi / 2, np.pi / 2, n // 2 + 1)[1:-1]
    ring = np.stack(
        [np.outer(np.cos(lat), np.cos(lon)), np.outer(np.cos(lat), np.sin(lon))], axis=-1
    ).reshape(-1, 2)
    z = np.repeat(np.sin(lat), n)
    pts = np.concatenate([np.column_stack([ring, z]), [[0, 0, 1], [0, 0, -1]]])
    # Largest angular distance from a face's points to its nearest vertex: half a cell
    # diagonal of the longitude/latitude grid.
    half_gap = math.hypot(np.pi / n, np.pi / n)
    return pts / math.cos(half_gap)


def _unit_circle_points() -> np.ndarray:
    """Vertices of a polygon enclosing the unit circle."""
    n = _ROUND_SEGMENTS
    a = np.arange(n) * 2 * np.pi / n
    return np.column_stack([np.cos(a), np.sin(a)]) / math.cos(np.pi / n)


def _hull_edges(points: np.ndarray) -> np.ndarray:
    """Index pairs that include every edge of the points' convex hull."""
    n = len(points)
    if n > _ALL_PAIRS_MAX:
        try:
            simplices = ConvexHull(points).simplices
        except (QhullError, ValueError):
            pass  # flat or degenerate: every pair below is still correct
        else:
            e = np.concatenate([simplices[:, [0, 1]], simplices[:, [1, 2]], simplices[:, [0, 2]]])
            return np.unique(np.sort(e, axis=1), axis=0)
    i, j = np.triu_indices(n, 1)
    return np.column_stack([i, j])


def _local_points(model: mujoco.MjModel, g: int) -> np.ndarray | None:
    """Points (in the geom frame) whose convex hull encloses geom ``g``; None if unsupported."""
    t = model.geom_type[g]
    size = model.geom_size[g]
    gt = mujoco.mjtGeom
    if t == gt.mjGEOM_MESH:
        m = model.geom_dataid[g]
        adr, num = model.mesh_vertadr[m], model.mesh_vertnum[m]
        return np.asarray(model.mesh_vert[adr : adr + num], dtype=float)
    if t == gt.mjGEOM_SPHERE:
        return _unit_sphere_points() * size[0]
    if t == gt.mjGEOM_ELLIPSOID:
        return _unit_sphere_points() * size[:3]
    if t == gt.mjGEOM_CAPSULE:
        s = _unit_sphere_points() * size[0]
        offset = np.array([0.0, 0.0, size[1]])
        return np.concatenate([s + offset, s - offset])
    if t == gt.mjGEOM_CYLINDER:
        c = _unit_circle_points() * size[0]
        return np.concatenate(
            [np.column_stack([c, np.full(len(c), z)]) for z in (-size[1], size[1])]
        )
    return None  # planes, height fields and SDFs are not rasterised


def collision_shapes(model: mujoco.MjModel) -> Shapes:
    """World-frame convex shapes of every collision geom, posed at the model's qpos0."""
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    ids = np.flatnonzero(model.geom_group == groups.COLLISION)
    is_box = model.geom_type[ids] == mujoco.mjtGeom.mjGEOM_BOX
    b = ids[is_box]
    xmat = data.geom_xmat[b].reshape(-1, 3, 3)
    local = _BOX_SIGNS[None] * model.geom_size[b][:, None, :]  # (B, 8, 3)
    boxes = data.geom_xpos[b][:, None, :] + np.einsum("bij,bkj->bki", xmat, local)
    others = []
    for g in ids[~is_box]:
        pts = _local_points(model, int(g))
        if pts is None or not len(pts):
            continue
        world = data.geom_xpos[g] + pts @ data.geom_xmat[g].reshape(3, 3).T
        others.append(Convex(world, _hull_edges(world)))
    return Shapes(boxes, tuple(others))


def _clip_to_slab(
    points: np.ndarray, edges: np.ndarray, lo: float, hi: float
) -> tuple[np.ndarray, np.ndarray]:
    """Plan-view points whose convex hull is the footprint of a convex solid in a slab.

    The part of a convex polytope between the planes ``z = lo`` and ``z = hi`` is the hull of
    its vertices inside the slab and of the points where its edges cross the two planes;
    the part's footprint is the 2-D hull of those points. Extra pairs (non-edges) only add
    points inside the solid, so passing every vertex pair is also correct.

    Args:
        points: (N, n, 3) vertices of N solids.
        edges: (m, 2) vertex index pairs including every hull edge, shared by the N solids.
        lo: Lower plane height.
        hi: Upper plane height.

    Returns:
        (N, n + 2m, 2) candidate points and their (N, n + 2m) validity mask.
    """
    z = points[..., 2]
    xy = [points[..., :2]]
    ok = [(z >= lo) & (z <= hi)]
    a, b = points[:, edges[:, 0]], points[:, edges[:, 1]]  # (N, m, 3)
    za, zb = a[..., 2], b[..., 2]
    for h in (lo, hi):
        cross = (za - h) * (zb - h) < 0
        t = np.where(cross, (h - za) / np.where(cross, zb - za, 1.0), 0.0)
        xy.append(a[..., :2] + t[..., None] * (b[..., :2] - a[..., :2]))
        ok.append(cross)
    return np.concatenate(xy, axis=1), np.concatenate(ok, axis=1)
