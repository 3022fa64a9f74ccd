"""Free floor of a graph proxy on a plan grid, in layers of non-overlapping floor.

Free floor is the union of a disc around every included viewpoint and a corridor along every
drawn edge, each at its own floor height (viewpoint z − height; interpolated along an edge,
which makes stairs of edges that climb). Elements whose floors would overlap at different
heights go to separate layers, so storeys stacked above each other each keep their floor.

Bodies walk the paths (viewpoints and edges) and reach the cells around them; the floors near
a path are drawn for them: a floor beside a path stays below the band of the body walking it
(a lower floor is never in a body's way), and where two floors are too close to stack, the
lower keeps the cells its bodies reach unless the higher one's path runs through them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.proxy.params import ProxyParams
from havln_mj.scene.proxy.raster import Grid, corridor, disc, neighbours

Edge = tuple[str, str]

_EPS_D = 0.05  # metres: keeps element weights finite at their centre
_MIN_WEIGHT = 0.05  # an element's weight at its very edge (its cells stay free)
_CAP = 0.2  # metres: floors within a body's reach stay this close above its own
FLOOR_QUANTUM = 0.02  # metres: floor heights are drawn rounded to this
_TOL = 1e-6  # metres: a cell at the limit of a path's reach is within it


@dataclass
class Layer:
    """One layer's free cells and what made them (per cell).

    A cell's floor is the blend of the elements covering it, but no higher than ``_CAP``
    above any element whose walking body reaches the cell, unless a path runs through the
    cell (its support): a lower floor is never in a body's way.
    """

    wsum: np.ndarray  # sum of element weights per cell
    whsum: np.ndarray  # weighted sum of element floor heights
    cap: np.ndarray  # highest floor the bodies reaching the cell allow (inf: none reaches it)
    line: np.ndarray  # whether a path runs through the cell
    dist: np.ndarray  # distance to the nearest element covering the cell
    near: np.ndarray  # Chebyshev distance to the nearest path (viewpoint or edge) covering it
    comp: np.ndarray  # graph component of that element, -1 where not free
    stair: np.ndarray  # whether that element is a climbing edge
    base: np.ndarray  # that stair's bottom floor (nan where no stair)
    top: np.ndarray  # its top floor
    rise: np.ndarray  # and its riser height (signed)

    @classmethod
    def empty(cls, shape: tuple[int, int]) -> Layer:
        """A layer with no free cell."""
        return cls(
            wsum=np.zeros(shape),
            whsum=np.zeros(shape),
            cap=np.full(shape, np.inf),
            line=np.zeros(shape, bool),
            dist=np.full(shape, np.inf),
            near=np.full(shape, np.inf),
            comp=np.full(shape, -1),
            stair=np.zeros(shape, bool),
            base=np.full(shape, np.nan),
            top=np.full(shape, np.nan),
            rise=np.full(shape, np.nan),
        )

    def clear(
        self, cells: np.ndarray, window: tuple[slice, slice] = (slice(None), slice(None))
    ) -> None:
        """Makes ``cells`` (a mask over ``window`` of the grid) not free."""
        self.wsum[window][cells] = 0.0
        self.whsum[window][cells] = 0.0
        self.cap[window][cells] = np.inf
        self.line[window][cells] = False
        self.comp[window][cells] = -1
        self.stair[window][cells] = False
        self.base[window][cells] = np.nan
        self.top[window][cells] = np.nan
        self.rise[window][cells] = np.nan
        self.dist[window][cells] = np.inf
        self.near[window][cells] = np.inf

    @property
    def free(self) -> np.ndarray:
        """Whether each cell has floor."""
        return self.wsum > 0

    @property
    def height(self) -> np.ndarray:
        """Floor height, nan where not free."""
        return self.height_in((slice(None), slice(None)))

    def height_in(self, window: tuple[slice, slice]) -> np.ndarray:
        """Floor height over ``window`` of the grid, nan where not free."""
        w = window
        h = _height(self.wsum[w], self.whsum[w], self.cap[w], self.line[w])
        return stepped(h, self.base[w], self.top[w], self.rise[w])


def _height(wsum, whsum, cap, line) -> np.ndarray:
    """Floor height from a layer's sums (see :class:`Layer`), nan where not free."""
    with np.errstate(invalid="ignore", divide="ignore"):
        h = whsum / wsum
    return np.where(wsum > 0, np.where(line, h, np.minimum(h, cap)), np.nan)


