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
proxy and followed by the robot. Where the graph has no such route, the proxy draws a flight
of its own for the edge (:mod:`~havln_mj.scene.proxy.stairs`); edges left with none of these
are reported.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from havln_mj.scene.boxes import BoxSet
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.proxy.draw import draw_elements
from havln_mj.scene.proxy.layers import Disc, Edge, Layer, Leg, graph_elements
from havln_mj.scene.proxy.params import ProxyParams
from havln_mj.scene.proxy.raster import Grid
from havln_mj.scene.proxy.routes import Route, crossings, route_floor_points, shortest_routes
from havln_mj.scene.proxy.stairs import flight_legs, plan_flights, plan_span, spans_meet
from havln_mj.scene.proxy.walk import CAUSES, edge_grade, path_fault

__all__ = ["Proxy", "ProxyParams", "build_proxy", "edge_walkability"]

_ROUNDS = 4  # most redraws after leaving routed edges out
_FLIGHT_MARGIN = 1.0  # metres: a flight this near a path it broke is dropped


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
        routes: Edges walked by a route instead, ``(a, ..., b)``: through other viewpoints,
            each link an edge walkable straight, or along a flight drawn for the edge, through
            floor points (see :mod:`~havln_mj.scene.proxy.routes`).
    """

    boxes: BoxSet
    grid: Grid
    free: list[np.ndarray]
    faults: dict[Edge, str]
    crossing: frozenset[Edge]
    routes: dict[Edge, Route]

    @property
    def unwalkable(self) -> list[Edge]:
        """Edges walkable neither straight nor by route."""
        return [e for e in self.faults if e not in self.routes]

    @property
    def flights(self) -> list[Edge]:
        """Routed edges walked along a flight drawn for them."""
        return [e for e, via in self.routes.items() if not all(isinstance(s, str) for s in via)]


def build_proxy(graph: NavGraph, params: ProxyParams | None = None) -> Proxy:
    """Draws the graph proxy of ``graph``, checks every edge on it and routes what it can.

    Edges steeper than ``max_grade`` are never drawn. The others are drawn and checked. An
    edge that fails straight while its corridor crosses another drawn edge's is left out of
    the drawing when it has a route, else one of the edges it crosses that has one, and the
    proxy is redrawn (a few rounds). Links of a route stay drawn, and of two crossing edges at
    most one is left out per round. Finally each edge that fails straight and is steep or
    crossing gets its shortest route, when one is at most ``route_ratio`` times as long and
    passes the check as a whole. An edge left with no route gets a flight of its own when
    one fits, moving a walk in its way onto a flight where that makes room (see
    :func:`~havln_mj.scene.proxy.stairs.plan_flights`).
    """
    p = params or ProxyParams()
    xy = np.array([graph.position(v)[:2] for v in graph.nodes])
    grid = _grid(xy, p)
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
        discs, legs = graph_elements(graph, drawn, comp_of)
        layers, boxes = draw_elements(discs, legs, grid, p)
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
    routes: dict[Edge, Route] = {
        e: route
        for e, route in shortest_routes(graph, walkable, wanted, p.route_ratio).items()
        if path_fault(route_floor_points(graph, route), boxes, p) is None
    }
    legs_of = dict(zip(drawn, legs, strict=True))
    flights, moved = _choose_flights(graph, edges, faults, routes, discs, legs_of, grid, p, comp_of)
    if flights:
        grid, layers, boxes, faults, flights = _draw_flights(
            graph, edges, faults, routes, flights, moved, discs, legs_of, p, comp_of
        )
    routes = {e: r for e, r in routes.items() if e in faults}  # a flight may free an edge
    for (a, b), flight in flights.items():
        if (a, b) in faults:
            routes[(a, b)] = (a, *(tuple(map(float, q)) for q in flight[1:-1]), b)
    drawn = [g for e, g in legs_of.items() if e not in moved or e not in flights]
    drawn += [g for e, f in flights.items() for g in flight_legs(f, comp_of[e[0]])]
    layers, boxes, faults = _cut_stairs(graph, edges, faults, routes, discs, drawn, grid, p)
    return Proxy(boxes, grid, [layer.free for layer in layers], faults, crossing, routes)


def _cut_stairs(
    graph: NavGraph,
    edges: list[Edge],
    faults: dict[Edge, str],
    routes: dict[Edge, Route],
    discs: list[Disc],
    legs: list[Leg],
    grid: Grid,
    p: ProxyParams,
) -> tuple[list[Layer], BoxSet, dict[Edge, str]]:
    """The proxy redrawn with its stairs cut into treads and risers, where that breaks no walk.

    The proxy is planned with stairs drawn as ramps at their edge's grade. Cutting them into
    treads moves floors by up to half a riser, which can leave a viewpoint halfway up a stair
    out of reach: the stairs within ``_FLIGHT_MARGIN`` of a path that broke (an edge that
    walked straight, a route, a flight) stay ramps, and the proxy is redrawn until none
    breaks.
    """
    paths = [route_floor_points(graph, r) for r in routes.values()]
    stepped = [g._replace(stepped=True) for g in legs]
    while True:
        layers, boxes = draw_elements(discs, stepped, grid, p)
        new_faults = _faults(graph, edges, boxes, p)
        broken = [route_floor_points(graph, e) for e in new_faults if e not in faults]
        broken += [q for q in paths if path_fault(q, boxes, p) is not None]
        if not broken:
            return layers, boxes, new_faults
        spans, m = np.array([plan_span(q) for q in broken]), _FLIGHT_MARGIN
        near = [
            g.stepped
            and spans_meet(spans, np.minimum(g.a, g.b) - m, np.maximum(g.a, g.b) + m).any()
            for g in stepped
        ]
        if not any(near):  # nothing left to smooth there: the planned drawing
            layers, boxes = draw_elements(discs, legs, grid, p)
            return layers, boxes, faults
        stepped = [
            g._replace(stepped=False) if n else g for g, n in zip(stepped, near, strict=True)
        ]


def _grid(xy: np.ndarray, p: ProxyParams) -> Grid:
    """The plan grid holding points ``xy`` with room for their floors and walls."""
    return Grid.around(xy, p.viewpoint_radius + 3 * p.cell, p.cell)


def _choose_flights(
    graph: NavGraph,
    edges: list[Edge],
    faults: dict[Edge, str],
    routes: dict[Edge, Route],
    discs: list[Disc],
    legs: dict[Edge, Leg],
    grid: Grid,
    p: ProxyParams,
    comp_of: dict[str, int],
) -> tuple[dict[Edge, np.ndarray], set[Edge]]:
    """Flights for edges walkable neither straight nor by route (see ``plan_flights``)."""
    paths = {e: route_floor_points(graph, e) for e in edges if e not in faults}
    paths |= {e: route_floor_points(graph, r) for e, r in routes.items()}
    flown = [e for e in faults if e not in routes]
    wanted = dict(zip(flown, graph_elements(graph, flown, comp_of)[1], strict=True))
    return plan_flights(
        wanted,
        discs,
        legs,
        paths,
        grid,
        lambda d, g, w: draw_elements(d, g, w, p, draft=True)[1],
        p,
    )


def _draw_flights(
    graph: NavGraph,
    edges: list[Edge],
    faults: dict[Edge, str],
    routes: dict[Edge, Route],
    flights: dict[Edge, np.ndarray],
    moved: set[Edge],
    discs: list[Disc],
    legs: dict[Edge, Leg],
    p: ProxyParams,
    comp_of: dict[str, int],
) -> tuple[Grid, list[Layer], BoxSet, dict[Edge, str], dict[Edge, np.ndarray]]:
    """Redraws the whole proxy with ``flights``, dropping those near a path that broke.

    The corridors of the ``moved`` edges give way to their flights (and come back if their
    flight is dropped). The grid grows to hold the flights (a flight may leave the
    building's outline). A path broke when an edge walkable straight before is neither
    that nor flown, a route no longer walks, or a flight is not walked itself. Flights
    within ``_FLIGHT_MARGIN`` of a broken path are dropped (all of them, if that leaves none
    near) and the proxy redrawn until none breaks.
    """
    flights = dict(flights)
    route_paths = [route_floor_points(graph, r) for r in routes.values()]
    xy = np.array([d.xy for d in discs])
    while True:
        grid = _grid(np.concatenate([xy, *(f[:, :2] for f in flights.values())]), p)
        drawn = [g for e, g in legs.items() if e not in moved or e not in flights]
        drawn += [g for e, f in flights.items() for g in flight_legs(f, comp_of[e[0]])]
        layers, boxes = draw_elements(discs, drawn, grid, p)
        new_faults = _faults(graph, edges, boxes, p)
        broken = [
            route_floor_points(graph, e) for e in new_faults if e not in faults and e not in flights
        ]
        broken += [q for q in route_paths if path_fault(q, boxes, p) is not None]
        broken += [f for f in flights.values() if path_fault(f, boxes, p) is not None]
        if not broken:
            return grid, layers, boxes, new_faults, flights
        spans, m = np.array([plan_span(q) for q in broken]), _FLIGHT_MARGIN
        near = {
            e
            for e, f in flights.items()
            if spans_meet(spans, f[:, :2].min(axis=0) - m, f[:, :2].max(axis=0) + m).any()
        }
        flights = {e: f for e, f in flights.items() if e not in (near or flights)}
        if not flights:
            grid = _grid(xy, p)
            layers, boxes = draw_elements(discs, list(legs.values()), grid, p)
            return grid, layers, boxes, faults, flights


def _faults(graph: NavGraph, edges: list[Edge], boxes: BoxSet, p: ProxyParams) -> dict[Edge, str]:
    out = {}
    for a, b in edges:
        fault = path_fault(route_floor_points(graph, (a, b)), boxes, p)
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
