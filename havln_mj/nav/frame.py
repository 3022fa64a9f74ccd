"""The cell lattice of a grid: where its cells lie in the world, and points to cells and back."""

from __future__ import annotations

import math

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.nav.spec import point_xy, points_xy

MAX_CELLS = 40_000_000  # guards against absurd bounds or resolutions


class GridFrame:
    """A regular lattice of square cells in the plan view.

    Cell (row, col) covers x in ``[x0 + col·res, x0 + (col + 1)·res)`` and y in
    ``[y0 + row·res, y0 + (row + 1)·res)``: rows grow with y, so pictures of the grid are
    drawn with ``origin="lower"``. Points may be given as (x, y) or (x, y, z); z is ignored.

    Attributes:
        origin: (x0, y0), the world position of the lattice's lower-left corner.
        resolution: Cell size in metres.
    """

    def __init__(self, origin: object, resolution: float, shape: tuple[int, int]) -> None:
        """Places the lattice.

        Args:
            origin: (x0, y0) of the lower-left corner.
            resolution: Cell size in metres.
            shape: (H, W) cells.

        Raises:
            InvalidArgumentError: ``origin`` is not a finite point.
        """
        self.origin = tuple(float(v) for v in point_xy(origin, "origin"))
        self.resolution = resolution
        self._shape = (int(shape[0]), int(shape[1]))

    @staticmethod
    def covering(
        bounds: tuple[float, float, float, float], resolution: float
    ) -> tuple[tuple[float, float], tuple[int, int]]:
        """Origin and (H, W) of a lattice covering ``bounds``, aligned to whole cells.

        Raises:
            InvalidArgumentError: Bounds that are not a finite, non-empty box, or a lattice of
                more than ``MAX_CELLS`` cells.
        """
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
        res = resolution
        eps = 1e-9
        c0, r0 = math.floor(xmin / res + eps), math.floor(ymin / res + eps)
        c1, r1 = math.ceil(xmax / res - eps), math.ceil(ymax / res - eps)
        width, height = max(c1 - c0, 1), max(r1 - r0, 1)
        if width * height > MAX_CELLS:
            raise InvalidArgumentError(
                f"a grid of {height} x {width} cells (bounds {bounds!r}, resolution {res!r}) "
                f"exceeds {MAX_CELLS} cells; pass smaller bounds or a coarser resolution"
            )
        return (c0 * res, r0 * res), (height, width)

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W): rows (along y) and columns (along x)."""
        return self._shape

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
        p = points_xy(xy, "xy")
        cr = np.floor((p - self.origin) / self.resolution).astype(np.int64)
        return cr[..., ::-1]

    def to_cell(self, xy: object) -> tuple[int, int]:
        """The (row, col) of the cell holding one point.

        Raises:
            InvalidArgumentError: The point is not a finite point or lies outside the grid.
        """
        p = point_xy(xy, "xy")
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
        inside = self._inside(self.to_cells(xy))
        return bool(inside) if inside.ndim == 0 else inside

    def _inside(self, rc: np.ndarray) -> np.ndarray:
        h, w = self.shape
        return (rc[..., 0] >= 0) & (rc[..., 0] < h) & (rc[..., 1] >= 0) & (rc[..., 1] < w)

    def _cell_of(self, p: np.ndarray) -> tuple[int, int]:
        """(row, col) of one (2,) point, unchecked: the scalar fast path of ``to_cells``."""
        c = math.floor((p[0] - self.origin[0]) / self.resolution)
        r = math.floor((p[1] - self.origin[1]) / self.resolution)
        return r, c

    def _centre(self, r: int, c: int) -> np.ndarray:
        """World (x, y) of one cell's centre: the scalar fast path of ``to_world``."""
        return np.array(
            [
                self.origin[0] + (c + 0.5) * self.resolution,
                self.origin[1] + (r + 0.5) * self.resolution,
            ]
        )
