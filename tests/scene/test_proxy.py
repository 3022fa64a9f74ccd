"""Graph proxies: the walkability check, crossing edges and routes, and the real graphs."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest
from scipy.ndimage import label

from havln_mj.errors import InvalidArgumentError, MalformedDataError
from havln_mj.scene.boxes import BoxSet
from havln_mj.scene.connectivity import parse_connectivity
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.proxy.build import ProxyParams, build_proxy, edge_walkability
from havln_mj.scene.proxy.draw import draw_elements
from havln_mj.scene.proxy.layers import graph_elements
from havln_mj.scene.proxy.raster import Grid, cover_cells, cover_rows
from havln_mj.scene.proxy.routes import (
    crossings,
    read_routes,
    route_camera_points,
    route_floor_points,
    shortest_routes,
    write_routes,
)
from havln_mj.scene.proxy.seams import SEAM_OVERLAP
from havln_mj.scene.proxy.stairs import candidate_flights
from havln_mj.scene.proxy.walk import CAUSES, edge_grade, path_fault, stair_steps

# Small and large, single- and multi-storey, scans whose graphs have several components, and
# a four-storey stairwell with landings at every height (yqstnuAEVhm).
SAMPLE = [
    "17DRP5sb8fy",
    "gZ6f7yhEvPG",
    "pLe4wQe7qrG",
    "2azQ1b91cZZ",
    "JF19kD82Mey",
    "PuKPg4mmafe",
    "yqstnuAEVhm",
]
P = ProxyParams()


def _graph(floors: dict[str, tuple[float, float, float]], edges: list[tuple[str, str]]):
    """A graph of viewpoints at floor points (x, y, floor), cameras 1.5 m above."""
    ids = list(floors)
    flags = set(edges) | {(b, a) for a, b in edges}
    data = [
        {
            "image_id": vp,
            "pose": [1, 0, 0, x, 0, 1, 0, y, 0, 0, 1, f + 1.5, 0, 0, 0, 1],
            "included": True,
            "visible": [False] * len(ids),
            "unobstructed": [(vp, other) in flags for other in ids],
            "height": 1.5,
        }
        for vp, (x, y, f) in floors.items()
    ]
    return NavGraph(parse_connectivity(data, "toy_connectivity.json"))


def _boxes(*spans: tuple[tuple[float, ...], tuple[float, ...]]) -> BoxSet:
    lo = np.array([s[0] for s in spans], float)
    hi = np.array([s[1] for s in spans], float)
    return BoxSet(lo, hi, ("floor",) * len(lo), ("floor",) * len(lo), np.ones((len(lo), 4)))


_SLAB = ((-1.0, -1.0, -0.1), (5.0, 1.0, 0.0))  # floor top at z = 0 from x = -1 to 5
_LINE = np.array([[0.0, 0.0, 0.0], [4.0, 0.0, 0.0]])


# ------------------------------------------------------------------ the walkability check


def test_a_clear_floor_is_walkable():
    assert path_fault(_LINE, _boxes(_SLAB), P) is None


@pytest.mark.parametrize(
    ("extra", "points", "cause"),
    [
        # A 0.25 m ledge across the path (on the floor slab) is a riser taller than `step`.
        ([((2.0, -1.0, 0.0), (5.0, 1.0, 0.25))], np.array([[0.0, 0, 0], [4.0, 0, 0.25]]), "step"),
        # A box in the body band beside the path (0.15 m off the centre line).
        ([((1.9, 0.15, 0.0), (2.1, 0.5, 1.0))], _LINE, "blocked"),
        # The far viewpoint's floor is 0.15 m above the floor drawn under it.
        ([], np.array([[0.0, 0, 0], [4.0, 0, 0.15]]), "no_floor"),
        # Nothing under the path halfway.
        ([], np.array([[0.0, 0, 0], [7.0, 0, 0]]), "no_floor"),
        # A straight edge climbing 1.2 m over 1 m: steeper than 45° whatever is drawn.
        ([], np.array([[0.0, 0, 0], [1.0, 0, 1.2]]), "steep"),
    ],
)
def test_the_check_names_the_fault(extra, points, cause):
    assert path_fault(points, _boxes(_SLAB, *extra), P) == cause


def test_low_sills_are_stepped_onto_and_overhead_slabs_passed_under():
    sill = ((1.9, -1.0, 0.0), (2.1, 1.0, 0.15))
    overhead = ((1.0, -1.0, 1.96), (3.0, 1.0, 2.05))  # above the band, even on the sill
    assert path_fault(_LINE, _boxes(_SLAB, sill, overhead), P) is None
    low_beam = ((1.0, -1.0, 1.7), (3.0, 1.0, 1.75))
    assert path_fault(_LINE, _boxes(_SLAB, low_beam), P) == "blocked"


def test_a_flight_steeper_than_the_grade_limit_is_steep_though_the_edge_is_not():
    # The edge climbs 1.5 m over 4 m (a grade of 0.375), but the floor drawn under it stays
    # level, then climbs it all in one metre of 0.15 m risers (each within `step`).
    edge = np.array([[0.0, 0, 0], [4.0, 0, 1.5]])
    slab = ((-1.0, -1.0, -0.1), (5.0, 1.0, 0.0))

    def flight(start: float, tread: float, rise: float) -> list:
        n = round(1.5 / rise)
        return [((start + tread * k, -1, 0.0), (5.0, 1, rise * (k + 1))) for k in range(n)]

    assert path_fault(edge, _boxes(slab, *flight(1.5, 0.1, 0.15)), P) == "steep"
    assert path_fault(edge, _boxes(slab, *flight(0.5, 0.2, 0.1)), P) is None


def test_a_route_is_checked_as_one_path():
    corner = np.array([[0.0, 0, 0], [4.0, 0, 0], [4.0, 0.5, 0.0]])
    assert path_fault(corner, _boxes(_SLAB), P) is None
    assert path_fault(corner * [1, 1, 0] + [0, 0.6, 0], _boxes(_SLAB), P) == "no_floor"


# ------------------------------------------------------------ crossings and routes, by hand


def test_crossing_corridors_at_body_height_conflict_and_stacked_ones_do_not():
    g = _graph(
        {
            "w": (-2.0, 0.0, 0.0),
            "e": (2.0, 0.0, 0.0),
            "s": (0.0, -3.0, 0.0),
            "n": (0.0, 3.0, 1.6),  # crosses w-e 0.8 m up: in the body band
            "s2": (0.5, -3.0, 2.4),
            "n2": (0.5, 3.0, 2.4),  # crosses w-e 2.4 m up: a storey above
            "w3": (-2.0, 0.3, 0.05),
            "e3": (-0.5, 0.3, 0.05),  # beside w-e at the same height
        },
        [("w", "e"), ("s", "n"), ("s2", "n2"), ("w3", "e3")],
    )
    edges = [(a, b) for a, b, _ in g.edges()]
    conflicts = crossings(g, edges, P)
    we = next(e for e in edges if set(e) == {"w", "e"})
    sn = next(e for e in edges if set(e) == {"s", "n"})
    assert conflicts[we] == {sn} and conflicts[sn] == {we}
    assert len(conflicts) == 2


def test_shortest_routes_avoid_the_edge_itself_and_respect_the_ratio():
    g = _graph({"a": (0.0, 0.0, 0.0), "b": (2.0, 0.0, 0.0), "c": (1.0, 0.5, 0.0)},
               [("a", "b"), ("a", "c"), ("c", "b")])  # fmt: skip
    edges = {frozenset(e[:2]): e[:2] for e in g.edges()}
    ab, ac, cb = edges[frozenset("ab")], edges[frozenset("ac")], edges[frozenset("cb")]
    routes = shortest_routes(g, [ab, ac, cb], [ab], ratio=1.5)
    assert routes == {ab: (ab[0], "c", ab[1])}
    assert shortest_routes(g, [ab, ac, cb], [ab], ratio=1.05) == {}  # the detour is 1.12×


def test_a_steep_edge_is_left_undrawn_and_walked_by_its_route():
    # b stands 1.6 m above a and 1 m beside it (a turning stair seen from its foot); the walk
    # goes round by c and d.
    floors = {"a": (0, 0, 0), "b": (1, 0, 1.6), "c": (-1, 4, 0.5), "d": (2, 4, 1.1)}
    g = _graph(floors, [("a", "b"), ("a", "c"), ("c", "d"), ("d", "b")])
    ab = next((a, b) for a, b, _ in g.edges() if {a, b} == {"a", "b"})
    assert edge_grade(g, *ab) > P.max_grade
    loose = build_proxy(g, ProxyParams(route_ratio=7.0))  # the detour is 6 times as long
    assert loose.faults == {ab: "steep"}
    assert loose.routes == {ab: ("a", "c", "d", "b")} and loose.unwalkable == []
    assert path_fault(route_floor_points(g, loose.routes[ab]), loose.boxes, P) is None
    # Without a route short enough, the proxy draws a flight of its own for the edge.
    strict = build_proxy(g)
    assert strict.faults == {ab: "steep"} and strict.flights == [ab] and strict.unwalkable == []


@pytest.mark.parametrize("rise", [0.6, 2.4, -3.0])
def test_a_lone_steep_edge_gets_a_gentle_flight(rise):
    # A line of sight up a turning stair with no other way between its storeys: the proxy
    # draws a flight climbing at stair_grade at most, which a body walks.
    g = _graph({"a": (0, 0, 0), "b": (0.5, 0.2, rise), "c": (-3, 0, 0), "d": (3.5, 0.2, rise)},
               [("a", "b"), ("a", "c"), ("b", "d")])  # fmt: skip
    ab = next((a, b) for a, b, _ in g.edges() if {a, b} == {"a", "b"})
    proxy = build_proxy(g)
    assert proxy.faults == {ab: "steep"} and proxy.flights == [ab] and proxy.unwalkable == []
    route = proxy.routes[ab]
    assert route[0] == ab[0] and route[-1] == ab[1]
    assert all(not isinstance(s, str) for s in route[1:-1])
    points = route_floor_points(g, route)
    legs = np.diff(points, axis=0)
    assert np.all(np.abs(legs[:, 2]) <= P.stair_grade * np.hypot(*legs[:, :2].T) + 1e-9)
    assert path_fault(points, proxy.boxes, P) is None
    # The other edges still walk straight.
    assert len(proxy.faults) == 1


def test_a_walk_over_a_viewpoint_on_a_stair_moves_out_of_its_way():
    # rqfALeAoiTq: the straight edge b-c runs 0.7 m over viewpoint a, halfway up a stair
    # from a to b. Drawn straight, b-c takes a's floor: no flight reaches a, and a-c does
    # not walk. Moving b-c onto a flight of its own frees a for both of its edges.
    g = _graph({"a": (-0.15, -1.17, -0.95), "b": (-0.88, -1.19, -0.06), "c": (1.03, -1.05, -0.58),
                "d": (2.34, -0.75, -0.56), "e": (-3.0, -1.2, -0.06)},
               [("a", "b"), ("a", "c"), ("b", "c"), ("c", "d"), ("b", "e")])  # fmt: skip
    proxy = build_proxy(g)
    assert proxy.unwalkable == []
    assert {frozenset(e) for e in proxy.flights} >= {frozenset("ab")}
    for via in proxy.routes.values():
        assert path_fault(route_floor_points(g, via), proxy.boxes, P) is None
    assert edge_walkability(g, proxy.boxes) == {
        cause: [e for e, c in proxy.faults.items() if c == cause] for cause in CAUSES
    }


@pytest.mark.parametrize(
    ("rise", "run", "degrees"),
    [(1.0, 2.5, 0.0), (1.5, 2.5, 20.0), (2.4, 4.0, 45.0), (-1.2, 3.0, 90.0)],
)
def test_a_stair_edge_is_drawn_with_treads_and_risers(rise, run, degrees):
    # A straight edge climbing more than stair_rise gets equal risers no higher than riser
    # (after 2 cm floor rounding) on treads run / risers long, give or take the 10 cm cells
    # the plan is drawn on.
    a = np.radians(degrees)
    g = _graph({"a": (0, 0, 0), "b": (run * np.cos(a), run * np.sin(a), rise), "c": (-2, 0, 0)},
               [("a", "b"), ("a", "c")])  # fmt: skip
    proxy = build_proxy(g)
    assert proxy.faults == {} and proxy.unwalkable == []
    ab = next((u, v) for u, v, _ in g.edges() if {u, v} == {"a", "b"})
    risers, treads = stair_steps(route_floor_points(g, ab), proxy.boxes, P)
    n = int(np.ceil(abs(rise) / P.riser))
    assert len(risers) == n and np.all(np.sign(risers) == np.sign(rise))
    assert np.abs(risers).max() <= P.riser + 1e-9
    assert np.all(np.abs(treads - run / n) <= 1.5 * P.cell)


def _seam_cells(proxy) -> int:
    """How many cell edges over free floor lie where two floor boxes of one top meet face to
    face."""
    b = proxy.boxes.of_kind("floor")
    lo, hi = b.lo, b.hi
    grid, free = proxy.grid, np.any(proxy.free, axis=0)
    same_top = np.abs(hi[:, None, 2] - hi[None, :, 2]) < 1e-6
    count = 0
    for axis in (0, 1):
        across = 1 - axis
        touch = np.abs(hi[:, None, axis] - lo[None, :, axis]) < 1e-6
        start = np.maximum(lo[:, None, across], lo[None, :, across])
        end = np.minimum(hi[:, None, across], hi[None, :, across])
        origin = np.array([grid.x0, grid.y0])
        for i, j in zip(*np.nonzero(touch & same_top & (end > start)), strict=True):
            line = (hi[i, axis] - origin[axis]) / grid.cell
            # The middles of the cells along the line that both faces span (a lip's 1 cm sliver
            # beside a side face spans none).
            steps = np.arange(start[i, j] + grid.cell / 2, end[i, j], grid.cell)
            along = ((steps - origin[across]) / grid.cell).astype(int)
            for side in (np.floor(line - 0.5), np.floor(line + 0.5)):
                beside = np.full_like(along, int(side))
                rc = (along, beside) if axis == 0 else (beside, along)
                inside = (rc[0] >= 0) & (rc[0] < free.shape[0]) & (rc[1] >= 0)
                inside &= rc[1] < free.shape[1]
                hit = np.zeros(len(along), bool)
                hit[inside] = free[rc[0][inside], rc[1][inside]]
                count += int(hit.sum())
    return count


def test_coplanar_floor_boxes_overlap_instead_of_meeting_face_to_face():
    # An L of corridors and a stair: its flat floor takes several boxes of one top. Where two
    # met face to face, a loaded foot was clamped between their side faces.
    g = _graph({"a": (0, 0, 0), "b": (4, 0, 0), "c": (4, 3, 0), "d": (-3, 0, 0.6)},
               [("a", "b"), ("b", "c"), ("a", "d")])  # fmt: skip
    proxy = build_proxy(g)
    floors = proxy.boxes.of_kind("floor")
    assert len(floors) > 10 and proxy.unwalkable == []
    assert _seam_cells(proxy) == 0
    # Each box still ends on the cell grid or one overlap past it.
    grid = proxy.grid
    for ends, lap in ((floors.lo, -SEAM_OVERLAP), (floors.hi, SEAM_OVERLAP)):
        cells = [(ends[:, :2] - s - (grid.x0, grid.y0)) / grid.cell for s in (0.0, lap)]
        on_grid = [np.abs(c - np.round(c)) < 1e-6 for c in cells]
        assert np.all(on_grid[0] | on_grid[1])
    # Of two boxes that meet, one reaches over the other: no strip is covered twice over.
    lo, hi = floors.lo, floors.hi
    span = np.minimum(hi[:, None, :2], hi[None, :, :2]) - np.maximum(
        lo[:, None, :2], lo[None, :, :2]
    )
    same_top = np.abs(hi[:, None, 2] - hi[None, :, 2]) < 1e-6
    shared = np.all(span > 1e-9, axis=-1) & same_top & ~np.eye(len(lo), dtype=bool)
    assert shared.any()
    assert np.all(span[shared].min(axis=-1) <= SEAM_OVERLAP + 1e-9)


def test_candidate_flights_join_the_ends_and_climb_gently_shortest_first():
    a, b = np.array([0.0, 0.0, 0.0]), np.array([0.3, 0.4, 2.0])  # 0.5 m apart, 2 m up
    flights = candidate_flights(a, b, P)
    assert len(flights) > 16
    lengths = []
    for flight in flights:
        np.testing.assert_allclose(flight[0], a, atol=1e-12)
        np.testing.assert_allclose(flight[-1], b, atol=1e-9)
        legs = np.diff(flight, axis=0)
        run = np.hypot(*legs[:, :2].T)
        assert np.all(np.abs(legs[:, 2]) <= P.stair_grade * run + 1e-9)
        assert np.all(legs[:, 2] >= -1e-12)  # climbs all the way
        lengths.append(run.sum())
    assert lengths[0] == pytest.approx(min(lengths))  # shortest first
    assert min(lengths) >= 2.0 / P.stair_grade - 1e-9


def test_route_stops_may_be_floor_points_with_cameras_at_their_ends_height():
    g = _graph({"a": (0, 0, 0), "b": (4, 0, 2.0)}, [("a", "b")])
    route = ("a", (2.0, 3.0, 1.0), "b")
    floors = route_floor_points(g, route)
    np.testing.assert_allclose(floors, [[0, 0, 0], [2, 3, 1], [4, 0, 2]])
    cameras = route_camera_points(g, route)
    np.testing.assert_allclose(cameras[[0, 2]], [g.position("a"), g.position("b")])
    np.testing.assert_allclose(cameras[1], [2, 3, 2.5])  # both cameras stand 1.5 m up


# ------------------------------------------------------------- drawing near other floors


def _walkable(floors: dict, edges: list[tuple[str, str]], edge: tuple[str, str]) -> bool:
    """Whether ``edge`` walks straight with all ``edges`` drawn straight (no routes, flights)."""
    g = _graph(floors, edges)
    comp_of = {vp: k for k, members in enumerate(g.components()) for vp in members}
    discs, legs = graph_elements(g, [(a, b) for a, b, _ in g.edges()], comp_of)
    grid = Grid.around(np.array([d.xy for d in discs]), P.viewpoint_radius + 3 * P.cell, P.cell)
    _, boxes = draw_elements(discs, legs, grid, P)
    return path_fault(route_floor_points(g, edge), boxes, P) is None


def test_a_landing_beside_a_corridor_stays_below_the_corridors_band():
    # A viewpoint on a stair landing 0.9 m up stands 0.6 m beside a flat edge: its floor
    # blends with the corridor's, but not into the band of a body walking the corridor.
    floors = {"a": (0, 0, 0), "b": (3, 0, 0), "s": (1.5, 0.6, 0.9), "t": (1.5, 3, 1.5)}
    assert _walkable(floors, [("a", "b"), ("s", "t")], ("a", "b"))
    # The landing's own edge does not walk beside the straight corridor; the proxy moves the
    # corridor onto a flight round the landing, and both walk.
    assert not _walkable(floors, [("a", "b"), ("s", "t")], ("s", "t"))
    assert build_proxy(_graph(floors, [("a", "b"), ("s", "t")])).unwalkable == []


def test_storeys_stack_where_a_body_fits_under_the_upper_floor():
    # Two viewpoints 0.14 m apart in plan, their floors 1.96 m apart: more than a body's
    # 1.8 m and a slab, so the lower floor keeps its walkway under the upper one.
    floors = {"l": (0, 0, 0), "l2": (3, 0, 0), "u": (0.1, 0.1, 1.96), "u2": (0.1, 3, 1.96)}
    assert _walkable(floors, [("l", "l2"), ("u", "u2")], ("l", "l2"))


@pytest.mark.parametrize("offset", [0.35, 0.45])
def test_a_floor_over_the_side_of_a_corridor_keeps_out_of_its_band(offset):
    # A viewpoint 1.85 m above a corridor, beside its line: its floor may not hang into
    # the band (1.8 m) of a body walking the corridor; where it must stay, it is thinned.
    floors = {"a": (0, 0, 0), "b": (4, 0, 0), "u": (2, offset, 1.85), "u2": (2, 3, 1.85)}
    assert _walkable(floors, [("a", "b"), ("u", "u2")], ("a", "b"))


def test_routes_file_round_trip_and_checks(tmp_path):
    routes = {
        ("a", "b"): ("a", "c", "b"),
        ("d", "e"): ("d", "f", "g", "e"),
        ("h", "i"): ("h", (0.5, -1.25, 2.0), (1.0, 0.0, 2.5), "i"),  # a flight
    }
    path = tmp_path / "routes.json"
    write_routes(path, routes)
    assert read_routes(path) == routes
    for stop in ([1.0, 2.0], [1.0, 2.0, float("nan")], {"x": 1}):
        path.write_text(json.dumps({"routes": [{"edge": ["a", "b"], "via": ["a", stop, "b"]}]}))
        with pytest.raises(MalformedDataError, match="not a valid routes file"):
            read_routes(path)
    assert read_routes(tmp_path / "absent.json") == {}
    path.write_text('{"routes": [{"edge": ["a", "b"], "via": ["a", "b"]}]}')
    with pytest.raises(MalformedDataError, match="a-b"):
        read_routes(path)
    path.write_text('{"routes": [{"edge": ["a"]}]}')
    with pytest.raises(MalformedDataError, match="not a valid routes file"):
        read_routes(path)


def test_proxy_params_are_checked():
    with pytest.raises(InvalidArgumentError, match=r"corridor_half_width=0\.1"):
        ProxyParams(corridor_half_width=0.1)
    with pytest.raises(InvalidArgumentError, match="cell=2"):
        ProxyParams(cell=2)
    with pytest.raises(InvalidArgumentError, match="max_grade=0"):
        ProxyParams(max_grade=0)
    with pytest.raises(InvalidArgumentError, match=r"headroom=1\.8"):
        ProxyParams(headroom=1.8)  # a body 1.8 m tall cannot pass under a 0.1 m slab
    assert ProxyParams().reach_cells == 2  # 0.2 m body radius on 0.1 m cells
    assert ProxyParams(cell=0.05).reach_cells == 4


def test_cover_cells_covers_each_cell_once_with_its_key_and_only_spare_cells_besides():
    rng = np.random.default_rng(3)
    key = np.where(rng.random((40, 30)) < 0.6, rng.integers(0, 3, (40, 30)), -1)
    key[:10] = 1  # a block that should merge into few rectangles
    spare = (key < 0) & (rng.random(key.shape) < 0.5)
    cover = np.zeros(key.shape, int)
    for r0, r1, c0, c1, k in cover_cells(key, spare):
        block = key[r0:r1, c0:c1]
        assert np.all((block == k) | spare[r0:r1, c0:c1])
        cover[r0:r1, c0:c1] += block == k
    # Exactly once: a foot on a cell covered twice would touch two boxes.
    assert np.all(cover[key >= 0] == 1)
    assert len(cover_cells(np.zeros((10, 10), int), np.zeros((10, 10), bool))) == 1
    # A disc on spare ground takes one box instead of one per row.
    yy, xx = np.mgrid[:20, :20]
    disc = np.where(np.hypot(yy - 9.5, xx - 9.5) < 9, 0, -1)
    assert len(cover_cells(disc, disc < 0)) == 1


def test_cover_rows_covers_each_keyed_cell_once_along_rows():
    rng = np.random.default_rng(4)
    key = np.where(rng.random((25, 30)) < 0.6, rng.integers(0, 3, (25, 30)), -1)
    rects = cover_rows(key)
    cover = np.zeros(key.shape, int)
    for r0, r1, c0, c1, k in rects:
        assert r1 == r0 + 1 and np.all(key[r0, c0:c1] == k)
        cover[r0, c0:c1] += 1
    np.testing.assert_array_equal(cover, key >= 0)
    # A maximal run is one rectangle: each ends where the key changes.
    assert len(rects) == int(
        np.sum((key >= 0) & (np.pad(key, ((0, 0), (1, 0)), constant_values=-1)[:, :-1] != key))
    )


# ------------------------------------------------------------------------ the real graphs


@pytest.fixture(scope="module")
def proxies(shared_data):
    out = {}
    for scan in SAMPLE:
        graph = NavGraph.from_file(shared_data / "mp3d_connectivity" / f"{scan}_connectivity.json")
        out[scan] = (graph, build_proxy(graph))
    return out


@pytest.mark.parametrize("scan", SAMPLE)
def test_edges_are_walkable_straight_or_by_route(proxies, scan):
    graph, proxy = proxies[scan]
    checked = {e: cause for cause, es in edge_walkability(graph, proxy.boxes).items() for e in es}
    assert proxy.faults == checked
    straight = [(a, b) for a, b, _ in graph.edges() if (a, b) not in proxy.faults]
    for (a, b), via in proxy.routes.items():
        points = route_floor_points(graph, via)
        assert path_fault(points, proxy.boxes, P) is None  # the whole route passes the check
        if (a, b) in proxy.flights:
            # A flight drawn for the edge climbs at stair_grade at most.
            legs = np.diff(points, axis=0)
            assert np.all(np.abs(legs[:, 2]) <= P.stair_grade * np.hypot(*legs[:, :2].T) + 1e-9)
            continue
        # Only edges that provably cannot be drawn straight are routed through viewpoints...
        assert edge_grade(graph, a, b) > P.max_grade or (a, b) in proxy.crossing
        # ...over edges walked straight, no longer than route_ratio times the edge...
        links = {frozenset(link) for link in itertools.pairwise(via)}
        assert links <= {frozenset(e) for e in straight}
        length = sum(np.linalg.norm(graph.position(u) - graph.position(v)) for u, v in links)
        assert length <= P.route_ratio * np.linalg.norm(graph.position(a) - graph.position(b))
    # Every edge walks, here as over all 90 graphs (benchmarks/bench_proxies.py).
    assert proxy.unwalkable == []


def test_a_walk_over_a_stair_viewpoint_moves_in_a_real_building(shared_data):
    # rqfALeAoiTq: viewpoint 670d5f stands halfway up a stair, 0.7 m under the straight edge
    # 72bdf3-4f6331. No flight reached it while nearby walks stayed where they were; one of
    # them (an edge that can be drawn) now takes a flight of its own.
    conn = shared_data / "mp3d_connectivity"
    graph = NavGraph.from_file(conn / "rqfALeAoiTq_connectivity.json")
    proxy = build_proxy(graph)
    assert proxy.unwalkable == []
    assert any(edge_grade(graph, *e) <= P.max_grade for e in proxy.flights)
    stair_vp = next(v for v in graph.nodes if v.startswith("670d5f"))
    for a, b, _ in graph.edges():
        if stair_vp in (a, b):
            via = proxy.routes.get((a, b), (a, b))
            assert path_fault(route_floor_points(graph, via), proxy.boxes, P) is None


@pytest.mark.parametrize("scan", SAMPLE)
def test_every_box_is_solid_at_the_precision_of_boxes_json(proxies, scan):
    _, proxy = proxies[scan]
    size = np.round(proxy.boxes.hi, 4) - np.round(proxy.boxes.lo, 4)
    assert size.min() >= 0.001  # MuJoCo rejects a box of zero size


@pytest.mark.parametrize("scan", SAMPLE)
def test_floors_stand_under_every_viewpoint(proxies, scan):
    graph, proxy = proxies[scan]
    b = proxy.boxes.of_kind("floor")
    for vp in graph.nodes:
        x, y, _ = graph.position(vp)
        under = (b.lo[:, 0] <= x) & (b.hi[:, 0] >= x) & (b.lo[:, 1] <= y) & (b.hi[:, 1] >= y)
        assert np.min(np.abs(b.hi[under, 2] - graph.floor_z(vp))) <= 0.1, vp


@pytest.mark.parametrize("scan", SAMPLE)
def test_few_coplanar_floor_boxes_meet_face_to_face(proxies, scan):
    # What is left: seams where no box has room to reach over (a body walking a floor below
    # or above within reach).
    _, proxy = proxies[scan]
    assert _seam_cells(proxy) <= 0.01 * np.count_nonzero(proxy.free)


@pytest.mark.parametrize("scan", ["JF19kD82Mey", "PuKPg4mmafe", "2azQ1b91cZZ"])
def test_disconnected_viewpoints_stay_disconnected(proxies, scan):
    graph, proxy = proxies[scan]
    comps = graph.components()
    comp_of = {vp: k for k, members in enumerate(comps) for vp in members}
    grid = proxy.grid
    for free in proxy.free:
        labels, _ = label(free, structure=np.ones((3, 3)))
        region_comp: dict[int, int] = {}
        for vp in graph.nodes:
            x, y, _ = graph.position(vp)
            r, c = int((y - grid.y0) / grid.cell), int((x - grid.x0) / grid.cell)
            if free[r, c]:
                k = region_comp.setdefault(labels[r, c], comp_of[vp])
                assert k == comp_of[vp], f"{vp} shares floor with component {k}"
    if scan != "2azQ1b91cZZ":
        assert len(comps) > 1
