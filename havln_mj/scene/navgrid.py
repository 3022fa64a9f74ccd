"""Per-floor occupancy grids rasterised from a world's collision geometry, with geodesics.

A ``NavGrid`` covers one level of a building. Every collision geom (group
``groups.COLLISION``) whose body reaches into a height band above the level's floor is
clipped to that band and its 2-D footprint (the convex hull of the clipped part) is filled
into an occupancy grid. The obstacles are then inflated by the robot's radius: a cell is
``free`` when no occupied cell's centre is nearer to its centre than the radius, so a free
cell is a place where the robot's centre may stand.

A cell is occupied when the footprint overlaps it at all (OpenCV's polygon fill at
1/256-cell precision), so the centre of the last occupied cell lies within half a cell of
the obstacle's edge, on either side. Centre-to-centre clearances, and with them the border
of the free region, are right to within about half a cell (0.7 cell diagonally), without
bias in either direction.

Geodesic distances are shortest paths on the graph of free cells whose edges are the moves
to the 8, 16 (default) or 32 nearest directions, each weighted by its Euclidean length; a
move is allowed only when every cell its straight segment touches is free (no corner
cutting). The grid metric overestimates a straight line by at most 8.2 % (8 neighbours),
2.8 % (16) or 1.0 % (32); ``NavGrid.distance`` is exact whenever the straight segment
between the two points is free. Distances are ``inf`` between cells that are not connected.

Example::

    world = build_world(load_scan("proc-3"))
    grids = build_navgrids(world, floor_heights(world.scan))
    d = grids[0].distance((1.0, 2.0), (4.5, -0.5))
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import cv2
import mujoco
import numpy as np
from scipy import ndimage
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import ConvexHull, QhullError

from havln_mj import groups
from havln_mj.errors import InvalidArgumentError

# Body heights (above the floor) that count as obstacles.
LEGGED_BAND = (0.1, 0.6)  # a GO1-sized quadruped: legs of tables block, table tops do not
PERSON_BAND = (0.05, 1.8)  # a person-height body (the point body's procedural sweep)

_SHIFT = 8  # OpenCV fixed-point bits: polygons are placed at 1/256 of a cell
_MAX_CELLS = 40_000_000  # guards against absurd bounds or resolutions
_NEIGHBOURS = (8, 16, 32)
_FIELD_CACHE = 8  # distance fields kept per grid
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
class GridSpec:
    """How to rasterise a level.

    The defaults fit a GO1-sized quadruped: about 0.65 m long and 0.3 m wide, so a disc of
    radius 0.25 m is a compromise between its half width (0.15 m) and half length
    (0.33 m), and a body from 0.1 m to 0.6 m above the floor (legs and trunk; the feet may
    step over door sills and rugs, table tops above 0.6 m do not block but table legs do).
    For a person-height body use ``GridSpec(z_band=PERSON_BAND, robot_radius=0.2)``, the
    body the procedural houses' navigation graphs are checked with.

    Attributes:
        resolution: Cell size in metres.
        robot_radius: Radius in metres by which obstacles are inflated (0 for none).
        z_band: (low, high) heights above the floor; a geom blocks where its body lies
            between them.
        margin: Free border in metres added around the collision geometry's extent when
            the grid bounds are not given.
        neighbours: 8, 16 or 32: the moves of the geodesic graph (more is more accurate and
            slower; see the module docstring).
    """

    resolution: float = 0.05
    robot_radius: float = 0.25
    z_band: tuple[float, float] = LEGGED_BAND
    margin: float = 0.5
    neighbours: int = 16

    def __post_init__(self) -> None:
        if not (_finite(self.resolution) and 0 < self.resolution <= 1.0):
            raise InvalidArgumentError(
                f"resolution must be in (0, 1] metres, got {self.resolution!r}"
            )
        if not (_finite(self.robot_radius) and 0 <= self.robot_radius <= 5.0):
            raise InvalidArgumentError(
                f"robot_radius must be in [0, 5] metres, got {self.robot_radius!r}"
            )
        try:
            band = tuple(self.z_band)
        except TypeError:
            band = ()
        if len(band) != 2 or not all(_finite(v) for v in band) or not band[0] < band[1]:
            raise InvalidArgumentError(
                f"z_band must be two finite heights (low, high) with low < high, "
                f"got {self.z_band!r}"
            )
        object.__setattr__(self, "z_band", (float(band[0]), float(band[1])))
        if not (_finite(self.margin) and self.margin >= 0):
            raise InvalidArgumentError(f"margin must be >= 0 metres, got {self.margin!r}")
        if self.neighbours not in _NEIGHBOURS:
            raise InvalidArgumentError(
                f"neighbours must be one of {_NEIGHBOURS}, got {self.neighbours!r}"
            )


def _finite(value: object) -> bool:
    return isinstance(value, int | float | np.floating | np.integer) and math.isfinite(value)


def _xy(point: object, name: str) -> np.ndarray:
    """One point as a float (2,) array (a z coordinate is dropped)."""
    try:
        p = np.asarray(point, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InvalidArgumentError(f"{name} must be a point (x, y[, z]), got {point!r}") from None
    if len(p) not in (2, 3) or not np.all(np.isfinite(p)):
        raise InvalidArgumentError(f"{name} must be a finite point (x, y[, z]), got {point!r}")
    return p[:2]


def _xy_array(points: object, name: str) -> np.ndarray:
    """Points as a float (..., 2) array (z coordinates are dropped)."""
    try:
        p = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise InvalidArgumentError(f"{name} must be points (..., 2 or 3), got {points!r}") from None
    if p.ndim == 0 or p.shape[-1] not in (2, 3) or not np.all(np.isfinite(p)):
        raise InvalidArgumentError(
            f"{name} must be finite points of shape (..., 2) or (..., 3), got shape {p.shape}"
        )
    return p[..., :2]


# Geometry: convex collision geoms as point sets, clipped to a horizontal slab.


@dataclass(frozen=True)
class _Convex:
    """A convex solid in world coordinates: the hull of ``points``, with hull ``edges``."""

    points: np.ndarray  # (n, 3)
    edges: np.ndarray  # (m, 2) vertex index pairs including every hull edge


@dataclass(frozen=True)
class _Shapes:
    """The collision geoms of a model: boxes batched, other convex geoms one by one."""

    boxes: np.ndarray  # (B, 8, 3) world corners
    others: tuple[_Convex, ...]

    def xy_bounds(self) -> tuple[float, float, float, float] | None:
        pts = [self.boxes.reshape(-1, 3)] + [c.points for c in self.others]
        allp = np.concatenate(pts)
        if not len(allp):
            return None
        lo, hi = allp[:, :2].min(axis=0), allp[:, :2].max(axis=0)
        return float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])


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


def _collision_shapes(model: mujoco.MjModel) -> _Shapes:
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
        others.append(_Convex(world, _hull_edges(world)))
    return _Shapes(boxes, tuple(others))


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


class _Raster:
    """Fills plan-view convex polygons into a boolean grid at sub-cell precision."""

    def __init__(self, origin: tuple[float, float], shape: tuple[int, int], res: float) -> None:
        self.origin = np.asarray(origin, dtype=float)
        self.res = res
        self.image = np.zeros(shape, dtype=np.uint8)
        # Fixed-point limit that keeps OpenCV's int32 arithmetic safe.
        self._limit = float(2**30 >> _SHIFT)

    def fill_hull(self, xy: np.ndarray) -> None:
        if not len(xy):
            return
        # OpenCV puts pixel (col, row) centres at integer coordinates.
        u = (xy - self.origin) / self.res - 0.5
        u = np.clip(u, -self._limit, self._limit)
        fixed = np.round(u * (1 << _SHIFT)).astype(np.int32).reshape(-1, 1, 2)
        hull = cv2.convexHull(fixed)
        cv2.fillConvexPoly(self.image, hull, 1, lineType=cv2.LINE_8, shift=_SHIFT)


def _rasterise(
    shapes: _Shapes,
    lo: float,
    hi: float,
    origin: tuple[float, float],
    shape: tuple[int, int],
    res: float,
) -> np.ndarray:
    """(H, W) bool: cells overlapped by any shape's footprint in the slab [lo, hi]."""
    raster = _Raster(origin, shape, res)
    if len(shapes.boxes):
        z = shapes.boxes[..., 2]
        near = (z.max(axis=1) > lo) & (z.min(axis=1) < hi)
        if near.any():
            xy, ok = _clip_to_slab(shapes.boxes[near], _BOX_EDGES, lo, hi)
            for pts, mask in zip(xy, ok, strict=True):
                raster.fill_hull(pts[mask])
    for c in shapes.others:
        z = c.points[:, 2]
        if z.max() > lo and z.min() < hi:
            xy, ok = _clip_to_slab(c.points[None], c.edges, lo, hi)
            raster.fill_hull(xy[0][ok[0]])
    return raster.image.astype(bool)


