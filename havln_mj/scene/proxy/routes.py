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
drawing, so they no longer take floor from the edges they cross.
"""

from __future__ import annotations

import json
from collections import defaultdict
from pathlib import Path

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from havln_mj.cache import atomic_write_json
from havln_mj.errors import MalformedDataError
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.proxy.params import ProxyParams
from havln_mj.scene.proxy.walk import floor_point, samples

Edge = tuple[str, str]


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
        pts, run = samples(np.array([floor_point(graph, a), floor_point(graph, b)]), p.cell / 2)
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


def write_routes(path: Path, routes: dict[Edge, tuple[str, ...]]) -> None:
    """Writes ``routes.json``: each routed edge with the viewpoints its route passes."""
    entries = [{"edge": list(edge), "via": list(via)} for edge, via in routes.items()]
    atomic_write_json(path, {"routes": entries}, indent=1)


def read_routes(path: Path) -> dict[Edge, tuple[str, ...]]:
    """Reads ``routes.json`` (empty when the file is absent).

    Raises:
        MalformedDataError: The file is not a list of routes joining their edge's ends.
    """
    if not path.is_file():
        return {}
    try:
        entries = json.loads(path.read_text(encoding="utf-8"))["routes"]
        routes = {
            (str(e["edge"][0]), str(e["edge"][1])): tuple(map(str, e["via"])) for e in entries
        }
    except (json.JSONDecodeError, KeyError, TypeError, IndexError) as exc:
        raise MalformedDataError(f"{path}: not a valid routes file ({exc!r})") from exc
    for (a, b), via in routes.items():
        if len(via) < 3 or via[0] != a or via[-1] != b:
            raise MalformedDataError(
                f"{path}: the route of edge {a}-{b} must run from {a} to {b} through at least "
                f"one other viewpoint; got {list(via)}"
            )
    return routes
