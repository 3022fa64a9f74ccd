"""A building synthesised from a navigation graph (a "graph proxy").

Free floor is the union of a disc around every included viewpoint and a corridor along every
edge, each at its own floor height (viewpoint z − height; interpolated along an edge, which
makes stairs of edges that climb). Elements whose floors would overlap at different heights go
to separate layers, so storeys stacked above each other each keep their floor. Each layer's
free cells become floor slabs; the cells around them become walls, except where another layer
needs that space to walk. Cells where two graph components meet become walls too, so
viewpoints that are not connected in the graph are not connected in the building either.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import binary_dilation

from havln_mj.errors import InvalidArgumentError
from havln_mj.scene.boxes import BoxSet
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.proxy.raster import Grid, corridor, cover_cells, disc

_FLOOR_RGBA = (0.62, 0.55, 0.45, 1.0)
_STAIR_RGBA = (0.50, 0.42, 0.34, 1.0)
_WALL_RGBA = (0.86, 0.85, 0.80, 1.0)
_EIGHT = np.ones((3, 3), dtype=bool)
_EPS_D = 0.05  # metres: keeps element weights finite at their centre
_NEAR = 4  # cells: within this of another layer's floor, boxes keep to their own cells


@dataclass(frozen=True)
class ProxyParams:
    """How a graph proxy is drawn.

    Attributes:
        cell: Grid resolution in metres.
        viewpoint_radius: Free floor around each viewpoint.
        corridor_half_width: Free floor on each side of an edge.
        layer_gap: Floors differing by more than this in one cell go to separate layers.
        wall_height: Wall height above the floor beside it.
        slab: Floor and stair slab thickness.
        stair_rise: An edge climbing more than this is drawn as stairs (its own material).
        headroom: Floors this far apart may overlap (storeys); closer ones may not.
        body_radius: Radius of the body whose walkability is checked.
        body_z: Heights above the floor the body's trunk occupies: a step lower than the
            band's bottom beside the path is stepped over, not bumped into.
        step: Largest rise or drop between neighbouring points of a path (a stair riser).
    """

    cell: float = 0.1
    viewpoint_radius: float = 0.9
    corridor_half_width: float = 0.5
    layer_gap: float = 1.0
    headroom: float = 2.1
    wall_height: float = 2.5
    slab: float = 0.1
    stair_rise: float = 0.3
    body_radius: float = 0.2
    body_z: tuple[float, float] = (0.3, 1.8)
    step: float = 0.2

    def __post_init__(self) -> None:
        if not 0.02 <= self.cell <= 0.5:
            raise InvalidArgumentError(f"ProxyParams.cell={self.cell!r}; valid: 0.02–0.5 m")
        if self.corridor_half_width < self.body_radius + self.cell:
            raise InvalidArgumentError(
                f"ProxyParams.corridor_half_width={self.corridor_half_width!r} must be at least "
                f"body_radius + cell = {self.body_radius + self.cell:.2f} m"
            )


@dataclass
class _Layer:
    wsum: np.ndarray  # sum of element weights per cell
    whsum: np.ndarray  # weighted sum of element floor heights
    dist: np.ndarray  # distance to the nearest element covering the cell
    comp: np.ndarray  # graph component of that element, -1 where not free
    stair: np.ndarray  # whether that element is a climbing edge

    @classmethod
    def empty(cls, shape: tuple[int, int]) -> _Layer:
        return cls(
            np.zeros(shape),
            np.zeros(shape),
            np.full(shape, np.inf),
            np.full(shape, -1),
            np.zeros(shape, bool),
        )

    def clear(
        self, cells: np.ndarray, window: tuple[slice, slice] = (slice(None), slice(None))
    ) -> None:
        """Makes ``cells`` (a mask over ``window`` of the grid) not free."""
        self.wsum[window][cells] = 0.0
        self.whsum[window][cells] = 0.0
        self.comp[window][cells] = -1
        self.stair[window][cells] = False
        self.dist[window][cells] = np.inf

    @property
    def free(self) -> np.ndarray:
        return self.wsum > 0

    @property
    def height(self) -> np.ndarray:
        """Blended floor height, nan where not free."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(self.free, self.whsum / self.wsum, np.nan)


