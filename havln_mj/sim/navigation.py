"""Navigable locations: which viewpoints the agent can move to, seen from its camera.

MatterSim's rules: index 0 is the current viewpoint (all relative values 0); the others are
the neighbours j with ``unobstructed[current][j]`` set and j included. With restricted
navigation a neighbour is kept only when the cosine of its horizontal bearing relative to the
heading is at least ``cos(vfov · width / height / 2)`` (elevation ignored; a neighbour
straight above or below has no bearing and is never kept). ``rel_heading`` is the signed
horizontal angle in (−π, π], right positive; ``rel_elevation = atan2(Δz, horizontal distance)
− camera elevation``; ``rel_distance`` is the 3-D distance. The list is sorted by
``sqrt(rel_heading² + rel_elevation²)``, ties in file order.

This runs on every action, so each viewpoint's neighbours are turned into plain tuples of
floats once, on first visit, sorted by bearing: a restricted query looks only at the
neighbours whose bearing lies in the field of view (found by bisection, with a margin, then
tested by the rule above), and the per-step work is a few ``math`` calls per visible
neighbour. Where the package was installed with a C compiler at hand, that query runs
compiled (``havln_mj.sim._navigable``) with the same arithmetic, float for float. A table
depends only on its graph, so simulators of one process share it (see
:mod:`havln_mj.sim.scenes`).
"""

from __future__ import annotations

import math
import weakref
from bisect import bisect_left, bisect_right

from havln_mj.scene.navgraph import NavGraph
from havln_mj.sim.state import ViewPoint, make

try:  # the window query compiled (built where a C compiler was at hand): the same answers
    from havln_mj.sim._navigable import window as _window
except ImportError:
    _window = None

_PI = math.pi
_cos, _hypot = math.cos, math.hypot
_TWO_PI = 2.0 * math.pi
_MARGIN = 1e-9  # radians: the bisection window is this much wider than the field of view

# (order in file, viewpointId, ix, x, y, z, bearing, horizontal distance, elevation angle,
#  distance)
_Neighbour = tuple[int, str, int, float, float, float, float, float, float, float]


def _rank(v: ViewPoint) -> tuple[float, int]:
    """Angle from the view centre, ties in file order (neighbours are listed in file order)."""
    return (_hypot(v.rel_heading, v.rel_elevation), v.ix)


class _Node:
    """One viewpoint's own location and its neighbours, ready for queries."""

    __slots__ = ("bearings", "here", "location", "ring", "rows", "xyz")

    def __init__(self, vp: str, here: tuple, rows: list[_Neighbour]) -> None:
        self.here = here  # (ix, x, y, z)
        self.xyz = here[1:]
        # The agent's own location here (relative values 0): the same object in every state
        # at this viewpoint, as nothing ever changes it.
        self.location = ViewPoint(vp, *here)
        self.rows = rows  # file order
        # Neighbours with a bearing, sorted by it and repeated one turn later, so that any
        # window [h − w, h + w] with h in [0, 2π) and w < π is one slice.
        ahead = sorted((r for r in rows if r[7] != 0.0), key=lambda r: r[6])
        self.bearings = [r[6] for r in ahead] + [r[6] + _TWO_PI for r in ahead]
        self.ring = ahead + ahead