def _grid_frame(
    bounds: tuple[float, float, float, float], res: float
) -> tuple[tuple[float, float], tuple[int, int]]:
    """Origin and (H, W) of a grid covering ``bounds``, aligned to multiples of ``res``."""
    try:
        xmin, ymin, xmax, ymax = (float(v) for v in bounds)
    except (TypeError, ValueError):
        raise InvalidArgumentError(
            f"bounds must be (xmin, ymin, xmax, ymax), got {bounds!r}"
        ) from None
    if not all(map(math.isfinite, (xmin, ymin, xmax, ymax))) or xmin >= xmax or ymin >= ymax:
        raise InvalidArgumentError(
            f"bounds must be finite (xmin, ymin, xmax, ymax) with xmin < xmax and "
            f"ymin < ymax, got {bounds!r}"
        )
    eps = 1e-9
    c0, r0 = math.floor(xmin / res + eps), math.floor(ymin / res + eps)
    c1, r1 = math.ceil(xmax / res - eps), math.ceil(ymax / res - eps)
    width, height = max(c1 - c0, 1), max(r1 - r0, 1)
    if width * height > _MAX_CELLS:
        raise InvalidArgumentError(
            f"a grid of {height} x {width} cells (bounds {bounds!r}, resolution {res!r}) "
            f"exceeds {_MAX_CELLS} cells; pass smaller bounds or a coarser resolution"
        )
    return (c0 * res, r0 * res), (height, width)