def _place(layers, shape, window, mask, height, dist, comp, stair, p: ProxyParams) -> None:
    """Adds one element's cells to the layers, cell by cell.

    A cell joins the first layer whose floor there is within ``layer_gap`` of the element's
    (floors blend: each element weighs ``1 / (d + ε)`` at distance ``d``, so its own centre
    follows its height and the surface runs smoothly between neighbours). A floor between
    ``layer_gap`` and ``headroom`` away cannot share the cell: the nearer element keeps it. A
    floor at least ``headroom`` away is another storey, and the cell moves to the next layer.
    """
    remaining = mask.copy()
    k = 0
    while remaining.any():
        if k == len(layers):
            layers.append(_Layer.empty(shape))
        layer = layers[k]
        ws, whs, dd = layer.wsum[window], layer.whsum[window], layer.dist[window]
        with np.errstate(invalid="ignore", divide="ignore"):
            diff = np.abs(np.where(ws > 0, whs / ws, np.nan) - height)
        empty = remaining & (ws == 0)
        blend = remaining & (diff <= p.layer_gap)
        contested = remaining & (diff > p.layer_gap) & (diff < p.headroom)
        take = contested & (dist < dd)
        ws[take] = 0.0
        whs[take] = 0.0
        add = empty | blend | take
        w = np.where(add, 1.0 / (dist + _EPS_D), 0.0)
        ws += w
        whs += w * height
        nearer = add & (dist < dd)
        dd[nearer] = dist[nearer]
        layer.comp[window][nearer] = comp
        layer.stair[window][nearer] = stair
        remaining &= ~(empty | blend | contested)
        k += 1


def _rasterise(
    graph: NavGraph, grid: Grid, p: ProxyParams, comp_of: dict[str, int]
) -> list[_Layer]:
    layers: list[_Layer] = []
    nodes = sorted(graph.nodes, key=graph.floor_z)
    for vp in nodes:
        xy, f = graph.position(vp)[:2], graph.floor_z(vp)
        window, d = disc(grid, xy, p.viewpoint_radius)
        _place(
            layers,
            grid.shape,
            window,
            d <= p.viewpoint_radius,
            np.full(d.shape, f),
            d,
            comp_of[vp],
            False,
            p,
        )
    edges = sorted(graph.edges(), key=lambda e: min(graph.floor_z(e[0]), graph.floor_z(e[1])))
    for a, b, _ in edges:
        fa, fb = graph.floor_z(a), graph.floor_z(b)
        pa, pb = graph.position(a)[:2], graph.position(b)[:2]
        window, d, t = corridor(grid, pa, pb, p.corridor_half_width)
        stair = abs(fb - fa) > p.stair_rise
        mask, height = d <= p.corridor_half_width, fa + t * (fb - fa)
        _place(layers, grid.shape, window, mask, height, d, comp_of[a], stair, p)
    return layers


def _shifted(arr: np.ndarray, dr: int, dc: int) -> tuple[tuple[slice, slice], tuple[slice, slice]]:
    """Slices pairing each cell with its neighbour at offset (dr, dc)."""
    h, w = arr.shape
    first = (slice(max(dr, 0), h), slice(max(dc, 0), w + min(dc, 0)))
    second = (slice(0, h - dr), slice(max(-dc, 0), w - max(dc, 0)))
    return first, second


