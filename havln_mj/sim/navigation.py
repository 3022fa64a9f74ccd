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
floats once, on first visit, and the per-step work is a few ``math`` calls per neighbour.
"""

from __future__ import annotations

import math

from havln_mj.scene.navgraph import NavGraph
from havln_mj.sim.state import ViewPoint

_PI = math.pi
_TWO_PI = 2.0 * math.pi

# (viewpointId, ix, x, y, z, bearing, horizontal distance, elevation angle, distance)
_Neighbour = tuple[str, int, float, float, float, float, float, float, float]


def _sort_key(v: ViewPoint) -> float:
    return math.hypot(v.rel_heading, v.rel_elevation)


class NavTable:
    """A scan's navigation graph, prepared for fast candidate queries.

    Attributes:
        scan_id: The scan's id, as the user gave it.
        graph: The scan's navigation graph.
    """

    def __init__(self, scan_id: str, graph: NavGraph) -> None:
        self.scan_id = scan_id
        self.graph = graph
        self._here: dict[str, tuple[int, float, float, float]] = {}
        self._neighbours: dict[str, list[_Neighbour]] = {}

    def location(self, vp: str) -> ViewPoint:
        """The agent's own location at ``vp`` (relative values 0).

        Raises:
            UnknownViewpointError: ``vp`` is unknown or excluded.
        """
        here = self._here.get(vp)
        if here is None:
            self._prepare(vp)
            here = self._here[vp]
        return ViewPoint(vp, *here)

    def _prepare(self, vp: str) -> None:
        g = self.graph
        neighbours = g.neighbors(vp)  # raises for unknown or excluded viewpoints
        x0, y0, z0 = (float(c) for c in g.position(vp))
        self._here[vp] = (g.index(vp), x0, y0, z0)
        table = []
        for j in neighbours:
            x, y, z = (float(c) for c in g.position(j))
            dx, dy, dz = x - x0, y - y0, z - z0
            flat = math.hypot(dx, dy)
            bearing = math.atan2(dx, dy)  # heading convention: from +y, right positive
            elev = math.atan2(dz, flat)
            table.append((j, g.index(j), x, y, z, bearing, flat, elev, math.sqrt(flat**2 + dz**2)))
        self._neighbours[vp] = table

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
        table = self._neighbours.get(vp)
        if table is None:
            self._prepare(vp)
            table = self._neighbours[vp]
        out = [ViewPoint(vp, *self._here[vp])]
        found = []
        for j, ix, x, y, z, bearing, flat, elev, dist in table:
            rel = bearing - heading
            if rel > _PI or rel <= -_PI:
                rel = math.fmod(rel + _PI, _TWO_PI)
                rel = rel - _PI if rel > 0.0 else rel + _PI
            if cos_half_hfov is not None and (flat == 0.0 or math.cos(rel) < cos_half_hfov):
                continue
            found.append(ViewPoint(j, ix, x, y, z, rel, elev - elevation, dist))
        if len(found) > 1:
            found.sort(key=_sort_key)
        out.extend(found)
        return out
