"""Free floor of a graph proxy on a plan grid, in layers of non-overlapping floor.

Free floor is the union of a disc around every included viewpoint and a corridor along every
drawn edge, each at its own floor height (viewpoint z − height; interpolated along an edge,
which makes stairs of edges that climb). Elements whose floors would overlap at different
heights go to separate layers, so storeys stacked above each other each keep their floor.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.proxy.params import ProxyParams
from havln_mj.scene.proxy.raster import Grid, corridor, disc

Edge = tuple[str, str]

_EPS_D = 0.05  # metres: keeps element weights finite at their centre
_MIN_WEIGHT = 0.05  # an element's weight at its very edge (its cells stay free)


@dataclass
class Layer:
    """One layer's free cells and what made them (per cell)."""

    wsum: np.ndarray  # sum of element weights per cell
    whsum: np.ndarray  # weighted sum of element floor heights
    dist: np.ndarray  # distance to the nearest element covering the cell
    comp: np.ndarray  # graph component of that element, -1 where not free
    stair: np.ndarray  # whether that element is a climbing edge

    @classmethod
    def empty(cls, shape: tuple[int, int]) -> Layer:
        """A layer with no free cell."""
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
        """Whether each cell has floor."""
        return self.wsum > 0

    @property
    def height(self) -> np.ndarray:
        """Blended floor height, nan where not free."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(self.free, self.whsum / self.wsum, np.nan)


def _place(layers, shape, window, mask, height, dist, reach, comp, stair, p: ProxyParams) -> None:
    """Adds one element's cells to the layers, cell by cell.

    A cell joins the first layer whose floor there is within ``layer_gap`` of the element's
    (floors blend: each element weighs ``1 / (d + ε) − 1 / (reach + ε)`` at distance ``d``, so
    its own centre follows its height and its weight fades to nothing at its edge, where the
    surface runs smoothly on into its neighbours instead of jumping). A floor between
    ``layer_gap`` and ``headroom`` away cannot share the cell: the nearer element keeps it. A
    floor at least ``headroom`` away is another storey, and the cell moves to the next layer.
    """
    remaining = mask.copy()
    k = 0
    while remaining.any():
        if k == len(layers):
            layers.append(Layer.empty(shape))
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
        fade = np.maximum(1.0 / (dist + _EPS_D) - 1.0 / (reach + _EPS_D), _MIN_WEIGHT)
        w = np.where(add, fade, 0.0)
        ws += w
        whs += w * height
        nearer = add & (dist < dd)
        dd[nearer] = dist[nearer]
        layer.comp[window][nearer] = comp
        layer.stair[window][nearer] = stair
        remaining &= ~(empty | blend | contested)
        k += 1


def rasterise(
    graph: NavGraph, edges: list[Edge], grid: Grid, p: ProxyParams, comp_of: dict[str, int]
) -> list[Layer]:
    """The layers of free floor of the viewpoints and ``edges``, lowest elements first."""
    layers: list[Layer] = []
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
            p.viewpoint_radius,
            comp_of[vp],
            False,
            p,
        )
    for a, b in sorted(edges, key=lambda e: min(graph.floor_z(e[0]), graph.floor_z(e[1]))):
        fa, fb = graph.floor_z(a), graph.floor_z(b)
        pa, pb = graph.position(a)[:2], graph.position(b)[:2]
        window, d, t = corridor(grid, pa, pb, p.corridor_half_width)
        stair = abs(fb - fa) > p.stair_rise
        mask, height = d <= p.corridor_half_width, fa + t * (fb - fa)
        reach = p.corridor_half_width
        _place(layers, grid.shape, window, mask, height, d, reach, comp_of[a], stair, p)
    return layers


def _shifted(arr: np.ndarray, dr: int, dc: int) -> tuple[tuple[slice, slice], tuple[slice, slice]]:
    """Slices pairing each cell with its neighbour at offset (dr, dc)."""
    h, w = arr.shape
    first = (slice(max(dr, 0), h), slice(max(dc, 0), w + min(dc, 0)))
    second = (slice(0, h - dr), slice(max(-dc, 0), w - max(dc, 0)))
    return first, second


def separate_components(layer: Layer) -> None:
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
