"""Viewpoints and their graph for a procedural house.

Viewpoints stand about ``viewpoint_spacing`` apart in each room's free floor (clear of walls
and furniture), plus one on each side of every door. ``unobstructed`` joins two viewpoints
when the agent's body, swept along the segment between them, touches no box; edges
that pass almost through a third viewpoint are pruned (the detour is kept instead, so the
graph's connectivity never changes). ``visible`` is line
of sight between the two camera positions.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from havln_mj.scene.boxes import BoxSet, body_sweep_blocked, segments_hit_boxes
from havln_mj.scene.procedural.furnish import Item
from havln_mj.scene.procedural.layout import FloorPlan, Room
from havln_mj.scene.procedural.recipe import Recipe

if TYPE_CHECKING:
    from scipy.sparse import csr_matrix

_DOOR_OFFSET = 0.7  # door viewpoints stand this far from the wall line
_LATTICE = 0.25  # free-floor sampling step
_DETOUR = (
    1.1  # an edge is dropped when a viewpoint k joined to both has d_ik + d_kj < _DETOUR * d_ij
)


@dataclass(frozen=True)
class ViewpointGraph:
    """Viewpoints (floor points), camera heights, rooms and graph flags."""

    floor: np.ndarray  # (N, 3) floor point under each camera
    height: np.ndarray  # (N,) camera height above the floor
    room: np.ndarray  # (N,) room index
    unobstructed: np.ndarray  # (N, N) bool, symmetric
    visible: np.ndarray  # (N, N) bool, symmetric

    @property
    def camera(self) -> np.ndarray:
        """(N, 3) camera positions."""
        return self.floor + np.column_stack([np.zeros((len(self.height), 2)), self.height])


def _clear_of(p: np.ndarray, feet: np.ndarray, clearance: float) -> bool:
    """Whether 2-D point ``p`` is at least ``clearance`` from every footprint (x0, y0, x1, y1)."""
    if len(feet) == 0:
        return True
    dx = np.maximum(np.maximum(feet[:, 0] - p[0], p[0] - feet[:, 2]), 0.0)
    dy = np.maximum(np.maximum(feet[:, 1] - p[1], p[1] - feet[:, 3]), 0.0)
    return bool(np.all(np.hypot(dx, dy) >= clearance))


def _far_from(p: np.ndarray, points: list[np.ndarray], spacing: float) -> bool:
    return all(np.hypot(*(p - q)) >= spacing for q in points)


def _room_lattice(
    recipe: Recipe, inner: np.ndarray, feet: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Lattice points on a room's free floor, and their clearance.

    Clearance is the distance in metres to the nearest wall or furniture footprint.
    """
    lo, hi = inner[:2] + recipe["wall_clearance"], inner[2:] - recipe["wall_clearance"]
    if np.any(hi < lo):
        return np.zeros((0, 2)), np.zeros(0)
    n = np.floor((hi - lo) / _LATTICE).astype(int) + 1
    offset = (hi - lo - (n - 1) * _LATTICE) / 2
    gx, gy = np.meshgrid(*(lo[k] + offset[k] + _LATTICE * np.arange(n[k]) for k in (0, 1)))
    grid = np.column_stack([gx.ravel(), gy.ravel()])
    to_wall = np.minimum(grid - inner[:2], inner[2:] - grid).min(axis=1)
    to_furniture = np.full(len(grid), np.inf)
    if len(feet):
        dx = np.maximum(feet[None, :, 0] - grid[:, None, 0], grid[:, None, 0] - feet[None, :, 2])
        dy = np.maximum(feet[None, :, 1] - grid[:, None, 1], grid[:, None, 1] - feet[None, :, 3])
        to_furniture = np.hypot(np.maximum(dx, 0), np.maximum(dy, 0)).min(axis=1)
    ok = to_furniture >= recipe["furniture_clearance"]
    return grid[ok], np.minimum(to_wall, to_furniture)[ok]


