"""Paths on a scan's navigation graph around people, and R2R's teacher action along them.

* :func:`people_near` and :func:`blocked_nodes`: who the human-aware expert avoids and which
  viewpoints that closes. Distances to people are horizontal, from a viewpoint to a pelvis,
  as the simulator's collision signal measures them; a person counts only on the viewpoint's
  storey (pelvis between 0.5 m below and 2 m above the viewpoint's floor).
* :class:`PathPlanner` and :func:`plan_path`: shortest paths on ``NavGraph``'s graph (R2R's
  undirected graph, weighted by edge length, or counting hops as HA3D's expert does) with
  blocked viewpoints masked out, searched by ``scipy.sparse.csgraph``.
* :func:`graph_teacher`: R2R's teacher action towards the next viewpoint of a path.

Among equally short paths, with nothing blocked a path is ``NavGraph.shortest_path`` (the
choice that follows every R2R val_seen path); around blocked viewpoints each viewpoint of
the path is reached from the neighbour a Dijkstra search popping (distance, file order)
settles first: of the neighbours on a shortest path to it, the nearest to the start, then
the first in the connectivity file. (A graph with edges of length 0 is traced along
scipy's own search tree instead.)
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from functools import cached_property

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from havln_mj.frames import heading_to, wrap_angle
from havln_mj.scene.navgraph import NavGraph
from havln_mj.sim.egocentric import DEFAULT_TURN
from havln_mj.sim.state import SimState
from havln_mj.tasks.step import GraphAction

TURN = DEFAULT_TURN  # 30°: one discrete view step, and the teacher's heading tolerance
SIGHT_RADIUS = 4.5  # metres: HA3D's expert avoids people this close to the agent
CLEARANCE = 1.0  # metres: nodes this close to such a person are removed
STOREY_BELOW, STOREY_ABOVE = 0.5, 2.0  # a pelvis this far below / above a floor is on it


# ---------------------------------------------------------------------- people


def _floors(graph: NavGraph, nodes: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    xy = np.array([graph.position(v)[:2] for v in nodes]).reshape(-1, 2)
    return xy, np.array([graph.floor_z(v) for v in nodes])


def _near(xy: np.ndarray, floor: np.ndarray, people: np.ndarray, radius: float) -> np.ndarray:
    """(N,) bool: points (xy, floor height) with a pelvis within ``radius`` on their storey."""
    if len(people) == 0 or len(xy) == 0:
        return np.zeros(len(xy), bool)
    d = np.hypot(xy[:, None, 0] - people[None, :, 0], xy[:, None, 1] - people[None, :, 1])
    dz = people[None, :, 2] - floor[:, None]
    return ((d <= radius) & (dz >= -STOREY_BELOW) & (dz <= STOREY_ABOVE)).any(axis=1)


def people_near(
    graph: NavGraph, vp: str, people: Iterable[np.ndarray], radius: float = SIGHT_RADIUS
) -> np.ndarray:
    """The pelvis positions ``(K, 3)`` within ``radius`` of viewpoint ``vp``, on its storey."""
    pts = np.asarray(list(people), float).reshape(-1, 3)
    xy, floor = _floors(graph, [vp])
    keep = [bool(_near(xy, floor, p[None], radius)[0]) for p in pts]
    return pts[np.array(keep, bool)] if len(pts) else pts


def blocked_nodes(
    graph: NavGraph,
    people: Iterable[np.ndarray],
    clearance: float = CLEARANCE,
    keep: Iterable[str] = (),
) -> set[str]:
    """The graph nodes within ``clearance`` of any of ``people`` (pelvis positions).

    Nodes in ``keep`` (the agent's and the goal) are never blocked.
    """
    xy, floor = _floors(graph, graph.nodes)
    return _blocked(graph.nodes, xy, floor, people, clearance, keep)


def _blocked(
    nodes: Sequence[str],
    xy: np.ndarray,
    floor: np.ndarray,
    people: Iterable[np.ndarray],
    clearance: float,
    keep: Iterable[str],
) -> set[str]:
    pts = np.asarray(list(people), float).reshape(-1, 3)
    hit = _near(xy, floor, pts, clearance)
    return {nodes[i] for i in np.flatnonzero(hit)} - set(keep)


# ---------------------------------------------------------------------- paths


class PathPlanner:
    """Shortest paths on one navigation graph with viewpoints blocked.

    Holds the graph's edges as a ``scipy.sparse`` matrix; each search gives the edges into
    blocked viewpoints an infinite length and runs ``scipy.sparse.csgraph.dijkstra`` from the
    start. Build one per graph and keep it: building reads every edge.

    Args:
        graph: The navigation graph.
    """

    def __init__(self, graph: NavGraph) -> None:
        self.graph = graph
        self._order = {v: k for k, v in enumerate(graph.nodes)}
        edges = graph.edges()
        a = np.array([self._order[e[0]] for e in edges], dtype=np.int32)
        b = np.array([self._order[e[1]] for e in edges], dtype=np.int32)
        w = np.array([e[2] for e in edges], dtype=float)
        n = graph.num_nodes
        # Both directions: R2R's graph is undirected. Columns ascend in file order.
        lengths = csr_matrix((np.r_[w, w], (np.r_[a, b], np.r_[b, a])), shape=(n, n))
        lengths.sort_indices()
        self._lengths = lengths.data.copy()
        self._zero_length = bool((w == 0).any())  # coincident viewpoints joined by an edge
        self._search = lengths  # its weights are rewritten by every search
        # The same as lists, for tracing a path back.
        self._starts = lengths.indptr.tolist()
        self._ends = lengths.indices.tolist()
        self._length_list = lengths.data.tolist()

    @cached_property
    def _floors(self) -> tuple[np.ndarray, np.ndarray]:
        return _floors(self.graph, self.graph.nodes)

    def blocked(
        self, people: Iterable[np.ndarray], clearance: float = CLEARANCE, keep: Iterable[str] = ()
    ) -> set[str]:
        """:func:`blocked_nodes` on this planner's graph (node positions read once)."""
        return _blocked(self.graph.nodes, *self._floors, people, clearance, keep)

    def plan(
        self, start: str, goal: str, blocked: Iterable[str] = (), *, weighted: bool = True
    ) -> list[str] | None:
        """A shortest path from ``start`` to ``goal`` avoiding ``blocked`` nodes, or None.

        With nothing blocked and ``weighted`` it is ``graph.shortest_path``.
        ``weighted=False`` counts edges, as HA3D's expert does. ``start`` and ``goal`` are
        never blocked; blocked names that are not nodes are ignored.

        Raises:
            UnknownViewpointError: ``start`` or ``goal`` is unknown or excluded.
        """
        graph = self.graph
        blocked = set(blocked) - {start, goal}
        if not math.isfinite(graph.distance(start, goal)):
            return None
        if not blocked and weighted:
            return graph.shortest_path(start, goal)
        search = self._search
        search.data[:] = self._lengths if weighted else 1.0
        closed = [self._order[v] for v in blocked if v in self._order]
        search.data[np.isin(search.indices, closed)] = np.inf
        s, g = self._order[start], self._order[goal]
        dist, pred = dijkstra(search, indices=s, return_predecessors=True)
        if math.isinf(dist[g]):
            return None
        path = [g]
        if self._zero_length:
            # Equal distances across an edge: the rule below could go round in a circle, so
            # follow the search's own tree (still a shortest path, ties as scipy settles them).
            while path[-1] != s:
                path.append(int(pred[path[-1]]))
        else:
            dist = dist.tolist()
            while path[-1] != s:
                path.append(self._reached_from(path[-1], dist, weighted))
        return [graph.nodes[k] for k in reversed(path)]

    def _reached_from(self, u: int, dist: list[float], weighted: bool) -> int:
        """The neighbour a Dijkstra popping (distance, file order) reaches ``u`` from first.

        Of the neighbours on a shortest path to ``u``, the nearest to the start, then the
        first in file order: the first of them popped (edges being longer than 0), whose
        relaxation of ``u`` stands.
        """
        lo, hi = self._starts[u], self._starts[u + 1]
        ends = self._ends[lo:hi]
        steps = self._length_list[lo:hi] if weighted else [1.0] * (hi - lo)
        du = dist[u]
        return min((dist[v], v) for v, w in zip(ends, steps, strict=True) if dist[v] + w == du)[1]


def plan_path(
    graph: NavGraph,
    start: str,
    goal: str,
    blocked: Iterable[str] = (),
    *,
    weighted: bool = True,
) -> list[str] | None:
    """A shortest path from ``start`` to ``goal`` avoiding ``blocked`` nodes, or None.

    :meth:`PathPlanner.plan` on a planner built for this call; hold a :class:`PathPlanner`
    to plan many times on one graph.

    Raises:
        UnknownViewpointError: ``start`` or ``goal`` is unknown or excluded.
    """
    blocked = set(blocked) - {start, goal}
    if not blocked and weighted:
        dist = graph.distance(start, goal)
        return graph.shortest_path(start, goal) if math.isfinite(dist) else None
    return PathPlanner(graph).plan(start, goal, blocked, weighted=weighted)


# ---------------------------------------------------------------------- teacher


def graph_teacher(state: SimState, next_vp: str, graph: NavGraph) -> GraphAction:
    """R2R's teacher action towards the neighbouring viewpoint ``next_vp``.

    Move when it is listed and within ±30° of the heading (looking up or down first when it
    is more than 30° above or below the camera); otherwise level the camera, then turn 30°
    towards it.
    """
    for i, loc in enumerate(state.navigableLocations[1:], start=1):
        if loc.viewpointId != next_vp:
            continue
        if loc.rel_heading > TURN:
            return (0, TURN, 0.0)
        if loc.rel_heading < -TURN:
            return (0, -TURN, 0.0)
        if loc.rel_elevation > TURN and state.elevation < TURN / 2:
            return (0, 0.0, TURN)
        if loc.rel_elevation < -TURN and state.elevation > -TURN / 2:
            return (0, 0.0, -TURN)
        return (i, 0.0, 0.0)
    if state.elevation > TURN / 2:
        return (0, 0.0, -TURN)
    if state.elevation < -TURN / 2:
        return (0, 0.0, TURN)
    here = state.location.position
    rel = wrap_angle(heading_to(here, graph.position(next_vp)) - state.heading)
    return (0, TURN if rel >= 0 else -TURN, 0.0)
