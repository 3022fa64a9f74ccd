"""A building synthesised from a navigation graph (a "graph proxy").

The floor is a disc around every included viewpoint and a corridor along every drawn edge,
each at its own floor height (viewpoint z − height; interpolated along an edge, which makes
stairs of edges that climb), drawn in layers so that storeys stacked above each other keep
their floors (:mod:`~havln_mj.scene.proxy.layers`). Walls bound the free floor; cells where
two graph components meet are walls too, so viewpoints that are not connected in the graph
are not connected in the building either (:mod:`~havln_mj.scene.proxy.draw`).

Every edge is then checked for a walking body (:mod:`~havln_mj.scene.proxy.walk`). Matterport's
``unobstructed`` means two panoramas see each other, not that the straight line between them
is a walk: an edge up a turning stair is too steep to walk straight, and two edges whose
straight corridors cross at different heights cannot both be drawn. Such edges are walked by
a *route* over other edges instead (:mod:`~havln_mj.scene.proxy.routes`), stored in the
proxy and followed by the legged robot; edges left with neither are reported.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from havln_mj.scene.boxes import BoxSet
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.proxy.draw import layer_boxes
from havln_mj.scene.proxy.layers import (
    Edge,
    Layer,
    clear_overhangs,
    rasterise,
    separate_components,
)
from havln_mj.scene.proxy.params import ProxyParams
from havln_mj.scene.proxy.raster import Grid
from havln_mj.scene.proxy.routes import crossings, shortest_routes
from havln_mj.scene.proxy.walk import CAUSES, edge_grade, floor_point, path_fault

__all__ = ["Proxy", "ProxyParams", "build_proxy", "edge_walkability"]

_ROUNDS = 4  # most redraws after leaving routed edges out


@dataclass(frozen=True)
class Proxy:
    """A graph proxy's geometry and how well it serves the graph.

    Attributes:
        boxes: Floors, stairs and walls.
        grid: The plan grid the geometry was drawn on.
        free: Each layer's free cells.
        faults: Edges a body cannot walk straight, with the cause (one of ``walk.CAUSES``).
        crossing: Edges whose straight corridor cannot coexist with another edge's (see
            :func:`~havln_mj.scene.proxy.routes.crossings`).
        routes: Edges walked by a route instead: ``(a, ..., b)`` through other viewpoints,
            each link an edge walkable straight.
    """

    boxes: BoxSet
    grid: Grid
    free: list[np.ndarray]
    faults: dict[Edge, str]
    crossing: frozenset[Edge]
    routes: dict[Edge, tuple[str, ...]]

    @property
    def unwalkable(self) -> list[Edge]:
        """Edges walkable neither straight nor by route."""
        return [e for e in self.faults if e not in self.routes]


def build_proxy(graph: NavGraph, params: ProxyParams | None = None) -> Proxy:
    """Draws the graph proxy of ``graph``, checks every edge on it and routes what it can.

    Edges steeper than ``max_grade`` are never drawn. The others are drawn and checked. An
    edge that fails straight while its corridor crosses another drawn edge's is left out of
    the drawing when it has a route, else one of the edges it crosses that has one, and the
    proxy is redrawn (a few rounds). Links of a route stay drawn, and of two crossing edges at
    most one is left out per round. Finally each edge that fails straight and is steep or
    crossing gets its shortest route, when one is at most ``route_ratio`` times as long and
    passes the check as a whole.
    """
    p = params or ProxyParams()
    xy = np.array([graph.position(v)[:2] for v in graph.nodes])
    grid = Grid.around(xy, p.viewpoint_radius + 3 * p.cell, p.cell)
    comp_of = {vp: k for k, members in enumerate(graph.components()) for vp in members}
    edges = [(a, b) for a, b, _ in graph.edges()]
    order = {e: k for k, e in enumerate(edges)}
    steep = {e for e in edges if edge_grade(graph, *e) > p.max_grade}
    drawable = [e for e in edges if e not in steep]
    conflicts = crossings(graph, drawable, p)
    left_out: set[Edge] = set()
    kept: set[Edge] = set()  # links of routes: stay drawn
    for rounds in range(_ROUNDS + 1):
        drawn = [e for e in drawable if e not in left_out]
        layers, boxes = _draw(graph, drawn, grid, p, comp_of)
        faults = _faults(graph, edges, boxes, p)
        if rounds == _ROUNDS:
            break
        walkable = [e for e in edges if e not in faults]
        open_conflicts = {e: conflicts.get(e, set()) - left_out for e in drawn}
        failing = sorted(
            (e for e in drawn if e in faults and open_conflicts[e]),
            key=lambda e: (-len(open_conflicts[e]), order[e]),
        )
        partners = sorted({f for e in failing for f in open_conflicts[e]}, key=order.get)
        routes = shortest_routes(graph, walkable, failing + partners, p.route_ratio)
        before = len(left_out)
        spared: set[Edge] = set()
        for e in failing:
            # Leave the failing edge out, else one it crosses; either is walked by its route.
            for f in [e, *sorted(open_conflicts[e], key=order.get)]:
                if f in routes and not {f} & (spared | kept | left_out):
                    left_out.add(f)
                    spared |= conflicts[f]
                    links = itertools.pairwise(routes[f])
                    kept |= {(a, b) if (a, b) in order else (b, a) for a, b in links}
                    break
        if len(left_out) == before:
            break
    crossing = frozenset(conflicts)
    walkable = [e for e in edges if e not in faults]
    wanted = [e for e in faults if e in steep or e in crossing]
    routes = {
        e: route
        for e, route in shortest_routes(graph, walkable, wanted, p.route_ratio).items()
        if path_fault(np.array([floor_point(graph, v) for v in route]), boxes, p) is None
    }
    return Proxy(boxes, grid, [layer.free for layer in layers], faults, crossing, routes)


def _draw(
    graph: NavGraph, edges: list[Edge], grid: Grid, p: ProxyParams, comp_of: dict[str, int]
) -> tuple[list[Layer], BoxSet]:
    layers = rasterise(graph, edges, grid, p, comp_of)
    clear_overhangs(layers, p)
    for layer in layers:
        separate_components(layer)
    return layers, layer_boxes(layers, grid, p)


def _faults(graph: NavGraph, edges: list[Edge], boxes: BoxSet, p: ProxyParams) -> dict[Edge, str]:
    out = {}
    for a, b in edges:
        fault = path_fault(np.array([floor_point(graph, a), floor_point(graph, b)]), boxes, p)
        if fault is not None:
            out[(a, b)] = fault
    return out


def edge_walkability(
    graph: NavGraph, boxes: BoxSet, params: ProxyParams | None = None
) -> dict[str, list[Edge]]:
    """Checks every edge walked straight (see :mod:`havln_mj.scene.proxy.walk`).

    Returns:
        The failing edges by cause (each of ``walk.CAUSES``).
    """
    p = params or ProxyParams()
    out: dict[str, list[Edge]] = {cause: [] for cause in CAUSES}
    for edge, cause in _faults(graph, [(a, b) for a, b, _ in graph.edges()], boxes, p).items():
        out[cause].append(edge)
    return out
