"""Navigable locations: the bearing-window query agrees with MatterSim's rule applied directly."""

from __future__ import annotations

import math

import numpy as np
import pytest

from havln_mj.scene.connectivity import Connectivity
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.scan import load_scan
from havln_mj.sim import navigation
from havln_mj.sim.navigation import NavTable, camera_positions


def _reference(graph: NavGraph, vp: str, heading: float, elevation: float, cos_fov):
    """MatterSim's rule, neighbour by neighbour: (id, rel_heading, rel_elevation, distance)."""
    here = graph.position(vp)
    found = []
    for order, j in enumerate(graph.neighbors(vp)):
        d = graph.position(j) - here
        flat = math.hypot(d[0], d[1])
        rel = math.remainder(math.atan2(d[0], d[1]) - heading, 2 * math.pi)
        rel = math.pi if rel == -math.pi else rel
        if cos_fov is not None and (flat == 0.0 or math.cos(rel) < cos_fov):
            continue
        rel_e = math.atan2(d[2], flat) - elevation
        found.append((math.hypot(rel, rel_e), order, j, rel, rel_e, float(np.linalg.norm(d))))
    found.sort()
    return [(vp, 0.0, 0.0, 0.0)] + [(j, r, e, dist) for _, _, j, r, e, dist in found]


def _check(graph: NavGraph, rng: np.random.Generator, queries: int) -> int:
    table = NavTable("scan", graph)
    seen = 0
    for _ in range(queries):
        vp = graph.nodes[int(rng.integers(graph.num_nodes))]
        fov = float(rng.choice([0.3, 0.7, 1.2, 2.5, 3.3]))  # half-widths; > π keeps all
        cos_fov = None if rng.random() < 0.1 else math.cos(fov)
        heading = float(rng.uniform(0.0, 2 * math.pi))
        neighbours = graph.neighbors(vp)
        if neighbours and rng.random() < 0.3:  # right at the edge of the field of view
            d = graph.position(neighbours[0]) - graph.position(vp)
            heading = (math.atan2(d[0], d[1]) + rng.choice([-fov, fov])) % (2 * math.pi)
        elevation = float(rng.uniform(-0.9, 0.9))
        got = table.candidates(vp, heading, elevation, cos_fov)
        want = _reference(graph, vp, heading, elevation, cos_fov)
        assert [v.viewpointId for v in got] == [w[0] for w in want], (vp, heading, cos_fov)
        for v, (_, rel, rel_e, dist) in zip(got, want, strict=True):
            assert v.rel_heading == pytest.approx(rel, abs=1e-12)
            assert v.rel_elevation == pytest.approx(rel_e, abs=1e-12)
            assert v.rel_distance == pytest.approx(dist, abs=1e-12)
        assert got[0].ix == graph.index(vp)
        assert (got[0].x, got[0].y, got[0].z) == camera_positions(graph)[vp]
        seen += len(got) - 1
    return seen


def test_candidates_follow_mattersims_rule_on_procedural_houses():
    rng = np.random.default_rng(0)
    assert sum(_check(load_scan(f"proc-{k}").graph, rng, 600) for k in range(3)) > 500


def test_candidates_follow_mattersims_rule_on_the_real_graphs(shared_data):
    rng = np.random.default_rng(1)
    files = sorted((shared_data / "mp3d_connectivity").glob("*_connectivity.json"))
    assert len(files) == 90
    seen = sum(_check(NavGraph.from_file(f), rng, 60) for f in files)
    assert seen > 3000


def _same(a: list, b: list) -> bool:
    """The same viewpoints in the same order with bit-identical values."""
    fields = ("viewpointId", "ix", "x", "y", "z", "rel_heading", "rel_elevation", "rel_distance")
    return [[getattr(v, f) for f in fields] for v in a] == [
        [getattr(v, f) for f in fields] for v in b
    ]


@pytest.fixture(params=["compiled", "python"])
def window_query(request, monkeypatch) -> None:
    """Runs a test with the compiled window query, then with its Python loop."""
    if request.param == "compiled" and navigation._window is None:
        pytest.skip("the C extension havln_mj.sim._navigable is not built here")
    if request.param == "python":
        monkeypatch.setattr(navigation, "_window", None)


@pytest.mark.parametrize("discretized", [False, True])
def test_the_bearing_window_gives_the_direct_rules_answer_bit_for_bit(
    shared_data, discretized, window_query
):
    """The bisected window's answer is the rule's loop over every neighbour, float for float.

    Both ways of answering it: the compiled query and its Python loop.
    """
    rng = np.random.default_rng(2 + discretized)
    files = sorted((shared_data / "mp3d_connectivity").glob("*_connectivity.json"))[::6]
    graphs = [NavGraph.from_file(f) for f in files] + [load_scan("proc-0").graph]
    views = 0
    for graph in graphs:
        table = NavTable("scan", graph)
        for _ in range(400):
            vp = graph.nodes[int(rng.integers(graph.num_nodes))]
            if discretized:  # the 36 views' exact angles
                heading = int(rng.integers(12)) * math.radians(30)
                elevation = int(rng.integers(-1, 2)) * math.radians(30)
            else:
                heading = float(rng.uniform(0.0, 2 * math.pi))
                elevation = float(rng.uniform(-0.9, 0.9))
            cos_fov = None if rng.random() < 0.2 else math.cos(float(rng.uniform(0.2, 3.3)))
            got = table.candidates(vp, heading, elevation, cos_fov)
            assert _same(got, table.direct(vp, heading, elevation, cos_fov)), (vp, heading)
            views += len(got) - 1
    assert views > 2000


def test_a_hub_with_a_hundred_neighbours_in_view_keeps_the_rules_order(window_query):
    """Many neighbours in one window, some at equal angles (ties go by file order)."""
    rng = np.random.default_rng(4)
    n = 101
    angles = np.repeat(rng.uniform(0.0, 2 * math.pi, 50), 2)[: n - 1]  # pairs at one bearing
    radii = np.tile([1.0, 2.0], 50)[: n - 1]  # ... at two distances
    poses = np.tile(np.eye(4), (n, 1, 1))
    poses[1:, 0, 3], poses[1:, 1, 3] = radii * np.sin(angles), radii * np.cos(angles)
    poses[1:, 2, 3] = rng.choice([0.0, 0.5], n - 1)
    unob = np.zeros((n, n), bool)
    unob[0, 1:] = unob[1:, 0] = True
    ids = [f"v{k:03d}" for k in range(n)]
    conn = Connectivity(ids, poses, [True] * n, ~np.eye(n, dtype=bool), unob, [1.5] * n)
    graph = NavGraph(conn)
    table = NavTable("hub", graph)
    longest = 0
    for heading in rng.uniform(0.0, 2 * math.pi, 50):
        for cos_fov in (math.cos(1.2), math.cos(2.9)):
            got = table.candidates("v000", float(heading), 0.1, cos_fov)
            assert _same(got, table.direct("v000", float(heading), 0.1, cos_fov))
            longest = max(longest, len(got) - 1)
    assert longest > 64  # beyond the compiled query's stack buffer