def _default_bounds(shapes: _Shapes, margin: float) -> tuple[float, float, float, float]:
    ext = shapes.xy_bounds()
    if ext is None:
        raise InvalidArgumentError(
            "the model has no collision geoms (group COLLISION); pass bounds explicitly"
        )
    return ext[0] - margin, ext[1] - margin, ext[2] + margin, ext[3] + margin


# Graph moves.


def _moves(neighbours: int) -> list[tuple[int, int, float, list[tuple[int, int]]]]:
    """Half of the move set: (dr, dc, length in cells, cells the segment touches).

    Each move (dr, dc) has gcd 1 and lies in the upper half plane; the touched cells are
    those whose closed square meets the segment between the two centres, endpoints excepted.
    """
    k = {8: 1, 16: 2, 32: 3}[neighbours]
    out = []
    for dr in range(0, k + 1):
        for dc in range(-k, k + 1):
            if (dr == 0 and dc <= 0) or math.gcd(dr, abs(dc)) != 1:
                continue
            touched = []
            for r in range(min(0, dr), max(0, dr) + 1):
                for c in range(min(0, dc), max(0, dc) + 1):
                    if (r, c) not in ((0, 0), (dr, dc)) and _segment_meets_cell(dr, dc, r, c):
                        touched.append((r, c))
            out.append((dr, dc, math.hypot(dr, dc), touched))
    return out