def stepped(height: np.ndarray, base: np.ndarray, top: np.ndarray, rise: np.ndarray) -> np.ndarray:
    """Heights of stair cells moved onto their stair's treads.

    A cell between its stair's ``base`` and ``top`` floors, ``k`` risers up (the nearest whole
    number of ``rise`` above ``base``), stands at ``base + k·rise``, both on the
    ``FLOOR_QUANTUM`` grid: the risers then differ from ``rise`` by at most a quantum, and
    never exceed it rounded up to one. Cells beyond the stair's floors (where it blends into
    its landings) keep their height.
    """
    with np.errstate(invalid="ignore"):
        inside = (height - base) * (top - height) >= 0.0
    stair = np.isfinite(rise) & np.isfinite(height) & inside
    if not stair.any():
        return height
    out = height.copy()
    b, r = base[stair], rise[stair]
    k = np.round((height[stair] - b) / r)
    out[stair] = (
        np.round(b / FLOOR_QUANTUM) * FLOOR_QUANTUM
        + np.round(k * r / FLOOR_QUANTUM) * FLOOR_QUANTUM
    )
    return out


def _place(
    layers, shape, window, mask, height, dist, cheb, reach, comp, steps, p: ProxyParams
) -> None:
    """Adds one element's cells to the layers, cell by cell.

    A cell joins a layer whose floor there is within ``layer_gap`` of the element's (floors
    blend: each element weighs ``1 / (d + ε) − 1 / (reach + ε)`` at distance ``d``, so
    its own centre follows its height and its weight fades to nothing at its edge, where the
    surface runs smoothly on into its neighbours instead of jumping). A floor between
    ``layer_gap`` and ``headroom`` away cannot share the cell (see :func:`_lower_wins`). A
    floor at least ``headroom`` away is another storey, and the cell moves to the next layer.
    ``cheb`` is each cell's Chebyshev distance to the element's path (its viewpoint, or its
    edge's segment).
    """
    remaining = mask.copy()
    for layer in layers:  # blend into a layer close enough, wherever it stands
        blend = remaining & (np.abs(layer.height_in(window) - height) <= p.layer_gap)
        _add(layer, window, blend, height, dist, cheb, reach, comp, steps, p)
        remaining &= ~blend
    k = 0
    while remaining.any():
        if k == len(layers):
            layers.append(Layer.empty(shape))
        layer = layers[k]
        h = layer.height_in(window)
        with np.errstate(invalid="ignore"):
            empty = remaining & np.isnan(h)
            contested = remaining & (np.abs(h - height) < p.headroom)
            lower = height < h
        nn = layer.near[window]
        low_wins = _lower_wins(np.where(lower, cheb, nn), np.where(lower, nn, cheb), p)
        new_wins = np.where(np.isnan(low_wins), dist < layer.dist[window], low_wins == lower)
        take = contested & new_wins
        layer.clear(take, window)
        _add(layer, window, empty | take, height, dist, cheb, reach, comp, steps, p)
        remaining &= ~(empty | contested)
        k += 1


def _add(layer, window, add, height, dist, cheb, reach, comp, steps, p: ProxyParams) -> None:
    """Adds an element's floor to the cells ``add`` (a mask over ``window``) of ``layer``.

    ``steps`` is a stair's :func:`stair_steps` or None for a floor without steps.
    """
    ws, whs, dd, nn = (
        layer.wsum[window],
        layer.whsum[window],
        layer.dist[window],
        layer.near[window],
    )
    fade = np.maximum(1.0 / (dist + _EPS_D) - 1.0 / (reach + _EPS_D), _MIN_WEIGHT)
    w = np.where(add, fade, 0.0)
    ws += w
    whs += w * height
    nn[add] = np.minimum(nn[add], cheb[add])
    body = add & (cheb <= p.body_radius + p.cell / 2 + _TOL)
    cap = layer.cap[window]
    cap[body] = np.minimum(cap[body], height[body] + _CAP)
    layer.line[window][add & (cheb <= p.cell / 2 + _TOL)] = True
    nearer = add & (dist < dd)
    dd[nearer] = dist[nearer]
    layer.comp[window][nearer] = comp
    layer.stair[window][nearer] = steps is not None
    base, top, rise = steps if steps is not None else (np.nan, np.nan, np.nan)
    layer.base[window][nearer] = base
    layer.top[window][nearer] = top
    layer.rise[window][nearer] = rise


def _lower_wins(low: np.ndarray, high: np.ndarray, p: ProxyParams) -> np.ndarray:
    """Which of two floors too close to stack keeps a cell.

    ``low`` and ``high`` are the Chebyshev distances from the cell to the nearest path on
    each floor. A body standing on the lower floor within reach of the cell (``body_radius``
    plus half a cell) would meet the higher floor's slab in its band, while a lower floor is
    never in a body's way: the lower floor keeps the cell unless the higher floor's path runs
    through it (its support), and the higher floor keeps a cell that only its own bodies reach.

    Returns:
        Per cell 1.0 where the lower floor keeps it, 0.0 the higher, nan the one nearer its
        element (neither or both need it).
    """
    reach, line = p.body_radius + p.cell / 2 + _TOL, p.cell / 2 + _TOL
    low_reach, high_line, high_reach = low <= reach, high <= line, high <= reach
    out = np.full(low.shape, np.nan)
    out[low_reach & ~high_line] = 1.0
    out[~low_reach & high_reach] = 0.0
    return out