def _footprints(items: list[Item]) -> np.ndarray:
    return np.array([it.bbox[[0, 1, 3, 4]] for it in items]).reshape(-1, 4)


def _free_lattice(
    recipe: Recipe, plan: FloorPlan, inners: list[np.ndarray], feet: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lattice points of all rooms, their rooms and clearances."""
    pts, rooms, clear = [], [], []
    for room, inner in zip(plan.rooms, inners, strict=True):
        grid, c = _room_lattice(recipe, inner, feet)
        pts.append(grid)
        rooms.append(np.full(len(grid), room.index))
        clear.append(c)
    return np.concatenate(pts), np.concatenate(rooms), np.concatenate(clear)


def _dense_graph(
    recipe: Recipe, door_pts: np.ndarray, lattice: np.ndarray, boxes: BoxSet
) -> csr_matrix:
    """Walkable links between neighbouring lattice points and from door points (first)."""
    from scipy.sparse import csr_matrix  # scipy: only while a house is generated
    from scipy.spatial import cKDTree

    dense = np.vstack([door_pts.reshape(-1, 2), lattice])
    tree = cKDTree(dense)
    near_pairs = tree.query_pairs(1.5 * _LATTICE, output_type="ndarray")
    door_pairs = tree.query_pairs(2 * _DOOR_OFFSET + 0.01, output_type="ndarray")
    door_pairs = door_pairs[door_pairs[:, 0] < len(door_pts)]
    d3 = np.column_stack([dense, np.zeros(len(dense))])
    i, j, w = _edges(d3, boxes, recipe, 0.0, np.vstack([near_pairs, door_pairs]))
    return csr_matrix((w + 1e-9, (i, j)), shape=(len(dense),) * 2)


def room_is_passable(
    recipe: Recipe, plan: FloorPlan, room: Room, inner: np.ndarray, items: list[Item], walls: BoxSet
) -> bool:
    """Whether the room's doors are joined through its free floor with ``items`` in place.

    Args:
        recipe: The procedural recipe.
        plan: The floor plan.
        room: The room.
        inner: The room's floor inside its walls.
        items: The room's furniture.
        walls: Wall boxes (of at least this room).

    Returns:
        True when all door points and most of the free floor form one walkable piece.
    """
    from scipy.sparse.csgraph import connected_components  # scipy: only while generating

    feet = _footprints(items)
    door_pts, door_rooms = _door_points(recipe, plan, feet)
    mine = np.array([r == room.index for r in door_rooms], dtype=bool)
    expected = sum(room.index in (d.a, d.b) for d in plan.doors)
    if mine.sum() < expected:
        return False
    lattice, _ = _room_lattice(recipe, inner, feet)
    parts = [p for it in items for p in it.parts]
    obstacles = BoxSet(
        np.vstack([walls.lo, *[p.lo[None] for p in parts]]),
        np.vstack([walls.hi, *[p.hi[None] for p in parts]]),
        ("wall",) * (len(walls) + len(parts)),
        ("",) * (len(walls) + len(parts)),
        np.zeros((len(walls) + len(parts), 4)),
    )
    pts = np.array(door_pts).reshape(-1, 2)[mine]
    _, labels = connected_components(_dense_graph(recipe, pts, lattice, obstacles), directed=False)
    if len(set(labels[: len(pts)])) > 1:
        return False
    return np.mean(labels == labels[0]) >= 0.6 if len(pts) else True


def _door_points(
    recipe: Recipe, plan: FloorPlan, feet: np.ndarray
) -> tuple[list[np.ndarray], list[int]]:
    """One point on each side of every door, on the door's centre line."""
    pts: list[np.ndarray] = []
    rooms: list[int] = []
    for door in plan.doors:
        normal = np.array([1.0, 0.0]) if door.vertical else np.array([0.0, 1.0])
        for r in (door.a, door.b):
            room = plan.rooms[r]
            centre = np.array([(room.x0 + room.x1) / 2, (room.y0 + room.y1) / 2])
            p = door.center + np.sign(np.dot(centre - door.center, normal)) * _DOOR_OFFSET * normal
            if _clear_of(p, feet, recipe["furniture_clearance"]) and _far_from(p, pts, 0.4):
                pts.append(p)
                rooms.append(r)
    return pts, rooms


def _edges(
    floor: np.ndarray,
    boxes: BoxSet,
    recipe: Recipe,
    max_len: float,
    pairs: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pairs (i < j) closer than ``max_len`` whose body sweep is clear, with their lengths."""
    from scipy.spatial import cKDTree  # scipy: only while a house is generated

    if pairs is None:
        pairs = cKDTree(floor[:, :2]).query_pairs(max_len, output_type="ndarray")
    pairs = pairs.reshape(-1, 2)
    i, j = pairs[:, 0], pairs[:, 1]
    blocked = body_sweep_blocked(
        floor[i], floor[j], boxes, recipe["body_radius"], tuple(recipe["body_z"])
    )
    i, j = i[~blocked], j[~blocked]
    return i, j, np.linalg.norm(floor[i, :2] - floor[j, :2], axis=1)


def _bridge(
    pts: np.ndarray,
    labels: np.ndarray,
    dense: np.ndarray,
    dense_graph: csr_matrix,
    boxes: BoxSet,
    recipe: Recipe,
) -> list[np.ndarray]:
    """New viewpoints joining the largest component to the nearest other one.

    The route follows the dense graph; the string is pulled tight, so each new point is the
    farthest route point still in clear reach of the previous one and consecutive points are
    always joined. Returns nothing when no other component is reachable.
    """
    from scipy.sparse.csgraph import dijkstra  # scipy: only while a house is generated

    max_len = recipe["max_edge_length"]
    radius, z_range = recipe["body_radius"], tuple(recipe["body_z"])
    near = np.argmin(np.linalg.norm(dense[None] - pts[:, None], axis=2), axis=1)
    main = labels == np.bincount(labels).argmax()
    dist, pred, src = dijkstra(
        dense_graph,
        directed=False,
        indices=np.unique(near[main]),
        min_only=True,
        return_predecessors=True,
    )
    others = np.flatnonzero(~main)
    others = others[np.isfinite(dist[near[others]])]
    if len(others) == 0:
        return []
    start = int(others[np.argmin(dist[near[others]])])
    node, route = int(near[start]), [pts[start]]
    while node >= 0:
        route.append(dense[node])
        node = int(pred[node])
    route.append(pts[np.flatnonzero(main & (near == src[near[start]]))[0]])
    route = np.array(route)
    out, anchor = [], 0
    while anchor < len(route) - 1:
        ahead = np.arange(anchor + 1, len(route))
        ahead = ahead[np.linalg.norm(route[ahead] - route[anchor], axis=1) <= 0.9 * max_len]
        a3 = np.column_stack([np.repeat(route[anchor][None], len(ahead), 0), np.zeros(len(ahead))])
        b3 = np.column_stack([route[ahead], np.zeros(len(ahead))])
        clear = ahead[~body_sweep_blocked(a3, b3, boxes, radius, z_range)]
        anchor = int(clear.max()) if len(clear) else anchor + 1
        if anchor < len(route) - 1:
            out.append(route[anchor])
    return out


def _candidates(
    rng: np.random.Generator,
    recipe: Recipe,
    plan: FloorPlan,
    inners: list[np.ndarray],
    items: list[Item],
    boxes: BoxSet,
) -> tuple[np.ndarray, np.ndarray]:
    """2-D viewpoint positions and their rooms.

    Door pairs come first, then a Poisson-disk sample of the free floor, then bridge points
    wherever the sample leaves reachable floor disconnected.
    """
    from scipy.sparse import csr_matrix  # scipy: only while a house is generated
    from scipy.sparse.csgraph import connected_components

    feet = _footprints(items)
    door_pts, door_rooms = _door_points(recipe, plan, feet)
    lattice, lattice_rooms, clearance = _free_lattice(recipe, plan, inners, feet)
    spacing = recipe["viewpoint_spacing"]
    chosen = list(door_pts)
    rooms = list(door_rooms)
    # Open floor first, with noise so the pattern is irregular like a human-placed survey.
    priority = np.minimum(clearance, 1.0) + rng.uniform(0.0, 0.6, len(lattice))
    for k in np.argsort(-priority, kind="stable"):
        if _far_from(lattice[k], chosen, spacing):
            chosen.append(lattice[k])
            rooms.append(int(lattice_rooms[k]))
    # Dense graph over doors + lattice: which floor is reachable from which.
    dense = np.vstack([np.array(door_pts).reshape(-1, 2), lattice])
    dense_rooms = np.concatenate([door_rooms, lattice_rooms]).astype(int)
    dense_graph = _dense_graph(recipe, np.array(door_pts), lattice, boxes)
    for _ in range(len(plan.rooms) * 4):
        floor = np.column_stack([np.array(chosen), np.zeros(len(chosen))])
        a, b, _ = _edges(floor, boxes, recipe, recipe["max_edge_length"])
        n_comp, labels = connected_components(
            csr_matrix((np.ones(len(a)), (a, b)), shape=(len(chosen),) * 2), directed=False
        )
        if n_comp == 1:
            break
        bridge = _bridge(np.array(chosen), labels, dense, dense_graph, boxes, recipe)
        if not bridge:
            break
        for p in bridge:
            chosen.append(p)
            rooms.append(int(dense_rooms[np.argmin(np.linalg.norm(dense - p, axis=1))]))
    return np.array(chosen), np.array(rooms)


def _prune(unob: np.ndarray, dist: np.ndarray) -> np.ndarray:
    """Drops edge ij when some k joined to both lies nearly on the way (a short detour)."""
    keep = unob.copy()
    for i, j in zip(*np.nonzero(np.triu(unob)), strict=True):
        witness = unob[i] & unob[j] & (dist[i] + dist[j] < _DETOUR * dist[i, j])
        if witness.any():
            keep[i, j] = keep[j, i] = False
    return keep


def place_viewpoints(
    rng: np.random.Generator,
    recipe: Recipe,
    plan: FloorPlan,
    inners: list[np.ndarray],
    items: list[Item],
    boxes: BoxSet,
) -> ViewpointGraph:
    """Places viewpoints and computes ``unobstructed`` and ``visible`` by ray casts on ``boxes``.

    Only the largest connected component is kept, so every viewpoint is reachable.
    """
    from scipy.sparse import csr_matrix  # scipy: only while a house is generated
    from scipy.sparse.csgraph import connected_components

    pts, rooms = _candidates(rng, recipe, plan, inners, items, boxes)
    n = len(pts)
    floor = np.column_stack([pts, np.zeros(n)])
    height = np.round(rng.uniform(*recipe["camera_height"], n), 3)
    dist = np.linalg.norm(floor[:, None, :2] - floor[None, :, :2], axis=2)
    i, j, _ = _edges(floor, boxes, recipe, recipe["max_edge_length"])
    unob = np.zeros((n, n), dtype=bool)
    unob[i, j] = True
    unob |= unob.T
    unob = _prune(unob, dist)

    solid = boxes.of_kind("wall", "furniture")
    cam = floor + np.column_stack([np.zeros((n, 2)), height])
    i, j = np.nonzero(np.triu(np.ones((n, n), dtype=bool), k=1))
    seen = ~segments_hit_boxes(cam[i], cam[j], solid.lo, solid.hi)
    vis = np.zeros((n, n), dtype=bool)
    vis[i[seen], j[seen]] = True
    vis |= vis.T

    _, labels = connected_components(csr_matrix(unob), directed=False)
    keep = labels == np.bincount(labels).argmax()
    idx = np.flatnonzero(keep)
    return ViewpointGraph(
        floor[idx], height[idx], np.array(rooms)[idx], unob[np.ix_(idx, idx)], vis[np.ix_(idx, idx)]
    )
