"""Boxes of a graph proxy's layers: floors and stairs in cells, and walls.

Each layer's free cells become floor boxes at their blended height, rounded to 2 cm: a stair
is a rough ramp at its edge's grade whose ledges the GO1's blind trot steps over (at 5 cm, one
graph action in ten tripped it on flat floors alone). The cells around a layer's free cells
become walls, except where another layer needs that space to walk: a wall within reach of a
body walking another floor ends below its band or starts above it. A floor slab over a
walkway is thinned (down to ``min_slab``) to keep the band of the bodies below clear.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import binary_dilation, maximum_filter

from havln_mj.scene.boxes import BoxSet
from havln_mj.scene.proxy.layers import (
    FLOOR_QUANTUM,
    Disc,
    Layer,
    Leg,
    clear_overhangs,
    rasterise,
    separate_components,
)
from havln_mj.scene.proxy.params import ProxyParams
from havln_mj.scene.proxy.raster import Grid, cover_cells, cover_rows, neighbours
from havln_mj.scene.proxy.seams import LipRoom, overlap_seams

FLOOR_RGBA = (0.62, 0.55, 0.45, 1.0)
STAIR_RGBA = (0.50, 0.42, 0.34, 1.0)
WALL_RGBA = (0.86, 0.85, 0.80, 1.0)
_EIGHT = np.ones((3, 3), dtype=bool)
_NEAR = 4  # cells: within this of another layer's floor, boxes keep to their own cells
_Q = FLOOR_QUANTUM
_EPS = 1e-6  # metres
_WALL_Q = 0.1  # wall top quantum under another layer's floor


def draw_elements(
    discs: list[Disc], legs: list[Leg], grid: Grid, p: ProxyParams, draft: bool = False
) -> tuple[list[Layer], BoxSet]:
    """The layers of free floor of ``discs`` and ``legs`` on ``grid``, and their boxes.

    Floor that would hang in a body's way is cleared and graph components are walled apart
    before the boxes are drawn (``draft``: see :func:`layer_boxes`).
    """
    layers = rasterise(discs, legs, grid, p)
    clear_overhangs(layers, p)
    for layer in layers:
        separate_components(layer)
    return layers, layer_boxes(layers, grid, p, draft)


def layer_boxes(layers: list[Layer], grid: Grid, p: ProxyParams, draft: bool = False) -> BoxSet:
    """Floor, stair and wall boxes of the layers.

    Boxes may reach over a layer's walls and past them where no other layer walks near:
    nothing stands there, and boxes that run on there instead of tracing the ragged outlines
    of discs and corridors are fewer. Floor cells of one height share boxes; within a layer
    no two floor boxes cover the same free cell (each would be one more contact to solve),
    except the strip where one reaches over a neighbour of its height
    (:func:`~havln_mj.scene.proxy.seams.overlap_seams`).
    A ``draft`` covers each row's runs of cells instead: the same cells, quickly, in many more
    boxes, none past the cells it covers (for trying a drawing out, not for keeping).
    """
    sets: list[BoxSet] = []
    frees = [layer.free for layer in layers]
    if not draft:
        tops = np.stack([_top(layer.height) for layer in layers])
        supports = np.where([layer.line for layer in layers], tops, np.nan)
        # Per floor top, the cell edges lips cover (see overlap_seams).
        covered: dict[float, tuple[np.ndarray, np.ndarray]] = {}
    for k, layer in enumerate(layers):
        free, height = frees[k], layer.height
        others = np.zeros(free.shape, bool)
        for j, other in enumerate(frees):
            if j != k:
                others |= other
        near_other = binary_dilation(others, _EIGHT, iterations=_NEAR)
        nmin, nmax = _neighbour_extremes(height)
        wall = binary_dilation(free, _EIGHT) & ~free
        z0 = np.floor((nmin - p.slab) / _Q) * _Q
        z1 = np.ceil((nmax + p.wall_height) / 0.5) * 0.5  # wall tops need no precision
        for j, other in enumerate(layers):
            if j != k:
                z0, z1 = _clear_bodies(z0, z1, frees[j], _top(other.height), p)
        wall &= z1 > z0 + _Q / 2
        # Cells where a box may stand although none is needed: the layer's walls and what
        # lies beyond them, unless another layer walks near.
        spare = ~free & ~near_other
        top = _top(np.nan_to_num(height))
        under = _underside(top, layers, p)
        lo, hi, rects = _cell_boxes(grid, free, under, top, spare, draft)
        if not draft:
            walls = np.where(wall, z0, np.nan), np.where(wall, z1, np.nan)
            room = LipRoom(tops, supports, spare, *walls, p)
            lo, hi = overlap_seams(lo, hi, rects, room, covered)
        # A box is stairs where most of its cells are.
        stairs = _rect_sums(free & layer.stair, rects) * 2 > _rect_sums(free, rects)
        sets.append(_set(lo[~stairs], hi[~stairs], "floor", "floor", FLOOR_RGBA))
        sets.append(_set(lo[stairs], hi[stairs], "floor", "stairs", STAIR_RGBA))
        walls = _cell_boxes(grid, wall, z0, z1, spare, draft)[:2]
        sets.append(_set(*walls, "wall", "wall", WALL_RGBA))
    return BoxSet(
        np.concatenate([b.lo for b in sets]).reshape(-1, 3),
        np.concatenate([b.hi for b in sets]).reshape(-1, 3),
        tuple(k for b in sets for k in b.kind),
        tuple(m for b in sets for m in b.material),
        np.concatenate([b.rgba for b in sets]).reshape(-1, 4),
    )


def _set(lo: np.ndarray, hi: np.ndarray, kind: str, material: str, rgba: tuple) -> BoxSet:
    return BoxSet(lo, hi, (kind,) * len(lo), (material,) * len(lo), np.tile(rgba, (len(lo), 1)))


def _top(height: np.ndarray) -> np.ndarray:
    """The drawn floor tops of floor heights ``height`` (rounded to ``_Q``)."""
    return np.round(height / _Q) * _Q


def _underside(top: np.ndarray, layers: list[Layer], p: ProxyParams) -> np.ndarray:
    """Floor slab bottoms under tops ``top``: ``slab`` below, or thinner over a walkway.

    A body walking a path (standing on its line cells) below the floor, within reach of the
    cell, keeps its band clear: the slab's underside rises to the band's top, leaving the
    slab at least ``min_slab`` thick.
    """
    under = top - p.slab
    for layer in layers:
        support = np.where(layer.line & layer.free, _top(layer.height), np.nan)
        for below in neighbours(support, p.reach_cells):
            with np.errstate(invalid="ignore"):
                lift = below + p.body_z[0] < top
            raised = np.maximum(under, np.minimum(below + p.body_z[1], top - p.min_slab))
            under = np.where(lift, raised, under)
    return under


def _clear_bodies(
    z0: np.ndarray, z1: np.ndarray, free: np.ndarray, height: np.ndarray, p: ProxyParams
) -> tuple[np.ndarray, np.ndarray]:
    """Wall spans ``z0..z1`` clear of the bodies walking another layer's floor (tops ``height``).

    A wall stops under a floor of the other layer above its foot. A body standing on the
    other layer reaches the walls within ``body_radius`` of its footprint's centre, which
    stands on a free cell at most ``reach_cells`` away: a wall whose span meets the body band
    over the floors within that reach is dropped where the other layer is free, else ends
    below the band (the other layer lies above its foot) or starts above it (below its foot).
    """
    with np.errstate(invalid="ignore"):
        above = free & (height > z0)
        under = np.floor((height - p.slab) / _WALL_Q) * _WALL_Q
        z1 = np.where(above, np.minimum(z1, under), z1)
        size = 2 * p.reach_cells + 1
        lo = -maximum_filter(np.where(free, -height, -np.inf), size=size)
        hi = maximum_filter(np.where(free, height, -np.inf), size=size)
        meets = (z0 < hi + p.body_z[1]) & (z1 > lo + p.body_z[0])
        over = meets & (lo > z0)
        # A hair's margin, so that the check's own sums cannot round into the wall.
        below = np.floor((lo + p.body_z[0] - _EPS) / _Q) * _Q
        z1 = np.where(over, np.minimum(z1, below), z1)
        above_band = np.ceil((hi + p.body_z[1] + _EPS) / _Q) * _Q
        z0 = np.where(meets & ~over, np.maximum(z0, above_band), z0)
        z1 = np.where(free & meets, -np.inf, z1)
    return z0, z1


def _neighbour_extremes(height: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Min and max floor height over each cell's 8 neighbours (nan where none is free)."""
    pad = np.pad(height, 1, constant_values=np.nan)
    h, w = height.shape
    stack = np.stack(
        [
            pad[1 + dr : 1 + dr + h, 1 + dc : 1 + dc + w]
            for dr in (-1, 0, 1)
            for dc in (-1, 0, 1)
            if dr or dc
        ]
    )
    none = np.isnan(stack).all(axis=0)
    filled = np.where(np.isnan(stack), np.inf, stack)
    nmin = np.where(none, np.nan, filled.min(axis=0))
    nmax = np.where(none, np.nan, np.where(np.isnan(stack), -np.inf, stack).max(axis=0))
    return nmin, nmax


