"""Per-floor occupancy grids rasterised from a world's collision geometry, with geodesics.

A ``NavGrid`` covers one level of a building. Every collision geom (group
``groups.COLLISION``) whose body reaches into a height band above the level's floor is
clipped to that band and its 2-D footprint (the convex hull of the clipped part) is filled
into an occupancy grid. The obstacles are then inflated by the robot's radius: a cell is
``free`` when no occupied cell's centre is nearer to its centre than the radius, so a free
cell is a place where the robot's centre may stand.

A cell is occupied when the footprint overlaps it at all, so the centre of the last occupied
cell lies within half a cell of the obstacle's edge, on either side. Centre-to-centre
clearances, and with them the border of the free region, are right to within about half a
cell (0.7 cell diagonally), without bias in either direction.

Geodesic distances are shortest paths on the graph of free cells (``havln_mj.nav.geodesic``);
``NavGrid.distance`` is exact whenever the straight segment between the two points is free.

Example::

    world = build_world(load_scan("proc-3"))
    grids = build_navgrids(world, floor_heights(world.scan))
    d = grids[0].distance((1.0, 2.0), (4.5, -0.5))
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from functools import cached_property

import mujoco
import numpy as np
from scipy import ndimage

from havln_mj.errors import InvalidArgumentError
from havln_mj.nav.frame import GridFrame
from havln_mj.nav.geodesic import CellGraph
from havln_mj.nav.raster import rasterise
from havln_mj.nav.shapes import Shapes, collision_shapes
from havln_mj.nav.spec import GridSpec, finite, point_xy, points_xy


class NavGrid(GridFrame):
    """An occupancy grid of one level and geodesic distances on its free cells.

    Cells are laid out as in ``GridFrame``: rows grow with y, so ``image()`` is drawn with
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
        if not finite(floor_z):
            raise InvalidArgumentError(f"floor_z must be a finite height, got {floor_z!r}")
        super().__init__(origin, self.spec.resolution, occ.shape)
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
        self._cells = CellGraph(self.free, self.resolution, self.spec.neighbours)

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
        shapes = collision_shapes(model)
        if bounds is None:
            bounds = shapes.bounds(spec.margin)
        return cls._from_shapes(shapes, floor_z, spec, bounds)

    @classmethod
    def _from_shapes(
        cls,
        shapes: Shapes,
        floor_z: float,
        spec: GridSpec,
        bounds: tuple[float, float, float, float],
    ) -> NavGrid:
        if not finite(floor_z):
            raise InvalidArgumentError(f"floor_z must be a finite height, got {floor_z!r}")
        origin, shape = GridFrame.covering(bounds, spec.resolution)
        lo, hi = floor_z + spec.z_band[0], floor_z + spec.z_band[1]
        occupied = rasterise(shapes.footprints(lo, hi), origin, shape, spec.resolution)
        return cls(occupied, origin, floor_z, spec)

    def __repr__(self) -> str:
        h, w = self.shape
        return (
            f"NavGrid(floor_z={self.floor_z:g}, {h}x{w} cells of {self.resolution:g} m, "
            f"origin=({self.origin[0]:g}, {self.origin[1]:g}), "
            f"free={self.free.mean():.1%}, radius={self.spec.robot_radius:g})"
        )

    # Free space.

    def is_free(self, xy: object) -> bool | np.ndarray:
        """Whether points lie on free cells (False outside the grid).

        Args:
            xy: One point, or an (..., 2) / (..., 3) array of points.

        Returns:
            A bool for one point, else a bool array of the points' leading shape.
        """
        rc = self.to_cells(xy)
        h, w = self.shape
        inside = self._inside(rc)
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
        p = points_xy(xy, "xy")
        rows, cols = self._nearest_free_index
        h, w = self.shape
        rc = self.to_cells(p)
        r = np.clip(rc[..., 0], 0, h - 1)
        c = np.clip(rc[..., 1], 0, w - 1)
        snapped = self.to_world(np.stack([rows[r, c], cols[r, c]], axis=-1))
        keep = np.asarray(self.is_free(p))[..., None]
        return np.where(keep, p, snapped)

    # Geodesics.

    def _snap(self, p: np.ndarray) -> tuple[np.ndarray, int, float]:
        """A free point near ``p`` (as ``nearest_free``), its flat cell and the distance moved."""
        h, w = self.shape
        r, c = self._cell_of(p)
        if 0 <= r < h and 0 <= c < w and self.free[r, c]:
            return p, r * w + c, 0.0
        rows, cols = self._nearest_free_index
        r0, c0 = min(max(r, 0), h - 1), min(max(c, 0), w - 1)
        r, c = int(rows[r0, c0]), int(cols[r0, c0])
        q = self._centre(r, c)
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
        return self._segment_free(point_xy(p, "p"), point_xy(q, "q"))

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
        _, flat, moved = self._snap(point_xy(p, "p"))
        field, _ = self._cells.field(flat)
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
        a, fa, ma = self._snap(point_xy(p, "p"))
        b, fb, mb = self._snap(point_xy(q, "q"))
        if self._segment_free(a, b):
            return ma + mb + math.hypot(b[0] - a[0], b[1] - a[1])
        source, target = (fa, fb) if fa in self._cells else (fb, fa)
        field, _ = self._cells.field(source)
        return ma + mb + float(field.flat[target])

    def path(self, p: object, q: object) -> np.ndarray | None:
        """A shortest path from ``p`` to ``q``: the points, cell centres between them.

        Returns:
            (K, 2) float array starting at ``p`` and ending at ``q`` (only the two when the
            straight segment is free), or None when they are not connected.
        """
        pa, pb = point_xy(p, "p"), point_xy(q, "q")
        a, fa, _ = self._snap(pa)
        b, fb, _ = self._snap(pb)
        if self._segment_free(a, b):
            pts = [pa, a, b, pb]
        else:
            cells = self._cells.cells_to(fa, fb)
            if cells is None:
                return None
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
    shapes = collision_shapes(model)
    if bounds is None:
        bounds = shapes.bounds(spec.margin)
    return [NavGrid._from_shapes(shapes, z, spec, bounds) for z in floors]
