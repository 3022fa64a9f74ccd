"""Grid helpers for graph proxies: rasterising discs and corridors, covering cells with boxes."""

from __future__ import annotations

from collections.abc import Iterator
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


def disc(
    grid: Grid, centre: np.ndarray, radius: float
) -> tuple[tuple[slice, slice], np.ndarray, np.ndarray]:
    """Cells near a disc: (window, distance and Chebyshev distance to the centre)."""
    rs, cs, gx, gy = grid.window(centre - radius, centre + radius)
    dx, dy = np.abs(gx - centre[0]), np.abs(gy - centre[1])
    return (rs, cs), np.hypot(dx, dy), np.maximum(dx, dy)


def corridor(
    grid: Grid, a: np.ndarray, b: np.ndarray, half_width: float
) -> tuple[tuple[slice, slice], np.ndarray, np.ndarray, np.ndarray]:
    """Cells near segment a-b.

    Returns:
        The window, and over it each cell's distance and Chebyshev distance to the segment
        and its position t ∈ [0, 1] along it.
    """
    rs, cs, gx, gy = grid.window(np.minimum(a, b) - half_width, np.maximum(a, b) + half_width)
    ab = b - a
    denom = float(ab @ ab) or 1.0
    t = np.clip(((gx - a[0]) * ab[0] + (gy - a[1]) * ab[1]) / denom, 0.0, 1.0)
    d = np.hypot(gx - (a[0] + t * ab[0]), gy - (a[1] + t * ab[1]))
    return (rs, cs), d, chebyshev(gx - a[0], gy - a[1], ab), t


def chebyshev(qx: np.ndarray, qy: np.ndarray, ab: np.ndarray) -> np.ndarray:
    """Chebyshev (max-norm) distance from points ``(qx, qy)`` to the segment from 0 to ``ab``.

    The distance along the segment, ``max(|qx − t·abx|, |qy − t·aby|)``, is convex and
    piecewise linear in t: its minimum over [0, 1] lies at an end or where a term vanishes or
    the two terms meet.
    """
    ux, uy = float(ab[0]), float(ab[1])
    cands = [np.zeros_like(qx), np.ones_like(qx)]
    for num, den in ((qx, ux), (qy, uy), (qx - qy, ux - uy), (qx + qy, ux + uy)):
        if abs(den) > 1e-12:
            cands.append(np.clip(num / den, 0.0, 1.0))
    return np.min([np.maximum(np.abs(qx - t * ux), np.abs(qy - t * uy)) for t in cands], axis=0)


def neighbours(arr: np.ndarray, n: int) -> Iterator[np.ndarray]:
    """``arr`` shifted by every offset of up to ``n`` cells in each axis (nan past its edges).

    Each yielded array holds, at each cell, the value of one neighbour of that cell.
    """
    h, w = arr.shape
    pad = np.pad(arr.astype(float), n, constant_values=np.nan)
    for dr in range(2 * n + 1):
        for dc in range(2 * n + 1):
            yield pad[dr : dr + h, dc : dc + w]


def cover_cells(key: np.ndarray, spare: np.ndarray) -> list[tuple[int, int, int, int, int]]:
    """Greedy rectangle cover of the cells where ``key >= 0``, each rectangle of one key.

    A rectangle may also take ``spare`` cells (where any box may stand), so rectangles grow
    past ragged outlines instead of following them. They may overlap on spare cells but never
    on a keyed cell (a foot standing there would touch every box covering it).

    Returns:
        (row0, row1, col0, col1, key) rectangles, end-exclusive.
    """
    rects: list[tuple[int, int, int, int, int]] = []
    for k in np.unique(key[key >= 0]).tolist():
        need = key == k
        rows, cols = np.nonzero(need)
        r0, r1, c0, c1 = rows.min(), rows.max() + 1, cols.min(), cols.max() + 1
        need = need[r0:r1, c0:c1].copy()
        spare_k = spare[r0:r1, c0:c1]
        allow = need | spare_k
        h, w = need.shape
        for r in range(h):
            while True:
                todo = np.flatnonzero(need[r])
                if not len(todo):
                    break
                c = int(todo[0])
                best = None
                for across_first in (True, False):
                    if across_first:
                        a = c - _run(allow[r, :c][::-1])
                        e = c + _run(allow[r, c:])
                        b = r + 1
                        while b < h and allow[b, a:e].all():
                            b += 1
                    else:
                        a, e, b = c, c + 1, r + _run(allow[r:, c])
                        while a > 0 and allow[r:b, a - 1].all():
                            a -= 1
                        while e < w and allow[r:b, e].all():
                            e += 1
                    gain = int(need[r:b, a:e].sum())
                    if best is None or gain > best[0]:
                        best = (gain, a, b, e)
                _, a, b, e = best
                need[r:b, a:e] = False
                allow[r:b, a:e] = spare_k[r:b, a:e]
                rects.append((int(r0 + r), int(r0 + b), int(c0 + a), int(c0 + e), int(k)))
    return rects


def cover_rows(key: np.ndarray) -> np.ndarray:
    """Rectangles one row high covering each run of equal ``key >= 0`` along each row.

    Many more rectangles than :func:`cover_cells` gives, but in a few array operations: for
    drafts that are checked, not kept.

    Returns:
        (n, 5) rectangles (row0, row1, col0, col1, key), end-exclusive.
    """
    padded = np.pad(key, ((0, 0), (1, 1)), constant_values=-1)
    rows, cols = np.nonzero(padded[:, 1:] != padded[:, :-1])  # a run starts or ends before col
    same_row = rows[:-1] == rows[1:]
    r, c0, c1 = rows[:-1][same_row], cols[:-1][same_row], cols[1:][same_row]
    k = key[r, c0]
    keep = k >= 0
    return np.column_stack([r[keep], r[keep] + 1, c0[keep], c1[keep], k[keep]])


def _run(line: np.ndarray) -> int:
    """Length of the leading run of True in ``line``."""
    stop = np.flatnonzero(~line)
    return int(stop[0]) if len(stop) else len(line)