class Disc(NamedTuple):
    """A viewpoint's free floor: a disc of ``viewpoint_radius`` at its floor height."""

    xy: np.ndarray
    floor: float
    comp: int


class Leg(NamedTuple):
    """A straight walk's free floor: a corridor from ``a`` (floor ``fa``) to ``b`` (``fb``).

    The corridor is ``corridor_half_width`` wide on each side; its height is interpolated,
    and where it climbs as a stair cut into treads and risers when ``stepped`` (see
    :func:`stair_steps`).
    """

    a: np.ndarray
    b: np.ndarray
    fa: float
    fb: float
    comp: int
    stepped: bool = False


def graph_elements(
    graph: NavGraph, edges: list[Edge], comp_of: dict[str, int]
) -> tuple[list[Disc], list[Leg]]:
    """The discs of all viewpoints and the legs of ``edges``."""
    discs = [Disc(graph.position(v)[:2], graph.floor_z(v), comp_of[v]) for v in graph.nodes]
    legs = [
        Leg(graph.position(a)[:2], graph.position(b)[:2], graph.floor_z(a), graph.floor_z(b),
            comp_of[a])
        for a, b in edges
    ]  # fmt: skip
    return discs, legs


def stair_steps(fa: float, fb: float, p: ProxyParams) -> tuple[float, float, float] | None:
    """(first floor, last floor, riser) of a corridor from ``fa`` to ``fb``; None unless a stair.

    A corridor climbing more than ``stair_rise`` is a stair of equal risers no higher than
    ``riser``, its first at ``fa``.
    """
    if abs(fb - fa) <= p.stair_rise:
        return None
    n = int(np.ceil(abs(fb - fa) / p.riser - 1e-9))
    return fa, fb, (fb - fa) / n


def rasterise(discs: list[Disc], legs: list[Leg], grid: Grid, p: ProxyParams) -> list[Layer]:
    """The layers of free floor of ``discs`` and ``legs``, lowest elements first."""
    layers: list[Layer] = []
    for xy, f, comp in sorted(discs, key=lambda d: d.floor):
        window, d, cheb = disc(grid, xy, p.viewpoint_radius)
        mask, height = d <= p.viewpoint_radius, np.full(d.shape, f)
        reach = p.viewpoint_radius
        _place(layers, grid.shape, window, mask, height, d, cheb, reach, comp, None, p)
    for pa, pb, fa, fb, comp, stepped in sorted(legs, key=lambda g: min(g.fa, g.fb)):
        window, d, cheb, t = corridor(grid, pa, pb, p.corridor_half_width)
        mask, height = d <= p.corridor_half_width, fa + t * (fb - fa)
        reach = p.corridor_half_width
        steps = stair_steps(fa, fb, p) if stepped else None
        _place(layers, grid.shape, window, mask, height, d, cheb, reach, comp, steps, p)
    return layers


def _shifted(arr: np.ndarray, dr: int, dc: int) -> tuple[tuple[slice, slice], tuple[slice, slice]]:
    """Slices pairing each cell with its neighbour at offset (dr, dc)."""
    h, w = arr.shape
    first = (slice(max(dr, 0), h), slice(max(dc, 0), w + min(dc, 0)))
    second = (slice(0, h - dr), slice(max(-dc, 0), w - max(dc, 0)))
    return first, second


def clear_overhangs(layers: list[Layer], p: ProxyParams) -> None:
    """Clears floor that would hang in the way of a body walking a path below it.

    A body stands on its path's cells (those a path runs through) and reaches the cells
    ``reach_cells`` around. A floor there more than ``layer_gap`` above the body (another
    storey, or the next turn of a stair) whose slab, however thinned (``min_slab``), would
    reach into the body's band is cleared, unless a path runs through it (no drawing serves
    both). The elements' heights blend as they are placed, so two floors placed as storeys
    may end up closer than that.
    """
    margin = FLOOR_QUANTUM  # the floors' tops are drawn rounded
    bodies = [np.where(layer.line, layer.height, np.nan) for layer in layers]
    for layer in layers:
        h = layer.height
        cut = np.zeros(h.shape, bool)
        for support in bodies:
            for s in neighbours(support, p.reach_cells):
                with np.errstate(invalid="ignore"):
                    cut |= (h > s + p.layer_gap) & (h - p.min_slab - margin < s + p.body_z[1])
        layer.clear(cut & ~layer.line)


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