def _cell_boxes(
    grid: Grid,
    mask: np.ndarray,
    z0: np.ndarray,
    z1: np.ndarray,
    spare: np.ndarray,
    draft: bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Boxes covering the cells of ``mask``, cell (r, c) spanning ``z0[r, c]..z1[r, c]``.

    Cells with equal spans share boxes, which may also stand on ``spare`` cells (a ``draft``
    covers runs along rows instead, see :func:`layer_boxes`).

    Returns:
        lo, hi and the (row0, row1, col0, col1) cell rectangle of each box.
    """
    spans, inverse = np.unique(np.stack([z0[mask], z1[mask]], axis=1), axis=0, return_inverse=True)
    key = np.full(mask.shape, -1, dtype=np.int64)
    key[mask] = inverse.ravel()
    cover = cover_rows(key) if draft else cover_cells(key, spare)
    rects = np.array(cover, dtype=float).reshape(-1, 5)
    s = grid.cell
    lo = np.column_stack(
        [grid.x0 + rects[:, 2] * s, grid.y0 + rects[:, 0] * s, spans[rects[:, 4].astype(int), 0]]
    )
    hi = np.column_stack(
        [grid.x0 + rects[:, 3] * s, grid.y0 + rects[:, 1] * s, spans[rects[:, 4].astype(int), 1]]
    )
    return lo, hi, rects[:, :4].astype(int)


def _rect_sums(mask: np.ndarray, rects: np.ndarray) -> np.ndarray:
    """Number of ``mask`` cells in each (row0, row1, col0, col1) rectangle."""
    c = np.pad(np.cumsum(np.cumsum(mask, axis=0), axis=1), ((1, 0), (1, 0)))
    r0, r1, c0, c1 = rects.T
    return c[r1, c1] - c[r0, c1] - c[r1, c0] + c[r0, c0]
