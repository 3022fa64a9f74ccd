"""Graph planning around blocked viewpoints: the csgraph planner against a plain Dijkstra."""

from __future__ import annotations

import heapq
import math

import numpy as np
import pytest

from havln_mj.errors import UnknownViewpointError
from havln_mj.scene.connectivity import Connectivity
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.scan import load_scan
from havln_mj.tasks.planning import PathPlanner, blocked_nodes, plan_path


def _reference(graph, start, goal, blocked, weighted):
    """Dijkstra over ``neighbors``, popping (distance, file order), first improvement kept."""
    blocked = set(blocked) - {start, goal}
    if not blocked and weighted:
        reachable = math.isfinite(graph.distance(start, goal))
        return graph.shortest_path(start, goal) if reachable else None
    order = {v: i for i, v in enumerate(graph.nodes)}
    best, prev = {start: 0.0}, {}
    heap = [(0.0, order[start], start)]
    while heap:
        d, _, v = heapq.heappop(heap)
        if v == goal:
            path = [goal]
            while path[-1] != start:
                path.append(prev[path[-1]])
            return path[::-1]
        if d > best[v]:
            continue
        for u in graph.neighbors(v):
            if u in blocked:
                continue
            nd = d + (math.dist(graph.position(v), graph.position(u)) if weighted else 1.0)
            if nd < best.get(u, math.inf):
                best[u], prev[u] = nd, v
                heapq.heappush(heap, (nd, order[u], u))
    return None


def _compare(graph, rng, pairs):
    """Plans ``pairs`` random cases both ways; returns how many found a detour or no path."""
    planner = PathPlanner(graph)
    nodes = graph.nodes
    changed = 0
    for _ in range(pairs):
        start, goal = (nodes[k] for k in rng.choice(len(nodes), 2, replace=False))
        free = plan_path(graph, start, goal)
        # Block part of the free shortest path (forcing detours) and some random nodes.
        inner = free[1:-1] if free else []
        blocked = {v for v in inner if rng.random() < 0.5}
        blocked |= {nodes[k] for k in rng.choice(len(nodes), int(rng.integers(0, 9)))}
        for weighted in (True, False):
            want = _reference(graph, start, goal, blocked, weighted)
            assert plan_path(graph, start, goal, blocked, weighted=weighted) == want
            assert planner.plan(start, goal, blocked, weighted=weighted) == want
            changed += want != free
    return changed


def test_planner_matches_reference_dijkstra_on_the_90_real_graphs(shared_data):
    folder = shared_data / "mp3d_connectivity"
    scans = (folder / "scans.txt").read_text().split()
    assert len(scans) == 90
    rng = np.random.default_rng(7)
    changed = 0
    for scan in scans:
        changed += _compare(NavGraph.from_file(folder / f"{scan}_connectivity.json"), rng, 12)
    assert changed > 500  # the blocked sets really change most plans


@pytest.mark.parametrize("scene", ["proc-0", "proc-3"])
def test_planner_matches_reference_on_procedural_graphs(scene):
    # Procedural viewpoints sit on regular spacings: equally long paths are common.
    assert _compare(load_scan(scene).graph, np.random.default_rng(1), 60) > 20


def test_planner_blocked_matches_blocked_nodes():
    graph = load_scan("proc-0").graph
    planner = PathPlanner(graph)
    rng = np.random.default_rng(3)
    for _ in range(20):
        at = [graph.nodes[k] for k in rng.choice(graph.num_nodes, 4)]
        people = [graph.position(v) - (0, 0, 0.6) for v in at[:3]]
        people.append(people[0] + (0.0, 0.0, 3.0))  # a storey up: no effect
        keep = (at[0], at[3])
        want = blocked_nodes(graph, people, 1.0, keep)
        assert planner.blocked(people, 1.0, keep) == want
        assert want and not want & set(keep)


def test_planner_edge_cases():
    graph = load_scan("proc-0").graph
    planner = PathPlanner(graph)
    a, b = graph.nodes[0], graph.nodes[-1]
    assert planner.plan(a, a, {a}) == [a]
    assert planner.plan(a, b, {"not-a-viewpoint"}) == graph.shortest_path(a, b)
    boxed = set(graph.neighbors(a))
    assert b not in boxed
    assert planner.plan(a, b, boxed) is None
    assert plan_path(graph, a, b, boxed, weighted=False) is None
    with pytest.raises(UnknownViewpointError, match="nowhere"):
        planner.plan("nowhere", b, {a})


def _toy_graph(xy, edges):
    ids = list(xy)
    n = len(ids)
    poses = np.tile(np.eye(4), (n, 1, 1))
    for i, (x, y) in enumerate(xy.values()):
        poses[i, 0, 3], poses[i, 1, 3], poses[i, 2, 3] = x, y, 1.5
    unob = np.zeros((n, n), bool)
    for a, b in edges:
        unob[ids.index(a), ids.index(b)] = unob[ids.index(b), ids.index(a)] = True
    return NavGraph(Connectivity(ids, poses, [True] * n, ~np.eye(n, dtype=bool), unob, [1.5] * n))


def test_zero_length_edges_still_give_a_shortest_path():
    # d0 and d1 are the same place; the way round through e is longer.
    xy = {"a": (0, 0), "d1": (1, 0), "d0": (1, 0), "g": (2, 0), "e": (1, 3)}
    edges = [("a", "d1"), ("a", "d0"), ("d1", "d0"), ("d1", "g"), ("d0", "g"), ("a", "e")]
    graph = _toy_graph(xy, [*edges, ("e", "g")])
    planner = PathPlanner(graph)
    for blocked in ({"e"}, {"d1"}, {"d0"}, {"d0", "e"}):
        path = planner.plan("a", "g", blocked)
        assert path[0] == "a" and path[-1] == "g" and not set(path) & blocked
        assert graph.path_length(path) == pytest.approx(2.0)
    assert len(planner.plan("a", "g", {"d1"}, weighted=False)) == 3
    # Three viewpoints at one place, all joined: equal distances all round the triangle.
    xy = {"y": (0, 0), "x": (0, 0), "s": (0, 0), "g": (1, 0), "z": (5, 5)}
    edges = [("s", "x"), ("s", "y"), ("x", "y"), ("x", "g"), ("y", "g")]
    path = PathPlanner(_toy_graph(xy, edges)).plan("s", "g", {"z"})
    assert path[0] == "s" and path[-1] == "g" and len(path) == len(set(path))
