"""Edges a straight corridor cannot serve, and the routes that serve them instead.

Matterport's ``unobstructed`` flag says two panoramas see each other, not that a person walks
the straight line between them. Where the line of sight crosses a stairwell, or runs up a
turning stair, the straight line is no walk at all:

* **Steep**: the edge climbs more than ``max_grade`` over its horizontal length (a U-shaped
  or spiral stair seen from its foot); no drawing makes it a walk.
* **Crossing**: two straight corridors (each at the constant grade between its viewpoints'
  floors) pass within a body radius of each other at heights that put one's floor inside the
  other's body band. No drawing serves both as straight corridors.

Such an edge is walked by a *route* instead: a chain of other edges, each walkable straight,
no longer than ``route_ratio`` times the edge. The builder leaves routed edges out of the
drawing, so they no longer take floor from the edges they cross. Where the graph has no such
chain, the builder draws a flight of its own for the edge (:mod:`~havln_mj.scene.proxy.stairs`):
its route passes floor points, not viewpoints.

A route is a tuple of *stops*, the edge's ends first and last: a stop is a viewpoint id or a
floor point ``(x, y, floor_z)``.
"""

from __future__ import annotations

import json
from collections import defaultdict
from pathlib import Path

import numpy as np

from havln_mj.cache import atomic_write_json
from havln_mj.errors import MalformedDataError
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.proxy.params import ProxyParams
from havln_mj.scene.proxy.walk import floor_point, samples

Edge = tuple[str, str]
Stop = str | tuple[float, float, float]
Route = tuple[Stop, ...]


def route_floor_points(graph: NavGraph, route: Route) -> np.ndarray:
    """(K, 3) floor points of a route's stops."""
    return np.array(
        [floor_point(graph, s) if isinstance(s, str) else s for s in route], dtype=float
    )


def route_camera_points(graph: NavGraph, route: Route) -> np.ndarray:
    """(K, 3) camera positions along a route.

    A viewpoint's own position, else the floor point raised by the camera height interpolated
    between the route's ends (by horizontal distance).
    """
    floors = route_floor_points(graph, route)
    run = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(floors[:, :2], axis=0).T))])
    ends = [graph.position(route[k])[2] - floors[k, 2] for k in (0, -1)]
    lift = np.interp(run, [0.0, max(run[-1], 1e-9)], ends)
    out = floors + np.column_stack([np.zeros((len(floors), 2)), lift])
    for k, stop in enumerate(route):
        if isinstance(stop, str):
            out[k] = graph.position(stop)
    return out


def crossings(graph: NavGraph, edges: list[Edge], p: ProxyParams) -> dict[Edge, set[Edge]]:
    """Pairs of edges whose straight corridors cannot both be walked.

    Each edge is sampled as the walkability check samples it, at its constant grade. Two
    edges conflict where a sample of one lies inside the other's body footprint (square,
    half side ``body_radius``) at a floor height inside that body's band: the floor there
    would stand in the other body's way, however thin it is drawn.

    Returns:
        For each edge in a conflict, the edges it conflicts with.
    """
    r, (z0, z1) = p.body_radius, p.body_z
    xy, h, band_lo, owner = [], [], [], []
    for k, (a, b) in enumerate(edges):
        pts, run = samples(route_floor_points(graph, (a, b)), p.cell / 2)
        rise = abs(pts[-1, 2] - pts[0, 2]) / max(run[-1], 1e-9)
        xy.append(pts[:, :2])
        h.append(pts[:, 2])
        # The band starts above the highest floor within one radius along the path.
        band_lo.append(np.minimum(pts[:, 2] + rise * r, pts[:, 2].max()) + z0)
        owner.append(np.full(len(pts), k))
    xy_a, h_a, lo_a = np.concatenate(xy), np.concatenate(h), np.concatenate(band_lo)
    own = np.concatenate(owner)
    cells = np.floor(xy_a / r).astype(np.int64)
    buckets: dict[tuple[int, int], list[int]] = defaultdict(list)
    for i, key in enumerate(map(tuple, cells.tolist())):
        buckets[key].append(i)
    out: dict[Edge, set[Edge]] = defaultdict(set)
    for (cx, cy), members in buckets.items():
        mine = np.array(members)
        other = np.concatenate(
            [np.array(buckets.get((cx + dx, cy + dy), []), dtype=np.int64) for dx in (-1, 0, 1)
             for dy in (-1, 0, 1)]
        )  # fmt: skip
        close = np.abs(xy_a[mine, None, :] - xy_a[None, other, :]).max(axis=2) < r
        # A floor at h_b inside the band of the body standing at h_a.
        inside = (h_a[other][None] > lo_a[mine][:, None]) & (
            h_a[other][None] < h_a[mine][:, None] + z1
        )
        hit = close & inside & (own[mine][:, None] != own[other][None])
        for i, j in zip(*np.nonzero(hit), strict=True):
            e, f = edges[own[mine[i]]], edges[own[other[j]]]
            out[e].add(f)
            out[f].add(e)
    return dict(out)


