"""Egocentric routes: where FORWARD goes, and the cheapest FORWARD / turn sequences to a goal.

The simulator's FORWARD takes the neighbour nearest the view centre within half the camera's
horizontal field of view (:func:`forward_target`), so it cannot reach every neighbour and the
egocentric route can differ from the graph's shortest path. :func:`ego_plan` searches
(viewpoint, heading) states forward from one start; :class:`EgoRoutes` holds backward
cost-to-go tables for teachers that label many states. Routes are shortest in metres, then in
turns (each turn costs :data:`TURN_COST`).
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Iterable

from havln_mj.frames import wrap_angle
from havln_mj.scene.navgraph import NavGraph
from havln_mj.sim.egocentric import EgoAction
from havln_mj.tasks.planning import TURN


def forward_target(
    graph: NavGraph, here: str, heading: float, elevation: float, half_hfov: float
) -> str | None:
    """Where FORWARD goes from ``here`` at ``heading``/``elevation``, or None (it waits).

    The simulator's rule: of the neighbours within ``half_hfov`` of the heading, the one
    nearest the view centre (``hypot(rel_heading, rel_elevation)``, ties in file order).
    """
    x0, y0, z0 = graph.position(here)
    best, best_key = None, math.inf
    for vp in graph.neighbors(here):
        x, y, z = graph.position(vp)
        flat = math.hypot(x - x0, y - y0)
        if flat == 0.0:
            continue  # straight above or below: no bearing, never navigable
        rel = wrap_angle(math.atan2(x - x0, y - y0) - heading)
        if abs(rel) > half_hfov:
            continue
        key = math.hypot(rel, math.atan2(z - z0, flat) - elevation)
        if key < best_key:
            best, best_key = vp, key
    return best


TURN_COST = 1e-3  # metres an egocentric turn "costs": fewest turns among shortest routes


def ego_plan(
    graph: NavGraph,
    start: str,
    heading: float,
    goal: str,
    half_hfov: float,
    blocked: Iterable[str] = (),
) -> list[EgoAction] | None:
    """The shortest egocentric action sequence from ``start`` at ``heading`` to ``goal``.

    Searches (viewpoint, heading) states, headings 30° apart from ``heading``, with the
    simulator's FORWARD rule (:func:`forward_target`, camera level): the route is shortest in
    metres, then in turns. FORWARD cannot reach every neighbour (another one may always be
    nearer the view centre), so this can differ from the graph's shortest path. FORWARD never
    enters a ``blocked`` viewpoint (``start`` and ``goal`` are never blocked).

    Returns:
        The actions, ending with STOP; None when FORWARD and turns cannot reach ``goal``.
    """
    blocked = set(blocked) - {start, goal}
    n = round(2 * math.pi / TURN)
    order = {v: i for i, v in enumerate(graph.nodes)}
    begin = (start, 0)
    best = {begin: 0.0}
    prev: dict[tuple[str, int], tuple[tuple[str, int], EgoAction]] = {}
    heap = [(0.0, order[start], 0, begin)]
    while heap:
        d, _, _, node = heapq.heappop(heap)
        vp, k = node
        if vp == goal:
            actions = [EgoAction.STOP]
            while node != begin:
                node, action = prev[node]
                actions.append(action)
            return actions[::-1]
        if d > best[node]:
            continue
        moves = [((vp, (k + 1) % n), EgoAction.TURN_RIGHT, TURN_COST)]
        moves.append(((vp, (k - 1) % n), EgoAction.TURN_LEFT, TURN_COST))
        ahead = forward_target(graph, vp, heading + k * TURN, 0.0, half_hfov)
        if ahead is not None and ahead not in blocked:
            length = math.dist(graph.position(vp), graph.position(ahead))
            moves.append(((ahead, k), EgoAction.FORWARD, length))
        for nxt, action, cost in moves:
            nd = d + cost
            if nd < best.get(nxt, math.inf):
                best[nxt], prev[nxt] = nd, (node, action)
                heapq.heappush(heap, (nd, order[nxt[0]], nxt[1], nxt))
    return None


class EgoRoutes:
    """Egocentric cost-to-go on one graph for any goal and avoided viewpoints (cached).

    The costs of :func:`ego_plan` (metres, plus :data:`TURN_COST` per turn) over the states
    (viewpoint, heading on the 30° lattice), found by one backward search per (goal, avoided
    set) instead of a forward search per state: a teacher that labels every state a learner
    reaches asks for the same few tables again and again.

    Args:
        graph: The navigation graph.
        half_hfov: FORWARD's half field of view.
        cache_size: Tables kept (least recently used dropped).
    """

    def __init__(self, graph: NavGraph, half_hfov: float, cache_size: int = 256) -> None:
        self.graph, self.half_hfov, self.cache_size = graph, half_hfov, cache_size
        self._n = round(2 * math.pi / TURN)
        self._ahead: dict[tuple[str, int], tuple[str, float]] = {}
        self._into: dict[tuple[str, int], list[tuple[str, float]]] = {}
        for vp in graph.nodes:
            for k in range(self._n):
                target = forward_target(graph, vp, k * TURN, 0.0, half_hfov)
                if target is not None:
                    length = math.dist(graph.position(vp), graph.position(target))
                    self._ahead[(vp, k)] = (target, length)
                    self._into.setdefault((target, k), []).append((vp, length))
        self._tables: dict[tuple[str, frozenset[str]], dict[tuple[str, int], float]] = {}

    def heading_step(self, heading: float) -> int | None:
        """The lattice step of ``heading``, or None when it is off the 30° lattice."""
        k = round(heading / TURN)
        return k % self._n if abs(heading - k * TURN) < 1e-6 else None

    def cost_to_go(self, goal: str, avoid: frozenset[str]) -> dict[tuple[str, int], float]:
        """Cost from every state to ``goal`` without FORWARD into ``avoid`` (absent: none)."""
        key = (goal, avoid)
        table = self._tables.pop(key, None)
        if table is None:
            table = {}
            heap = [(0.0, goal, k) for k in range(self._n)]
            while heap:
                d, vp, k = heapq.heappop(heap)
                if (vp, k) in table:
                    continue
                table[(vp, k)] = d
                prev = [(vp, (k - 1) % self._n, TURN_COST), (vp, (k + 1) % self._n, TURN_COST)]
                if vp not in avoid or vp == goal:
                    prev += [(u, k, length) for u, length in self._into.get((vp, k), ())]
                for u, j, cost in prev:
                    if (u, j) not in table:
                        heapq.heappush(heap, (d + cost, u, j))
            if len(self._tables) >= self.cache_size:
                self._tables.pop(next(iter(self._tables)))
        self._tables[key] = table
        return table

    def first_action(
        self, here: str, step: int, goal: str, avoid: frozenset[str]
    ) -> EgoAction | None:
        """The first action of a cheapest route (FORWARD, then right, then left on ties).

        Returns:
            STOP at the goal; None when no route avoids ``avoid``.
        """
        if here == goal:
            return EgoAction.STOP
        table = self.cost_to_go(goal, avoid - {here})
        best, action = math.inf, None
        ahead = self._ahead.get((here, step))
        if ahead is not None and (ahead[0] not in avoid or ahead[0] == goal):
            best, action = ahead[1] + table.get((ahead[0], step), math.inf), EgoAction.FORWARD
        for turn, j in ((EgoAction.TURN_RIGHT, step + 1), (EgoAction.TURN_LEFT, step - 1)):
            cost = TURN_COST + table.get((here, j % self._n), math.inf)
            if cost < best - 1e-9:
                best, action = cost, turn
        return action if math.isfinite(best) else None