def _segment_meets_cell(dr: int, dc: int, r: int, c: int) -> bool:
    """Whether the segment (0, 0)-(dr, dc) meets the closed unit square centred at (r, c)."""
    # Separating axes: the square's two axes (guaranteed by the bounding box loop) and the
    # segment's normal.
    n = np.array([-dc, dr], dtype=float)
    corners = np.array([[r + sr * 0.5, c + sc * 0.5] for sr in (-1, 1) for sc in (-1, 1)])
    s = corners @ n
    return bool(s.min() <= 1e-12 and s.max() >= -1e-12)


class NavGrid:
    """An occupancy grid of one level and geodesic distances on its free cells.

    Cell (row, col) covers x in ``[x0 + col·res, x0 + (col + 1)·res)`` and y in
    ``[y0 + row·res, y0 + (row + 1)·res)``: rows grow with y, so ``image()`` is drawn with
    ``origin="lower"``. Points may be given as (x, y) or (x, y, z); z is ignored.

    Attributes:
        origin: (x0, y0), the world position of the grid's lower-left corner.
        resolution: Cell size in metres.
        floor_z: Height of the level's floor.
        spec: The grid's parameters.
        occupied: (H, W) bool, cells an obstacle overlaps (before inflation).
        free: (H, W) bool, cells where the robot's centre may stand (after inflation).
        clearance: (H, W) float32, metres from each cell's centre to the nearest occupied
            cell's centre (0 on occupied cells, inf when the grid has no obstacle).
    """

    def __init__(
        self,
        occupied: np.ndarray,
        origin: tuple[float, float],
        floor_z: float = 0.0,
        spec: GridSpec | None = None,
    ) -> None:
        """Builds the grid from an occupancy array.

        Args:
            occupied: (H, W) bool obstacles, row 0 at the lowest y.
            origin: (x0, y0) of the grid's lower-left corner.
            floor_z: Height of the level's floor.
            spec: Grid parameters (resolution, robot radius, moves); default ``GridSpec()``.

        Raises:
            InvalidArgumentError: A value is out of range.
        """
        self.spec = spec or GridSpec()
        occ = np.asarray(occupied)
        if occ.ndim != 2 or occ.size == 0:
            raise InvalidArgumentError(
                f"occupied must be a non-empty (H, W) array, got shape {occ.shape}"
            )
        if not _finite(floor_z):
            raise InvalidArgumentError(f"floor_z must be a finite height, got {floor_z!r}")
        self.origin = tuple(float(v) for v in _xy(origin, "origin"))
        self.resolution = self.spec.resolution
        self.floor_z = float(floor_z)
        self.occupied = occ.astype(bool)
        self.occupied.flags.writeable = False
        if self.occupied.any():
            cells = ndimage.distance_transform_edt(~self.occupied)
        else:
            cells = np.full(self.occupied.shape, np.inf)
        self.clearance = (cells * self.resolution).astype(np.float32)
        self.clearance.flags.writeable = False
        # Disc inflation: a cell is blocked when an occupied cell's centre is nearer than
        # the radius. Centre-to-centre distances estimate the true clearance to within half a
        # cell either way, so the free region's border is unbiased (not shifted outward).
        radius_cells = self.spec.robot_radius / self.resolution
        self.free = (cells >= radius_cells - 1e-6) & ~self.occupied
        self.free.flags.writeable = False
        self._fields: OrderedDict[int, tuple[np.ndarray, np.ndarray]] = OrderedDict()

    @classmethod
    def from_model(
        cls,
        model: mujoco.MjModel,
        floor_z: float,
        spec: GridSpec | None = None,
        bounds: tuple[float, float, float, float] | None = None,
    ) -> NavGrid:
        """Rasterises a model's collision geoms (group ``COLLISION``) for one level.

        Geoms are posed at the model's reference configuration (the world's collision geoms
        are static). Boxes and meshes (their convex hulls, as MuJoCo collides them) are
        exact; spheres, capsules, cylinders and ellipsoids are enclosed in polyhedra at most
        about 5 % larger; planes, height fields and SDF geoms are ignored.

        Args:
            model: The compiled world.
            floor_z: Height of the level's floor.
            spec: Grid parameters; default ``GridSpec()``.
            bounds: (xmin, ymin, xmax, ymax) to cover, grown outward to whole cells; default
                the collision geoms' extent plus ``spec.margin``.

        Returns:
            The level's grid.

        Raises:
            InvalidArgumentError: Bad floor height, bounds, or a model without collision
                geoms and no bounds.
        """
        spec = spec or GridSpec()
        shapes = _collision_shapes(model)
        if bounds is None:
            bounds = _default_bounds(shapes, spec.margin)
        return cls._from_shapes(shapes, floor_z, spec, bounds)

    @classmethod
    def _from_shapes(
        cls,
        shapes: _Shapes,
        floor_z: float,
        spec: GridSpec,
        bounds: tuple[float, float, float, float],
    ) -> NavGrid:
        if not _finite(floor_z):
            raise InvalidArgumentError(f"floor_z must be a finite height, got {floor_z!r}")
        origin, shape = _grid_frame(bounds, spec.resolution)
        lo, hi = floor_z + spec.z_band[0], floor_z + spec.z_band[1]
        occupied = _rasterise(shapes, lo, hi, origin, shape, spec.resolution)
        return cls(occupied, origin, floor_z, spec)

    def __repr__(self) -> str:
        h, w = self.shape
        return (
            f"NavGrid(floor_z={self.floor_z:g}, {h}x{w} cells of {self.resolution:g} m, "
            f"origin=({self.origin[0]:g}, {self.origin[1]:g}), "
            f"free={self.free.mean():.1%}, radius={self.spec.robot_radius:g})"
        )

    # Geometry.

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W): rows (along y) and columns (along x)."""
        return self.occupied.shape

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(x0, x1, y0, y1) for matplotlib ``imshow(..., origin="lower", extent=...)``."""
        h, w = self.shape
        x0, y0 = self.origin
        return x0, x0 + w * self.resolution, y0, y0 + h * self.resolution

    def to_cells(self, xy: object) -> np.ndarray:
        """Cells (row, col) holding points; no bounds check (see ``contains``).

        Args:
            xy: (..., 2) or (..., 3) points.

        Returns:
            (..., 2) int64 array of (row, col).
        """
        p = _xy_array(xy, "xy")
        cr = np.floor((p - self.origin) / self.resolution).astype(np.int64)
        return cr[..., ::-1]

    def to_cell(self, xy: object) -> tuple[int, int]:
        """The (row, col) of the cell holding one point.

        Raises:
            InvalidArgumentError: The point is not a finite point or lies outside the grid.
        """
        p = _xy(xy, "xy")
        r, c = self.to_cells(p).tolist()
        h, w = self.shape
        if not (0 <= r < h and 0 <= c < w):
            raise InvalidArgumentError(
                f"point ({p[0]:g}, {p[1]:g}) is outside the grid, which covers x in "
                f"[{self.extent[0]:g}, {self.extent[1]:g}) and y in "
                f"[{self.extent[2]:g}, {self.extent[3]:g})"
            )
        return r, c

    def to_world(self, rc: object) -> np.ndarray:
        """World (x, y) of cell centres.

        Args:
            rc: (row, col) or an (..., 2) array of them.

        Returns:
            (..., 2) float array.
        """
        cells = np.asarray(rc, dtype=float)
        if cells.ndim == 0 or cells.shape[-1] != 2 or not np.all(np.isfinite(cells)):
            raise InvalidArgumentError(f"rc must be (row, col) pairs, got {rc!r}")
        return np.asarray(self.origin) + (cells[..., ::-1] + 0.5) * self.resolution

    def contains(self, xy: object) -> bool | np.ndarray:
        """Whether points lie inside the grid (a bool, or an array for several points)."""
        rc = self.to_cells(xy)
        h, w = self.shape
        inside = (rc[..., 0] >= 0) & (rc[..., 0] < h) & (rc[..., 1] >= 0) & (rc[..., 1] < w)
        return bool(inside) if inside.ndim == 0 else inside

    def is_free(self, xy: object) -> bool | np.ndarray:
        """Whether points lie on free cells (False outside the grid).

        Args:
            xy: One point, or an (..., 2) / (..., 3) array of points.

        Returns:
            A bool for one point, else a bool array of the points' leading shape.
        """
        rc = self.to_cells(xy)
        h, w = self.shape
        inside = (rc[..., 0] >= 0) & (rc[..., 0] < h) & (rc[..., 1] >= 0) & (rc[..., 1] < w)
        r = np.clip(rc[..., 0], 0, h - 1)
        c = np.clip(rc[..., 1], 0, w - 1)
        out = inside & self.free[r, c]
        return bool(out) if out.ndim == 0 else out

    @cached_property
    def _nearest_free_index(self) -> tuple[np.ndarray, np.ndarray]:
        if not self.free.any():
            raise InvalidArgumentError(
                f"the grid at floor_z={self.floor_z:g} has no free cell "
                f"(robot_radius={self.spec.robot_radius:g} m)"
            )
        _, idx = ndimage.distance_transform_edt(~self.free, return_indices=True)
        return idx[0], idx[1]

    def nearest_free(self, xy: object) -> np.ndarray:
        """The nearest place where the robot may stand.

        A point on a free cell is returned unchanged; any other point (inside an obstacle,
        in its inflation, or outside the grid) moves to the centre of the free cell nearest
        to its cell (outside the grid: to the nearest border cell first).

        Args:
            xy: One point, or an (..., 2) / (..., 3) array of points.

        Returns:
            (..., 2) float array.

        Raises:
            InvalidArgumentError: Bad points, or the grid has no free cell.
        """
        p = _xy_array(xy, "xy")
        rows, cols = self._nearest_free_index
        h, w = self.shape
        rc = self.to_cells(p)
        r = np.clip(rc[..., 0], 0, h - 1)
        c = np.clip(rc[..., 1], 0, w - 1)
        snapped = self.to_world(np.stack([rows[r, c], cols[r, c]], axis=-1))
        keep = np.asarray(self.is_free(p))[..., None]
        return np.where(keep, p, snapped)

    # Geodesics.

    @cached_property
    def _graph(self) -> tuple[csr_matrix, np.ndarray, np.ndarray]:
        """The free-cell graph, the flat index of each node and the node of each cell."""
        free = self.free
        h, w = free.shape
        nodes = np.flatnonzero(free)
        node_of = np.full(h * w, -1, dtype=np.int64)
        node_of[nodes] = np.arange(len(nodes))
        pad = 3  # the longest move reaches 3 cells
        padded = np.zeros((h + 2 * pad, w + 2 * pad), dtype=bool)
        padded[pad:-pad, pad:-pad] = free
        ids = np.full(padded.shape, -1, dtype=np.int64)
        ids[pad:-pad, pad:-pad] = node_of.reshape(h, w)

        def shifted(a: np.ndarray, dr: int, dc: int) -> np.ndarray:
            return a[pad + dr : pad + dr + h, pad + dc : pad + dc + w]

        src, dst, wts = [], [], []
        for dr, dc, length, touched in _moves(self.spec.neighbours):
            ok = free & shifted(padded, dr, dc)
            for r, c in touched:
                ok &= shifted(padded, r, c)
            a, b = shifted(ids, 0, 0)[ok], shifted(ids, dr, dc)[ok]
            src += [a, b]
            dst += [b, a]
            wts.append(np.full(2 * len(a), length * self.resolution))
        n = len(nodes)
        rows = np.concatenate(src) if src else np.zeros(0, dtype=np.int64)
        cols = np.concatenate(dst) if dst else np.zeros(0, dtype=np.int64)
        weights = np.concatenate(wts) if wts else np.zeros(0)
        graph = csr_matrix((weights, (rows, cols)), shape=(n, n))
        return graph, nodes, node_of

    def _field(self, flat: int) -> tuple[np.ndarray, np.ndarray]:
        """Distance field (H, W) and predecessor cells from a free cell (LRU-cached)."""
        hit = self._fields.get(flat)
        if hit is not None:
            self._fields.move_to_end(flat)
            return hit
        graph, nodes, node_of = self._graph
        dist, pred = dijkstra(
            graph, directed=True, indices=int(node_of[flat]), return_predecessors=True
        )
        field = np.full(self.free.size, np.inf)
        field[nodes] = dist
        prev = np.full(self.free.size, -1, dtype=np.int64)
        prev[nodes] = np.where(pred >= 0, nodes[np.maximum(pred, 0)], -1)
        field = field.reshape(self.shape)
        field.flags.writeable = False
        self._fields[flat] = (field, prev)
        while len(self._fields) > _FIELD_CACHE:
            self._fields.popitem(last=False)
        return field, prev

    def _snap(self, p: np.ndarray) -> tuple[np.ndarray, int, float]:
        """A free point near ``p`` (as ``nearest_free``), its flat cell and the distance moved."""
        h, w = self.shape
        c = math.floor((p[0] - self.origin[0]) / self.resolution)
        r = math.floor((p[1] - self.origin[1]) / self.resolution)
        if 0 <= r < h and 0 <= c < w and self.free[r, c]:
            return p, r * w + c, 0.0
        rows, cols = self._nearest_free_index
        r0, c0 = min(max(r, 0), h - 1), min(max(c, 0), w - 1)
        r, c = int(rows[r0, c0]), int(cols[r0, c0])
        q = np.array(
            [
                self.origin[0] + (c + 0.5) * self.resolution,
                self.origin[1] + (r + 0.5) * self.resolution,
            ]
        )
        return q, r * w + c, math.hypot(q[0] - p[0], q[1] - p[1])

    def _segment_free(self, a: np.ndarray, b: np.ndarray) -> bool:
        # Samples every quarter cell along the segment.
        h, w = self.shape
        res = self.resolution
        n = math.ceil(math.hypot(b[0] - a[0], b[1] - a[1]) / (0.25 * res)) + 1
        t = np.linspace(0.0, 1.0, n + 1)
        c = np.floor((a[0] - self.origin[0] + t * (b[0] - a[0])) / res).astype(np.intp)
        r = np.floor((a[1] - self.origin[1] + t * (b[1] - a[1])) / res).astype(np.intp)
        if c.min() < 0 or r.min() < 0 or c.max() >= w or r.max() >= h:
            return False
        return bool(self.free[r, c].all())

    def segment_is_free(self, p: object, q: object) -> bool:
        """Whether the straight segment from ``p`` to ``q`` crosses only free cells.

        The segment is sampled every quarter of a cell, so it may clip a blocked cell's
        corner unseen.
        """
        return self._segment_free(_xy(p, "p"), _xy(q, "q"))

    def distances_from(self, p: object) -> np.ndarray:
        """Geodesic distance field from a point: metres to every cell's centre.

        The grid metric from ``p``'s cell (or the nearest free cell, plus the distance to
        it); no straight-line refinement. Fields are cached, so repeated queries from the
        same cell are cheap.

        Args:
            p: The source point.

        Returns:
            (H, W) float array, read-only, ``inf`` on cells that are not free or not
            reachable.
        """
        _, flat, moved = self._snap(_xy(p, "p"))
        field, _ = self._field(flat)
        if moved == 0.0:
            return field
        out = field + moved
        out.flags.writeable = False
        return out

    def distance(self, p: object, q: object) -> float:
        """Geodesic distance in metres between two points.

        Points not on free cells are first moved to the nearest free cell and the moves are
        added. When the straight segment between the (moved) points is free, the distance
        is its length; otherwise it is the grid geodesic between their cells. Distance
        fields are cached per source cell: the field of ``q`` is computed unless one of
        ``p`` is cached, so pass the fixed point (e.g. the goal) as ``q``.

        Args:
            p: One end, (x, y) or (x, y, z).
            q: The other end.

        Returns:
            Metres; ``inf`` when the two are not connected.
        """
        a, fa, ma = self._snap(_xy(p, "p"))
        b, fb, mb = self._snap(_xy(q, "q"))
        if self._segment_free(a, b):
            return ma + mb + math.hypot(b[0] - a[0], b[1] - a[1])
        source, target = (fa, fb) if fa in self._fields else (fb, fa)
        field, _ = self._field(source)
        return ma + mb + float(field.flat[target])

    def path(self, p: object, q: object) -> np.ndarray | None:
        """A shortest path from ``p`` to ``q``: the points, cell centres between them.

        Returns:
            (K, 2) float array starting at ``p`` and ending at ``q`` (only the two when the
            straight segment is free), or None when they are not connected.
        """
        pa, pb = _xy(p, "p"), _xy(q, "q")
        a, fa, _ = self._snap(pa)
        b, fb, _ = self._snap(pb)
        if self._segment_free(a, b):
            pts = [pa, a, b, pb]
        else:
            field, prev = self._field(fb)
            if not np.isfinite(field.flat[fa]):
                return None
            cells = [fa]
            while cells[-1] != fb:
                cells.append(int(prev[cells[-1]]))
            w = self.shape[1]
            centres = self.to_world(np.array([(c // w, c % w) for c in cells]))
            pts = [pa, a, *centres[1:-1], b, pb]
        out = [pts[0]]
        for x in pts[1:]:
            if np.hypot(*(x - out[-1])) > 1e-12:
                out.append(x)
        return np.array(out)

    # Drawing.

    def image(self, alpha: int = 255) -> tuple[np.ndarray, tuple[float, float, float, float]]:
        """An RGBA picture of the grid and its extent, for ``imshow(origin="lower")``.

        Free cells are white, cells blocked only by the robot's radius light red, and
        occupied cells dark grey.

        Args:
            alpha: Opacity (0-255) of the blocked cells; free cells get a third of it, so
                the grid can be laid over a map.

        Returns:
            ((H, W, 4) uint8 image, (x0, x1, y0, y1) extent).
        """
        if not (isinstance(alpha, int | np.integer) and 0 <= alpha <= 255):
            raise InvalidArgumentError(f"alpha must be an int in [0, 255], got {alpha!r}")
        img = np.empty((*self.shape, 4), dtype=np.uint8)
        img[...] = (255, 255, 255, alpha // 3)
        img[~self.free] = (240, 150, 140, alpha)
        img[self.occupied] = (60, 60, 60, alpha)
        return img, self.extent


def build_navgrids(
    world_or_model: object,
    floors: Sequence[float],
    spec: GridSpec | None = None,
    bounds: tuple[float, float, float, float] | None = None,
) -> list[NavGrid]:
    """Grids of several levels of one world, sharing their bounds (cells line up).

    Args:
        world_or_model: A ``World`` (anything with a ``model``) or a ``mujoco.MjModel``.
        floors: Floor heights of the levels (see ``floor_heights``).
        spec: Grid parameters; default ``GridSpec()``.
        bounds: (xmin, ymin, xmax, ymax); default the collision geoms' extent plus margin.

    Returns:
        One grid per floor, in the order given.

    Raises:
        InvalidArgumentError: Not a model, a bad floor height, or bad bounds.
    """
    model = getattr(world_or_model, "model", world_or_model)
    if not isinstance(model, mujoco.MjModel):
        raise InvalidArgumentError(
            f"world_or_model must be a World or a mujoco.MjModel, "
            f"got {type(world_or_model).__name__}"
        )
    spec = spec or GridSpec()
    shapes = _collision_shapes(model)
    if bounds is None:
        bounds = _default_bounds(shapes, spec.margin)
    return [NavGrid._from_shapes(shapes, z, spec, bounds) for z in floors]
