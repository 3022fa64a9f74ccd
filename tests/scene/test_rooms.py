"""Room plans: portals between rectangular rooms, what a camera can see, geometry by room."""

from __future__ import annotations

import math

import numpy as np
import pytest

from havln_mj.scene.boxes import BoxSet
from havln_mj.scene.mesh import MeshPart, merge_by_look
from havln_mj.scene.regions import Level, Region, Regions
from havln_mj.scene.rooms import FULL, overlap, portal_wedge, room_plan, split_by_rooms
from havln_mj.scene.scan import load_scan

HEIGHT = 2.5


def _regions(rects: list[tuple[float, float, float, float]], levels: int = 1) -> Regions:
    regions = tuple(
        Region(
            k,
            0,
            "b",
            np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]),
            np.array([x0, y0, 0.0, x1, y1, HEIGHT]),
            HEIGHT,
        )
        for k, (x0, y0, x1, y1) in enumerate(rects)
    )
    return Regions(tuple(Level(k, 3.0 * k, 3.0 * k + HEIGHT) for k in range(levels)), regions)


def _walls(boxes: list[tuple[tuple, tuple]]) -> BoxSet:
    n = len(boxes)
    return BoxSet(
        np.array([lo for lo, _ in boxes], float).reshape(n, 3),
        np.array([hi for _, hi in boxes], float).reshape(n, 3),
        ("wall",) * n,
        ("paint",) * n,
        np.ones((n, 4)),
    )


# Two 4 m rooms side by side; the wall between them (x = 4) has a door from y = 1.5 to 2.5.
TWO_ROOMS = _regions([(0.0, 0.0, 4.0, 4.0), (4.0, 0.0, 8.0, 4.0)])
WALL_WITH_DOOR = _walls(
    [((4.0, 0.0, 0.0), (4.1, 1.5, HEIGHT)), ((4.0, 2.5, 0.0), (4.1, 4.0, HEIGHT))]
)


def _facing(azimuth_deg: float, half_deg: float = 35.0) -> tuple[float, float]:
    return math.radians(azimuth_deg), math.radians(half_deg)


def test_a_door_is_the_one_portal_between_two_rooms():
    plan = room_plan(TWO_ROOMS, WALL_WITH_DOOR)
    assert plan is not None and plan.n_rooms == 2
    (portal,) = plan.portals[0]
    assert portal.room == 1 and plan.portals[1][0].room == 0
    assert portal.a[0] == pytest.approx(4.0) and portal.b[0] == pytest.approx(4.0)
    assert sorted([portal.a[1], portal.b[1]]) == pytest.approx([1.5, 2.5], abs=2e-3)


def test_a_camera_sees_the_next_room_through_the_door_only():
    plan = room_plan(TWO_ROOMS, WALL_WITH_DOOR)
    at = np.array([2.0, 2.0, 1.5])
    assert plan.visible(at, _facing(0.0)).tolist() == [True, True]  # facing the door
    assert plan.visible(at, _facing(180.0)).tolist() == [True, False]  # back to it
    beside = np.array([2.0, 0.5, 1.5])  # facing the wall beside the door, the door out of view
    assert plan.visible(beside, _facing(0.0, 10.0)).tolist() == [True, False]
    assert plan.visible(beside, _facing(0.0, 30.0)).tolist() == [True, True]
    assert plan.visible(at, FULL).tolist() == [True, True]


def test_without_a_wall_the_shared_edge_is_open_and_a_full_wall_closes_it():
    open_plan = room_plan(TWO_ROOMS, _walls([]))
    assert open_plan.visible(np.array([2.0, 0.5, 1.5]), _facing(0.0, 10.0)).all()
    closed = room_plan(TWO_ROOMS, _walls([((4.0, 0.0, 0.0), (4.1, 4.0, HEIGHT))]))
    assert closed.portals == ((), ())
    assert closed.visible(np.array([2.0, 2.0, 1.5]), FULL).tolist() == [True, False]


def test_a_wall_short_of_the_ceiling_is_no_occluder():
    half = room_plan(TWO_ROOMS, _walls([((4.0, 0.0, 0.0), (4.1, 4.0, 1.2))]))
    assert half.visible(np.array([2.0, 2.0, 1.5]), FULL).all()


def test_cameras_outside_the_rooms_or_the_storey_see_everything():
    plan = room_plan(TWO_ROOMS, WALL_WITH_DOOR)
    assert plan.visible(np.array([-1.0, 2.0, 1.5]), FULL) is None
    assert plan.visible(np.array([2.0, 2.0, HEIGHT + 0.5]), FULL) is None
    # At a room's edge (in the doorway) the search starts in both rooms.
    assert plan.visible(np.array([4.02, 2.0, 1.5]), _facing(90.0)).all()