def _separate_components(layer: _Layer) -> None:
    """Walls off cells where two graph components touch (the higher-numbered side goes)."""
    comp = layer.comp
    cut = np.zeros(comp.shape, dtype=bool)
    for dr, dc in ((0, 1), (1, 0), (1, 1), (1, -1)):
        s1, s2 = _shifted(comp, dr, dc)
        a, b = comp[s1], comp[s2]
        both = (a >= 0) & (b >= 0) & (a != b)
        cut[s1] |= both & (a > b)
        cut[s2] |= both & (b > a)
    layer.clear(cut)


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
    grid: Grid, mask: np.ndarray, z0: np.ndarray, z1: np.ndarray, spare: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Boxes covering the cells of ``mask``, cell (r, c) spanning ``z0[r, c]..z1[r, c]``.

    Cells with equal spans share boxes, which may also stand on ``spare`` cells.

    Returns:
        lo, hi and the (row0, row1, col0, col1) cell rectangle of each box.
    """
    spans, inverse = np.unique(np.stack([z0[mask], z1[mask]], axis=1), axis=0, return_inverse=True)
    key = np.full(mask.shape, -1, dtype=np.int64)
    key[mask] = inverse.ravel()
    rects = np.array(cover_cells(key, spare), dtype=float).reshape(-1, 5)
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


def _layer_boxes(layers: list[_Layer], grid: Grid, p: ProxyParams) -> BoxSet:
    """Floor, stair and wall boxes of the layers.

    Boxes may reach over a layer's walls and past them where no other layer walks near:
    nothing stands there, and boxes that run on there instead of tracing the ragged outlines
    of discs and corridors are fewer (physics steps cost about linearly in boxes). Floor and
    stair cells of one height share boxes.
    """
    parts: list[tuple[np.ndarray, np.ndarray, str, str, tuple]] = []
    q = 0.05  # floor height quantum (a step a legged robot takes in its stride)
    frees = [layer.free for layer in layers]
    for k, layer in enumerate(layers):
        free, height = frees[k], layer.height
        others = np.zeros(free.shape, bool)
        for j, other in enumerate(frees):
            if j != k:
                others |= other
        near_other = binary_dilation(others, _EIGHT, iterations=_NEAR)
        nmin, nmax = _neighbour_extremes(height)
        wall = binary_dilation(free, _EIGHT) & ~free
        z0 = np.floor((nmin - p.slab) / q) * q
        z1 = np.ceil((nmax + p.wall_height) / 0.5) * 0.5  # wall tops need no precision
        for j, other in enumerate(layers):
            if j != k:
                # Leave space where another layer walks: its body band must stay clear.
                with np.errstate(invalid="ignore"):
                    blocks = (z0 < other.height + p.body_z[1]) & (z1 > other.height + p.body_z[0])
                wall &= ~(frees[j] & blocks)
        # Cells where a box may stand although none is needed: the layer's walls and what
        # lies beyond them, unless another layer walks near.
        spare = ~free & ~near_other
        top = np.round(np.nan_to_num(height) / q) * q
        # A box is stairs where most of its cells are.
        lo, hi, rects = _cell_boxes(grid, free, top - p.slab, top, spare)
        stairs = _rect_sums(free & layer.stair, rects) * 2 > _rect_sums(free, rects)
        parts.append((lo[~stairs], hi[~stairs], "floor", "floor", _FLOOR_RGBA))
        parts.append((lo[stairs], hi[stairs], "floor", "stairs", _STAIR_RGBA))
        parts.append((*_cell_boxes(grid, wall, z0, z1, spare)[:2], "wall", "wall", _WALL_RGBA))
    n = [len(lo) for lo, *_ in parts]
    return BoxSet(
        np.concatenate([lo for lo, *_ in parts]),
        np.concatenate([hi for _, hi, *_ in parts]),
        tuple(k for (_, _, k, _, _), m in zip(parts, n, strict=True) for _ in range(m)),
        tuple(mat for (_, _, _, mat, _), m in zip(parts, n, strict=True) for _ in range(m)),
        np.concatenate([np.tile(c, (m, 1)) for (*_, c), m in zip(parts, n, strict=True)]),
    )


@dataclass(frozen=True)
class Proxy:
    """A graph proxy's geometry and how well it serves the graph.

    Attributes:
        boxes: Floors, stairs and walls.
        grid: The plan grid the geometry was drawn on.
        free: Each layer's free cells.
        unwalkable: Edges a body cannot walk (see ``edge_walkability``).
    """

    boxes: BoxSet
    grid: Grid
    free: list[np.ndarray]
    unwalkable: list[tuple[str, str]]


def build_proxy(graph: NavGraph, params: ProxyParams | None = None) -> Proxy:
    """Draws the graph proxy of ``graph`` and checks every edge on it."""
    p = params or ProxyParams()
    xy = np.array([graph.position(v)[:2] for v in graph.nodes])
    grid = Grid.around(xy, p.viewpoint_radius + 3 * p.cell, p.cell)
    comp_of = {vp: k for k, members in enumerate(graph.components()) for vp in members}
    layers = _rasterise(graph, grid, p, comp_of)
    for layer in layers:
        _separate_components(layer)
    boxes = _layer_boxes(layers, grid, p)
    return Proxy(boxes, grid, [layer.free for layer in layers], unwalkable_edges(graph, boxes, p))


def edge_walkability(
    graph: NavGraph, boxes: BoxSet, params: ProxyParams | None = None
) -> dict[str, list[tuple[str, str]]]:
    """Checks every edge for a body walking it; returns the failing edges by cause.

    The body is sampled every half cell along the edge. Under each sample the support is the
    box top nearest to the floor height interpolated along the edge (within ``layer_gap``).
    An edge fails with ``"no_floor"`` where a sample has no support, ``"step"`` where the
    support changes by more than ``step`` between samples, and ``"blocked"`` where a box meets
    the body's square footprint (radius ``body_radius``) in the ``body_z`` band above the
    support (its bottom above the highest support within a body radius along the path, so
    the stairs ahead are not an obstacle).
    """
    p = params or ProxyParams()
    spacing = p.cell / 2
    out: dict[str, list[tuple[str, str]]] = {"no_floor": [], "step": [], "blocked": []}
    for a, b, length in graph.edges():
        n = max(2, int(np.ceil(length / spacing)) + 1)
        t = np.linspace(0.0, 1.0, n)[:, None]
        pa, pb = graph.position(a), graph.position(b)
        x = pa[0] + t * (pb[0] - pa[0])  # (n, 1)
        y = pa[1] + t * (pb[1] - pa[1])
        f = graph.floor_z(a) + t * (graph.floor_z(b) - graph.floor_z(a))
        lo, hi = boxes.lo[None], boxes.hi[None]  # (1, B, 3)
        over = (lo[..., 0] <= x) & (hi[..., 0] >= x) & (lo[..., 1] <= y) & (hi[..., 1] >= y)
        gap = np.where(over, np.abs(hi[..., 2] - f), np.inf)
        nearest = gap.argmin(axis=1)
        support = np.where(gap.min(axis=1) <= p.layer_gap, hi[0, nearest, 2], np.inf)
        if not np.isfinite(support).all():
            out["no_floor"].append((a, b))
            continue
        if np.abs(np.diff(support)).max(initial=0.0) > p.step + 1e-6:
            out["step"].append((a, b))
            continue
        r, s = p.body_radius, support[:, None]
        # On a slope the floor under the front of the body is higher than under its centre:
        # the band starts above the highest support within one body radius along the path.
        k = int(np.ceil(r / spacing))
        padded = np.pad(support, k, mode="edge")
        ahead = np.lib.stride_tricks.sliding_window_view(padded, 2 * k + 1).max(axis=1)[:, None]
        meets = (
            (lo[..., 0] < x + r)
            & (hi[..., 0] > x - r)
            & (lo[..., 1] < y + r)
            & (hi[..., 1] > y - r)
        )
        meets &= (lo[..., 2] < s + p.body_z[1]) & (hi[..., 2] > ahead + p.body_z[0])
        if meets.any():
            out["blocked"].append((a, b))
    return out


def unwalkable_edges(
    graph: NavGraph, boxes: BoxSet, params: ProxyParams | None = None
) -> list[tuple[str, str]]:
    """All edges that ``edge_walkability`` finds a body cannot walk."""
    return [e for edges in edge_walkability(graph, boxes, params).values() for e in edges]
