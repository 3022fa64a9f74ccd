"""Grid helpers for graph proxies: rasterising discs and corridors, merging cells into boxes."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Grid:
    """A regular plan-view grid; cell (r, c) starts at ``(x0 + c·cell, y0 + r·cell)``."""

    x0: float
    y0: float
    cell: float
    shape: tuple[int, int]

    @classmethod
    def around(cls, xy: np.ndarray, margin: float, cell: float) -> Grid:
        """A grid covering points ``xy`` plus ``margin`` on every side."""
        lo = np.floor((xy.min(axis=0) - margin) / cell) * cell
        hi = np.ceil((xy.max(axis=0) + margin) / cell) * cell
        w, h = np.round((hi - lo) / cell).astype(int)
        return cls(float(lo[0]), float(lo[1]), cell, (int(h), int(w)))

    def window(self, lo: np.ndarray, hi: np.ndarray) -> tuple[slice, slice, np.ndarray, np.ndarray]:
        """Rows/cols slices covering the box [lo, hi] and the cell-centre coordinates there."""
        c0 = max(0, int(np.floor((lo[0] - self.x0) / self.cell)))
        c1 = min(self.shape[1], int(np.ceil((hi[0] - self.x0) / self.cell)) + 1)
        r0 = max(0, int(np.floor((lo[1] - self.y0) / self.cell)))
        r1 = min(self.shape[0], int(np.ceil((hi[1] - self.y0) / self.cell)) + 1)
        xs = self.x0 + (np.arange(c0, c1) + 0.5) * self.cell
        ys = self.y0 + (np.arange(r0, r1) + 0.5) * self.cell
        gx, gy = np.meshgrid(xs, ys)
        return slice(r0, r1), slice(c0, c1), gx, gy


def disc(grid: Grid, centre: np.ndarray, radius: float) -> tuple[tuple[slice, slice], np.ndarray]:
    """Cells near a disc: (window, distance to the centre) over the window."""
    rs, cs, gx, gy = grid.window(centre - radius, centre + radius)
    return (rs, cs), np.hypot(gx - centre[0], gy - centre[1])


def corridor(
    grid: Grid, a: np.ndarray, b: np.ndarray, half_width: float
) -> tuple[tuple[slice, slice], np.ndarray, np.ndarray]:
    """Cells near segment a-b: (window, distance to the segment, position t ∈ [0, 1] along it)."""
    rs, cs, gx, gy = grid.window(np.minimum(a, b) - half_width, np.maximum(a, b) + half_width)
    ab = b - a
    denom = float(ab @ ab) or 1.0
    t = np.clip(((gx - a[0]) * ab[0] + (gy - a[1]) * ab[1]) / denom, 0.0, 1.0)
    d = np.hypot(gx - (a[0] + t * ab[0]), gy - (a[1] + t * ab[1]))
    return (rs, cs), d, t


def merge_cells(mask: np.ndarray, key: np.ndarray) -> list[tuple[int, int, int, int, int]]:
    """Greedy rectangle cover of the cells where ``mask``, joining only equal ``key`` values.

    Returns:
        (row0, row1, col0, col1, key) rectangles, end-exclusive, covering each cell once.
    """
    rects: list[tuple[int, int, int, int, int]] = []
    open_runs: dict[tuple[int, int, int], int] = {}  # (c0, c1, key) -> first row
    for r in range(mask.shape[0]):
        row_mask, row_key = mask[r], key[r]
        runs = set()
        cols = np.flatnonzero(row_mask)
        if len(cols):
            # Split the row's cells into runs of consecutive columns with equal key.
            breaks = np.flatnonzero((np.diff(cols) != 1) | (np.diff(row_key[cols]) != 0)) + 1
            for seg in np.split(cols, breaks):
                runs.add((int(seg[0]), int(seg[-1]) + 1, int(row_key[seg[0]])))
        for run in list(open_runs):
            if run not in runs:
                rects.append((open_runs.pop(run), r, run[0], run[1], run[2]))
        for run in runs:
            open_runs.setdefault(run, r)
    for run, r0 in open_runs.items():
        rects.append((r0, mask.shape[0], run[0], run[1], run[2]))
    return sorted(rects)