def shortest_routes(
    graph: NavGraph, walkable: list[Edge], wanted: list[Edge], ratio: float
) -> dict[Edge, tuple[str, ...]]:
    """Shortest chains of ``walkable`` edges joining the ends of each ``wanted`` edge.

    A wanted edge is never a link of its own route. Routes longer than ``ratio`` times the
    edge (3-D distance between the viewpoints) are dropped.

    Returns:
        For each wanted edge that has one, its route ``(a, ..., b)``.
    """
    from scipy.sparse import csr_matrix  # a large import: only when routes are planned
    from scipy.sparse.csgraph import dijkstra

    index = {vp: k for k, vp in enumerate(graph.nodes)}
    pos = np.array([graph.position(vp) for vp in graph.nodes]).reshape(-1, 3)
    links = {(index[a], index[b]) for a, b in walkable}
    links |= {(j, i) for i, j in links}
    routes: dict[Edge, tuple[str, ...]] = {}
    n = len(graph.nodes)
    for a, b in wanted:
        i, j = index[a], index[b]
        use = sorted(links - {(i, j), (j, i)})
        if not use:
            continue
        rows, cols = np.array(use).T
        weight = np.linalg.norm(pos[rows] - pos[cols], axis=1)
        matrix = csr_matrix((weight, (rows, cols)), shape=(n, n))
        dist, pred = dijkstra(matrix, indices=i, return_predecessors=True)
        if not dist[j] <= ratio * float(np.linalg.norm(pos[i] - pos[j])):
            continue
        path = [j]
        while path[-1] != i:
            path.append(int(pred[path[-1]]))
        routes[(a, b)] = tuple(graph.nodes[v] for v in reversed(path))
    return routes


def write_routes(path: Path, routes: dict[Edge, Route]) -> None:
    """Writes ``routes.json``: each routed edge with the stops its route passes.

    Stops are viewpoint ids, or floor points as ``[x, y, floor_z]``.
    """
    entries = [
        {"edge": list(edge), "via": [s if isinstance(s, str) else [*map(float, s)] for s in via]}
        for edge, via in routes.items()
    ]
    atomic_write_json(path, {"routes": entries}, indent=1)


def read_routes(path: Path) -> dict[Edge, Route]:
    """Reads ``routes.json`` (empty when the file is absent).

    Raises:
        MalformedDataError: The file is not a list of routes joining their edge's ends.
    """
    if not path.is_file():
        return {}
    try:
        entries = json.loads(path.read_text(encoding="utf-8"))["routes"]
        routes = {(str(e["edge"][0]), str(e["edge"][1])): _stops(e["via"]) for e in entries}
    except (json.JSONDecodeError, KeyError, TypeError, IndexError, ValueError) as exc:
        raise MalformedDataError(f"{path}: not a valid routes file ({exc!r})") from exc
    for (a, b), via in routes.items():
        if len(via) < 3 or via[0] != a or via[-1] != b:
            raise MalformedDataError(
                f"{path}: the route of edge {a}-{b} must run from {a} to {b} through at least "
                f"one other stop; got {list(via)}"
            )
    return routes


def _stops(via: list) -> Route:
    """A route's stops from JSON: strings, or lists of three finite numbers."""
    out: list[Stop] = []
    for s in via:
        if isinstance(s, str):
            out.append(s)
            continue
        x, y, z = (float(c) for c in s)  # ValueError unless three numbers
        if not np.isfinite([x, y, z]).all():
            raise ValueError(f"stop {s!r} is not finite")
        out.append((x, y, z))
    return tuple(out)