def test_an_open_plan_of_many_rooms_is_searched_quickly():
    # 6 × 5 rooms with no walls: paths between them are countless, wedges keep it short.
    rects = [(3.0 * i, 3.0 * j, 3.0 * i + 3, 3.0 * j + 3) for i in range(6) for j in range(5)]
    plan = room_plan(_regions(rects), _walls([]))
    assert sum(len(p) for p in plan.portals) == 2 * (5 * 5 + 6 * 4)
    assert plan.visible(np.array([1.5, 1.5, 1.5]), FULL).all()
    ahead = plan.visible(np.array([1.5, 1.5, 1.5]), _facing(0.0, 5.0))  # along +x only
    assert ahead.reshape(6, 5)[:, 0].all() and not ahead.reshape(6, 5)[:, 2:].any()


def test_only_one_storey_of_rectangles_tiling_a_rectangle_has_a_plan():
    assert room_plan(_regions([(0, 0, 4, 4), (4, 0, 8, 4)], levels=2), WALL_WITH_DOOR) is None
    assert room_plan(_regions([(0, 0, 4, 4), (5, 0, 8, 4)]), WALL_WITH_DOOR) is None  # a gap
    assert room_plan(_regions([(0, 0, 4, 4), (3, 0, 8, 4)]), WALL_WITH_DOOR) is None  # overlap
    assert room_plan(TWO_ROOMS, None) is None
    assert room_plan(None, WALL_WITH_DOOR) is None


def test_portal_wedges_and_their_overlap():
    centre, half = portal_wedge((0.0, 0.0), (1.0, -1.0), (1.0, 1.0))
    assert centre == pytest.approx(0.0) and half == pytest.approx(math.pi / 4)
    assert portal_wedge((1.0, 0.0), (1.0, -1.0), (1.0, 1.0)) == FULL  # on its line
    # Wedges on either side of the ±π cut still meet.
    left, right = (math.radians(170), math.radians(15)), (math.radians(-170), math.radians(15))
    centre, half = overlap(left, right)
    assert abs(math.remainder(centre - math.pi, math.tau)) < 1e-9
    assert half == pytest.approx(math.radians(5))
    assert overlap((0.0, 0.1), (1.0, 0.1)) is None
    assert overlap(FULL, (1.0, 0.1)) == (1.0, 0.1)


def test_a_procedural_house_has_doors_where_no_wall_stands():
    scan = load_scan("proc-0")
    plan = scan.room_plan
    assert plan is not None and plan.n_rooms == len(scan.regions.regions)
    portals = [p for room in plan.portals for p in room]
    assert len(portals) >= 2 * (plan.n_rooms - 1)  # every room reached
    walls = scan.boxes.of_kind("wall")
    for portal in portals:
        mid = 0.5 * (np.array(portal.a) + np.array(portal.b))
        covering = np.all((walls.lo[:, :2] <= mid) & (walls.hi[:, :2] >= mid), axis=1)
        full = (walls.lo[:, 2] <= 0.01) & (walls.hi[:, 2] >= plan.ceiling - 0.01)
        assert not (covering & full).any()
    # From every viewpoint, looking every way, every room reachable by doors is seen; the
    # house's rooms are not all seen from anywhere.
    seen = [plan.visible(np.array(scan.graph.position(v)), FULL) for v in scan.graph.nodes]
    assert all(s is not None and s.any() for s in seen)
    assert min(int(s.sum()) for s in seen) < plan.n_rooms


def test_splitting_by_room_keeps_every_triangle_once():
    scan = load_scan("proc-3")
    parts = merge_by_look(scan.mesh_parts)
    split = split_by_rooms(parts, scan.room_plan)

    def triangles(ps: list[MeshPart]) -> np.ndarray:
        tri = np.concatenate([np.asarray(p.vertices)[p.faces].reshape(-1, 9) for p in ps])
        return tri[np.lexsort(tri.T[::-1])]

    np.testing.assert_array_equal(triangles(parts), triangles([p for _, p in split]))
    assert len(split) > len(parts)
    rects = scan.room_plan.rects
    for rooms, part in split:
        lo, hi = part.vertices[:, :2].min(axis=0), part.vertices[:, :2].max(axis=0)
        for r in rooms:  # each room listed holds some of the part (within the margin)
            x0, y0, x1, y1 = rects[r]
            assert lo[0] <= x1 + 0.011 and hi[0] >= x0 - 0.011
            assert lo[1] <= y1 + 0.011 and hi[1] >= y0 - 0.011
        assert part.uv is None or len(part.uv) == len(part.vertices)
