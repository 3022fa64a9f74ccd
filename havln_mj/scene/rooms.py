"""Which rooms a camera can see: full-height walls hide, doorways are portals.

A building whose regions are one storey of axis-aligned rectangles tiling a rectangle, with
its exact boxes (procedural houses), has a :class:`RoomPlan`. Where two rooms share an edge,
the stretches of it no full-height wall covers are *portals*. A straight line of sight from a
room into another crosses their shared edge, so it passes through a portal: the rooms a
camera can see are those reached from its own through portals whose directions, seen from
the camera, overlap its field of view, narrowed portal by portal (portal culling). Walls are
full height, so this plan view answers for every line of sight in 3-D.

The answer is conservative: a room counted as seen may be hidden after all, never the
reverse. A wall counts only where it covers the shared edge itself, openings below lintels
and half-height walls are portals, and a camera near an edge, above or below the storey, or
outside every room sees everything (None).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from havln_mj.scene.boxes import BoxSet, interval_gaps
from havln_mj.scene.mesh import MeshPart
from havln_mj.scene.regions import Regions

EDGE_TOL_M = 1e-4
"""Metres within which two rooms share an edge and a wall covers it."""

ROOM_TOL_M = 0.01
"""Metres a room's rectangle is grown by when geometry is assigned to rooms."""

START_MARGIN_M = 0.05
"""A camera this close to another room's rectangle starts its search there too."""

PORTAL_GROW_M = 1e-3
"""Metres each portal is lengthened at both ends (numerical margin)."""

FULL = (0.0, math.pi)
"""The wedge of every direction, ``(centre, half width)`` with half width π."""

Wedge = tuple[float, float]


@dataclass(frozen=True)
class Portal:
    """An open stretch of the edge two rooms share: from ``a`` to ``b`` (x, y)."""

    room: int
    a: tuple[float, float]
    b: tuple[float, float]


@dataclass(frozen=True)
class RoomPlan:
    """One storey's rooms (rectangles) and the portals between them.

    Attributes:
        rects: (R, 4) ``xlo, ylo, xhi, yhi`` of each room.
        floor: The storey's floor height (m).
        ceiling: Its ceiling height (m).
        portals: For each room, the portals out of it (``Portal.room`` is the room beyond).
    """

    rects: np.ndarray
    floor: float
    ceiling: float
    portals: tuple[tuple[Portal, ...], ...]

    @property
    def n_rooms(self) -> int:
        """Number of rooms."""
        return len(self.rects)

    def rooms_meeting(
        self, lo: np.ndarray, hi: np.ndarray, margin: float = ROOM_TOL_M
    ) -> np.ndarray:
        """(N, R) bool: the rooms, grown by ``margin``, that each plan box ``lo``–``hi`` meets."""
        r = self.rects[None]
        lo, hi = lo[:, None], hi[:, None]
        return (
            (lo[..., 0] <= r[..., 2] + margin)
            & (hi[..., 0] >= r[..., 0] - margin)
            & (lo[..., 1] <= r[..., 3] + margin)
            & (hi[..., 1] >= r[..., 1] - margin)
        )

    def visible(self, position: np.ndarray, wedge: Wedge) -> np.ndarray | None:
        """Which rooms a camera at ``position`` seeing the plan directions ``wedge`` may see.

        Args:
            position: The camera's (x, y, z).
            wedge: ``(centre, half width)`` of the azimuths (radians, atan2 of y, x) its view
                spans in plan; :data:`FULL` for all.

        Returns:
            (R,) bool, or None when the camera is outside the storey's rooms (all are seen).
        """
        x, y, z = (float(v) for v in position)
        if not self.floor < z < self.ceiling:
            return None
        point = np.array([[x, y]])
        if not self.rooms_meeting(point, point, 0.0).any():
            return None
        starts = np.flatnonzero(self.rooms_meeting(point, point, START_MARGIN_M)[0]).tolist()
        seen = np.zeros(self.n_rooms, dtype=bool)
        for room in starts:
            self._search(room, wedge, (x, y), seen, {room})
        return seen

    def _search(
        self, room: int, wedge: Wedge, at: tuple[float, float], seen: np.ndarray, path: set
    ) -> None:
        # A line of sight crosses each (convex) room once: paths without repeats suffice.
        seen[room] = True
        for portal in self.portals[room]:
            if portal.room in path:
                continue
            narrowed = overlap(wedge, portal_wedge(at, portal.a, portal.b))
            if narrowed is not None:
                path.add(portal.room)
                self._search(portal.room, narrowed, at, seen, path)
                path.discard(portal.room)