class NavTable:
    """A scan's navigation graph, prepared for fast candidate queries.

    Attributes:
        scan_id: The scan's id, as the user gave it.
        graph: The scan's navigation graph.
    """

    def __init__(self, scan_id: str, graph: NavGraph) -> None:
        self.scan_id = scan_id
        self.graph = graph
        self._nodes: dict[str, _Node] = {}
        self._window = (2.0, 0.0)  # (cos_half_hfov, half-width of its bisection window)

    def location(self, vp: str) -> ViewPoint:
        """The agent's own location at ``vp`` (relative values 0).

        Raises:
            UnknownViewpointError: ``vp`` is unknown or excluded.
        """
        node = self._nodes.get(vp) or self._prepare(vp)
        return node.location

    def position(self, vp: str) -> tuple[float, float, float]:
        """The camera position of ``vp`` as plain floats.

        Raises:
            UnknownViewpointError: ``vp`` is unknown or excluded.
        """
        node = self._nodes.get(vp) or self._prepare(vp)
        return node.xyz

    def _prepare(self, vp: str) -> _Node:
        g = self.graph
        neighbours = g.neighbors(vp)  # raises for unknown or excluded viewpoints
        x0, y0, z0 = (float(c) for c in g.position(vp))
        rows = []
        for order, j in enumerate(neighbours):
            x, y, z = (float(c) for c in g.position(j))
            dx, dy, dz = x - x0, y - y0, z - z0
            flat = math.hypot(dx, dy)
            bearing = math.atan2(dx, dy)  # heading convention: from +y, right positive
            elev = math.atan2(dz, flat)
            dist = math.sqrt(flat**2 + dz**2)
            rows.append((order, j, g.index(j), x, y, z, bearing, flat, elev, dist))
        node = self._nodes[vp] = _Node(vp, (g.index(vp), x0, y0, z0), rows)
        return node

    def _half_width(self, cos_half_hfov: float) -> float:
        """Half-width of the bearing window holding every neighbour the rule keeps."""
        # cos(rel) ≥ c  ⇔  |rel| ≤ acos(c) for rel in (−π, π]; the margin covers rounding.
        w = math.acos(max(-1.0, min(1.0, cos_half_hfov))) + _MARGIN
        self._window = (cos_half_hfov, w)
        return w

    def candidates(
        self, vp: str, heading: float, elevation: float, cos_half_hfov: float | None
    ) -> list[ViewPoint]:
        """The navigable locations at ``vp`` for a camera at ``heading``/``elevation``.

        Args:
            vp: The current viewpoint.
            heading: Camera heading (radians).
            elevation: Camera elevation (radians).
            cos_half_hfov: Restricted navigation's threshold, or None for all neighbours.

        Raises:
            UnknownViewpointError: ``vp`` is unknown or excluded.
        """
        node = self._nodes.get(vp) or self._prepare(vp)
        if cos_half_hfov is None or not 0.0 <= heading < _TWO_PI:
            return self.direct(vp, heading, elevation, cos_half_hfov)
        c, w = self._window
        if c != cos_half_hfov:
            c, w = cos_half_hfov, self._half_width(cos_half_hfov)
        if w >= _PI:
            return self.direct(vp, heading, elevation, cos_half_hfov)
        # Restricted, the usual case: the bisected window holds only neighbours with a
        # bearing (never one straight above or below), most often none or one.
        if _window is not None:
            return _window(
                node.bearings, node.ring, node.location, heading, elevation, c, w, ViewPoint
            )
        b = node.bearings
        lo, hi = bisect_left(b, heading - w), bisect_right(b, heading + w)
        if lo == hi:
            return [node.location]
        out = [node.location]
        for _order, j, ix, x, y, z, bearing, _flat, elev, dist in node.ring[lo:hi]:
            rel = bearing - heading
            if rel > _PI or rel <= -_PI:
                rel = math.fmod(rel + _PI, _TWO_PI)
                rel = rel - _PI if rel > 0.0 else rel + _PI
            if _cos(rel) >= c:
                out.append(make(ViewPoint, (j, ix, x, y, z, rel, elev - elevation, dist)))
        if len(out) > 2:
            out[1:] = sorted(out[1:], key=_rank)
        return out

    def direct(
        self, vp: str, heading: float, elevation: float, cos_half_hfov: float | None
    ) -> list[ViewPoint]:
        """:meth:`candidates` by MatterSim's rule applied to every neighbour in turn."""
        node = self._nodes.get(vp) or self._prepare(vp)
        found = []
        for order, j, ix, x, y, z, bearing, flat, elev, dist in node.rows:
            rel = bearing - heading
            if rel > _PI or rel <= -_PI:
                rel = math.fmod(rel + _PI, _TWO_PI)
                rel = rel - _PI if rel > 0.0 else rel + _PI
            if cos_half_hfov is not None and (flat == 0.0 or math.cos(rel) < cos_half_hfov):
                continue
            rel_e = elev - elevation
            vp_j = ViewPoint(j, ix, x, y, z, rel, rel_e, dist)
            found.append((math.hypot(rel, rel_e), order, vp_j))
        found.sort()  # by angle from the view centre, ties in file order
        return [node.location] + [f[2] for f in found]


def camera_positions(graph: NavGraph) -> dict[str, tuple[float, float, float]]:
    """Viewpoint camera positions of ``graph`` as plain floats, filled as they are asked for.

    One dictionary per graph object in the process (freed with the graph): bodies on the same
    scan share it.
    """
    positions = _POSITIONS.get(graph)
    if positions is None:
        positions = _POSITIONS[graph] = _Positions(graph)
    return positions


class _Positions(dict):
    """Viewpoint id to ``(x, y, z)``, computed on first access."""

    def __init__(self, graph: NavGraph) -> None:
        super().__init__()
        self._graph = weakref.ref(graph)

    def __missing__(self, vp: str) -> tuple[float, float, float]:
        xyz = self[vp] = tuple(float(c) for c in self._graph().position(vp))
        return xyz


_POSITIONS: weakref.WeakKeyDictionary[NavGraph, _Positions] = weakref.WeakKeyDictionary()