def portal_wedge(at: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> Wedge:
    """The directions from ``at`` through the segment ``a``–``b`` (:data:`FULL` on its line)."""
    ax, ay = a[0] - at[0], a[1] - at[1]
    bx, by = b[0] - at[0], b[1] - at[1]
    length = math.hypot(b[0] - a[0], b[1] - a[1])
    if abs(ax * by - ay * bx) <= EDGE_TOL_M * length:  # the camera is on the portal's line
        return FULL
    ta, tb = math.atan2(ay, ax), math.atan2(by, bx)
    half = 0.5 * abs(math.remainder(tb - ta, math.tau))
    return ta + math.remainder(tb - ta, math.tau) / 2, half


def overlap(a: Wedge, b: Wedge) -> Wedge | None:
    """The directions in both wedges, or None. Each is :data:`FULL` or narrower than π."""
    if a[1] >= math.pi:
        return b
    if b[1] >= math.pi:
        return a
    d = math.remainder(b[0] - a[0], math.tau)
    lo, hi = max(-a[1], d - b[1]), min(a[1], d + b[1])
    if lo > hi:
        return None
    return a[0] + (lo + hi) / 2, (hi - lo) / 2


def room_plan(regions: Regions | None, boxes: BoxSet | None) -> RoomPlan | None:
    """The plan of a one-storey building of rectangular rooms, or None for any other."""
    if regions is None or boxes is None or len(regions.levels) != 1 or not regions.regions:
        return None
    rects = []
    for region in regions.regions:
        poly = np.asarray(region.polygon, dtype=float)
        lo, hi = poly.min(axis=0), poly.max(axis=0)
        if len(poly) != 4 or not np.all(np.isclose(poly, lo) | np.isclose(poly, hi)):
            return None
        rects.append([lo[0], lo[1], hi[0], hi[1]])
    rects = np.array(rects)
    if not _tiles_a_rectangle(rects):
        return None
    level = regions.levels[0]
    floor, ceiling = float(level.z_floor), float(level.z_ceiling)
    walls = [
        (lo, hi)
        for lo, hi, kind in zip(boxes.lo, boxes.hi, boxes.kind, strict=True)
        if kind == "wall" and lo[2] <= floor + EDGE_TOL_M and hi[2] >= ceiling - EDGE_TOL_M
    ]
    portals: list[list[Portal]] = [[] for _ in rects]
    for i, j, axis, at, lo, hi in _shared_edges(rects):
        for s, e in _open_stretches(walls, axis, at, lo, hi):
            s, e = s - PORTAL_GROW_M, e + PORTAL_GROW_M
            a, b = ((at, s), (at, e)) if axis == 0 else ((s, at), (e, at))
            portals[i].append(Portal(j, a, b))
            portals[j].append(Portal(i, a, b))
    return RoomPlan(rects, floor, ceiling, tuple(tuple(p) for p in portals))


def _tiles_a_rectangle(rects: np.ndarray) -> bool:
    """Whether the rectangles cover their bounding rectangle without overlapping."""
    area = np.prod(rects[:, 2:] - rects[:, :2], axis=1)
    if np.any(area <= 0.0):
        return False
    box = np.prod(rects[:, 2:].max(axis=0) - rects[:, :2].min(axis=0))
    lo = np.maximum(rects[:, None, :2], rects[None, :, :2])
    hi = np.minimum(rects[:, None, 2:], rects[None, :, 2:])
    shared = np.prod(np.clip(hi - lo, 0.0, None), axis=2)
    np.fill_diagonal(shared, 0.0)
    return bool(abs(area.sum() - box) <= 1e-6 * box and shared.max() <= 1e-9 * box)


def _shared_edges(rects: np.ndarray):
    """``(i, j, axis, at, lo, hi)``: rooms i and j share ``coord[axis] == at`` over lo–hi."""
    for i in range(len(rects)):
        for j in range(i + 1, len(rects)):
            for axis in (0, 1):
                other = 1 - axis
                a, b = rects[i], rects[j]
                for at_a, at_b in ((a[axis + 2], b[axis]), (a[axis], b[axis + 2])):
                    if abs(at_a - at_b) > EDGE_TOL_M:
                        continue
                    lo = max(a[other], b[other])
                    hi = min(a[other + 2], b[other + 2])
                    if hi - lo > EDGE_TOL_M:
                        yield i, j, axis, float(at_a), float(lo), float(hi)


def _open_stretches(walls, axis: int, at: float, lo: float, hi: float) -> list[tuple[float, float]]:
    """The stretches of ``lo``–``hi`` on the line ``coord[axis] == at`` no wall covers."""
    other = 1 - axis
    covers = [
        (w_lo[other], w_hi[other])
        for w_lo, w_hi in walls
        if w_lo[axis] - EDGE_TOL_M <= at <= w_hi[axis] + EDGE_TOL_M
    ]
    return interval_gaps(lo, hi, covers, EDGE_TOL_M)


def split_by_rooms(parts: list[MeshPart], plan: RoomPlan) -> list[tuple[tuple[int, ...], MeshPart]]:
    """Each part's connected pieces grouped by the rooms they reach, as ``(rooms, part)``.

    A piece (triangles joined by shared vertices) belongs to every room whose rectangle,
    grown by :data:`ROOM_TOL_M`, meets the piece's plan extent; pieces that meet no room
    (outside the building) get ``()``. Pieces are kept whole, so each vertex keeps the
    triangles around it (and its normal).
    """
    out = []
    for part in parts:
        label = _pieces(part.faces, len(part.vertices))
        verts = np.asarray(part.vertices, dtype=float)
        n = int(label.max()) + 1 if len(label) else 0
        lo = np.full((n, 2), np.inf)
        hi = np.full((n, 2), -np.inf)
        np.minimum.at(lo, label, verts[:, :2])
        np.maximum.at(hi, label, verts[:, :2])
        meets = plan.rooms_meeting(lo, hi)[label[part.faces[:, 0]]]  # per face
        if not len(meets):
            continue
        # Faces grouped by their rooms: sorted rows, cut where a row changes. (np.unique's
        # rows go through a structured dtype, whose comparison turns a Ctrl-C into a
        # TypeError.)
        order = np.lexsort(meets.T[::-1])
        rows = meets[order]
        change = np.flatnonzero(np.any(rows[1:] != rows[:-1], axis=1)) + 1
        for faces in np.split(order, change):
            rooms = tuple(np.flatnonzero(meets[faces[0]]).tolist())
            out.append((rooms, _sub_part(part, np.sort(faces))))
    return out


def _pieces(faces: np.ndarray, n_vertices: int) -> np.ndarray:
    """A label per vertex: vertices joined through triangles share one (0, 1, …)."""
    label = np.arange(n_vertices)
    if len(faces) == 0:
        return label
    while True:
        low = label[faces].min(axis=1)
        new = label.copy()
        for c in range(3):
            np.minimum.at(new, faces[:, c], low)
        new = new[new]  # jump to the label's own label
        if np.array_equal(new, label):
            break
        label = new
    return np.unique(label, return_inverse=True)[1]


def _sub_part(part: MeshPart, faces: np.ndarray) -> MeshPart:
    """The part's triangles ``faces`` with only the vertices they use."""
    tri = part.faces[faces]
    used, inverse = np.unique(tri, return_inverse=True)
    return MeshPart(
        part.name,
        part.vertices[used],
        inverse.reshape(tri.shape).astype(np.int32),
        part.rgba,
        None if part.uv is None else part.uv[used],
        part.texture,
        part.shine,
        part.emission,
    )
