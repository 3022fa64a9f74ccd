"""Flights of its own for an edge that neither its straight corridor nor the graph serves.

An edge up a turning stair climbs too steeply to walk straight, and where the graph has no
other way between its viewpoints (a lone line of sight between two storeys) the proxy draws
one: a *flight* from one viewpoint's floor to the other's, long enough to climb at
``stair_grade`` at most, as a dogleg (out to a turning point, then on to the far end) or a
U-turn (out, across, and back). An edge blocked where its corridor crosses another's gets a
dogleg around the crossing the same way.

Candidate flights are tried shortest first, in 16 directions, each drawn with the building
around it in a window (only the elements near it, so a try costs tens of milliseconds, not a
whole redraw). A flight is taken when a body walks it and every path that walked before still
walks: straight edges and routes near it. Where none fits because another walk passes too
close (a landing's edge right over a viewpoint on the stair below it, or a flight taken
earlier), that walk is moved out of the way: it gets a flight too, drawn after the edge's.
The whole proxy is then redrawn with the flights taken and checked again; a flight near a
path that broke there is dropped.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from havln_mj.scene.boxes import BoxSet
from havln_mj.scene.proxy.layers import Disc, Edge, Leg
from havln_mj.scene.proxy.params import ProxyParams
from havln_mj.scene.proxy.raster import Grid
from havln_mj.scene.proxy.walk import path_fault, samples

Draw = Callable[[list[Disc], list[Leg], Grid], BoxSet]

_DIRECTIONS = 16
_LENGTHS = (1.05, 1.25, 1.6, 2.2)  # lengths tried, times the shortest that climbs gently
_MIN_ARM = 0.3  # metres: shortest arm of a U-turn
_MARGIN = 1.5  # metres: paths this near a flight are checked; building this near is drawn
_MOVES = 4  # walks nearest an edge no flight fits that are tried out of its way


def candidate_flights(a: np.ndarray, b: np.ndarray, p: ProxyParams) -> list[np.ndarray]:
    """Polylines of floor points from ``a`` to ``b`` a body could climb, shortest first.

    Each is a dogleg ``a → m → b`` or a U-turn ``a → a + L·u → b + L·u → b`` (also one that
    first steps aside, so its flights are a corridor apart) for 16 directions ``u``, at
    horizontal lengths ``_LENGTHS`` times the shortest that climbs at ``stair_grade``, and
    never shorter than the edge itself, each shape once. Floors rise evenly with
    horizontal distance along the polyline.
    """
    v = b[:2] - a[:2]
    d = float(np.hypot(*v))
    rise = float(b[2] - a[2])
    base = max(d, abs(rise) / p.stair_grade)
    out: list[np.ndarray] = []
    for factor in _LENGTHS:
        need = base * factor
        for k in range(_DIRECTIONS):
            angle = 2 * np.pi * k / _DIRECTIONS
            u = np.array([np.cos(angle), np.sin(angle)])
            arm = _dogleg_arm(a[:2], b[:2], u, need)
            if arm is not None:
                out.append(np.array([a[:2], a[:2] + arm * u, b[:2]]))
            out += _u_turns(a[:2], b[:2], u, need, p)
    # Short U-turns keep their shortest arm at several lengths: each shape is tried once.
    shapes: dict[bytes, np.ndarray] = {}
    for xy in out:
        shapes.setdefault(np.round(xy, 3).tobytes(), xy)
    out = list(shapes.values())
    runs = [np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))]) for xy in out]
    order = sorted(range(len(out)), key=lambda k: runs[k][-1])  # stable: ties keep their turn
    return [np.column_stack([out[k], a[2] + rise * runs[k] / runs[k][-1]]) for k in order]


def _u_turns(
    a: np.ndarray, b: np.ndarray, u: np.ndarray, need: float, p: ProxyParams
) -> list[np.ndarray]:
    """U-turns from ``a`` to ``b`` whose flights run along ``u``, about ``need`` long.

    One turns straight back to ``b``; the other first steps aside from ``b`` (across ``u``)
    until its flights are a corridor's width apart, so that neither runs under the other.
    """
    n = np.array([-u[1], u[0]])
    if (b - a) @ n > 0:
        n = -n  # step aside away from b
    apart = 2 * p.corridor_half_width - abs(float((b - a) @ n))
    out = []
    for side in (0.0, apart) if apart > 0 else (0.0,):
        start = a + side * n
        arm = max(_MIN_ARM, (need - side - float(np.hypot(*(b - start)))) / 2)
        corners = [a, start] if side else [a]
        out.append(np.array([*corners, start + arm * u, b + arm * u, b]))
    return out


def _dogleg_arm(a: np.ndarray, b: np.ndarray, u: np.ndarray, need: float) -> float | None:
    """The arm ``l`` with ``l + |a + l·u − b| = need`` (None when too short to turn)."""
    w = b - a
    # l + sqrt(|w|² − 2 l u·w + l²) = need  ⇒  l = (need² − |w|²) / (2 (need − u·w))
    den = 2.0 * (need - float(u @ w))
    if den <= 1e-9:
        return None
    arm = (need**2 - float(w @ w)) / den
    return arm if arm >= _MIN_ARM else None


def flight_legs(flight: np.ndarray, comp: int) -> list[Leg]:
    """The corridors that draw ``flight``."""
    return [
        Leg(flight[k, :2], flight[k + 1, :2], float(flight[k, 2]), float(flight[k + 1, 2]), comp)
        for k in range(len(flight) - 1)
    ]


def choose_flight(
    a: np.ndarray,
    b: np.ndarray,
    comp: int,
    discs: list[Disc],
    legs: list[Leg],
    paths: list[np.ndarray],
    grid: Grid,
    draw: Draw,
    p: ProxyParams,
) -> np.ndarray | None:
    """The first of ``candidate_flights(a, b)`` that a body walks, breaking none of ``paths``.

    The ``paths`` (each walked in the whole drawing without the flight) that come within
    ``_MARGIN`` of a candidate must still be walked with it. The candidate is drawn by
    ``draw`` on ``grid``'s lattice with the ``discs`` and ``legs`` within ``_MARGIN`` of it
    and of those paths: all that shapes the floor along them.

    Returns:
        The flight, or None when every candidate fails.
    """
    spans = np.array([plan_span(q) for q in paths]).reshape(-1, 4)
    r = np.array([p.viewpoint_radius] * 2 + [-p.viewpoint_radius] * 2)
    disc_spans = np.array([[*d.xy, *d.xy] for d in discs]).reshape(-1, 4) - r
    w = np.array([p.corridor_half_width] * 2 + [-p.corridor_half_width] * 2)
    leg_spans = np.array([plan_span(np.array([g.a, g.b])) for g in legs]).reshape(-1, 4) - w
    for flight in candidate_flights(a, b, p):
        lo, hi = flight[:, :2].min(axis=0) - _MARGIN, flight[:, :2].max(axis=0) + _MARGIN
        near = np.flatnonzero(spans_meet(spans, lo, hi))
        if len(near):
            lo = np.minimum(lo, spans[near, :2].min(axis=0) - _MARGIN)
            hi = np.maximum(hi, spans[near, 2:].max(axis=0) + _MARGIN)
        window = Grid.around(np.array([lo, hi]), 0.0, grid.cell)
        near_discs = [discs[k] for k in np.flatnonzero(spans_meet(disc_spans, lo, hi))]
        near_legs = [legs[k] for k in np.flatnonzero(spans_meet(leg_spans, lo, hi))]
        boxes = draw(near_discs, near_legs + flight_legs(flight, comp), window)
        if path_fault(flight, boxes, p) is None and all(
            path_fault(paths[k], boxes, p) is None for k in near
        ):
            return flight
    return None


def plan_flights(
    wanted: dict[Edge, Leg],
    discs: list[Disc],
    legs: dict[Edge, Leg],
    paths: dict[Edge, np.ndarray],
    grid: Grid,
    draw: Draw,
    p: ProxyParams,
) -> tuple[dict[Edge, np.ndarray], set[Edge]]:
    """Flights for the ``wanted`` edges, where they fit, taken in turn.

    Each edge gets the first candidate :func:`choose_flight` takes. Then each edge none fit
    tries moving each of the ``_MOVES`` walks most in its way (see ``_in_the_way``) out
    of it, in turn: a straight edge (its corridor is no longer drawn) or a flight. The move
    is made when, without that walk, a flight fits the edge, and then, with the edge's
    flight, one fits the walk too.

    Args:
        wanted: The edges to fly, each as the leg between its ends' floors.
        discs: The viewpoints' discs.
        legs: The drawn straight edges' corridors.
        paths: Every path that walks (straight edges, routes), by the edge it serves.
        grid: The plan grid the proxy is drawn on.
        draw: Draws discs and legs on a window of ``grid``'s lattice (see :func:`choose_flight`).
        p: The body and the limits.

    Returns:
        The flights by edge, and the straight edges (keys of ``legs``) whose corridors they
        replace.
    """
    comp = {e: g.comp for e, g in (legs | wanted).items()}
    ends = {e: (np.array([*g.a, g.fa]), np.array([*g.b, g.fb])) for e, g in (legs | wanted).items()}
    flights: dict[Edge, np.ndarray] = {}
    moved: set[Edge] = set()

    def fit(edge: Edge, gone: set[Edge]) -> np.ndarray | None:
        gone = gone | moved
        drawn = [g for e, g in legs.items() if e not in gone]
        drawn += [g for e, f in flights.items() if e not in gone for g in flight_legs(f, comp[e])]
        walks = [q for e, q in (paths | flights).items() if e not in gone]
        return choose_flight(*ends[edge], comp[edge], discs, drawn, walks, grid, draw, p)

    for edge in wanted:
        flight = fit(edge, set())
        if flight is not None:
            flights[edge] = flight
    for edge in (e for e in wanted if e not in flights):
        for other in _in_the_way(ends[edge], legs, flights, paths, p):
            flight = fit(edge, {other})
            if flight is None:
                continue
            flights[edge] = flight
            detour = fit(other, {other})
            if detour is not None:
                flights[other] = detour
                moved |= {other} & legs.keys()
                break
            del flights[edge]
    return flights, moved


def _in_the_way(
    ends: tuple[np.ndarray, np.ndarray],
    legs: dict[Edge, Leg],
    flights: dict[Edge, np.ndarray],
    paths: dict[Edge, np.ndarray],
    p: ProxyParams,
) -> list[Edge]:
    """The ``_MOVES`` walks (straight edges walked, flights) most in the way of ``ends``.

    A walk reaches an end when its corridor meets the end's disc. It is in the way where it
    passes too far above or below the end's floor to walk on from it (a ``step`` more than
    ``max_grade`` allows over the distance) but too close to stack (``headroom``): those
    come first, nearest first, then the walks that only reach an end.
    """
    reach = p.viewpoint_radius + p.corridor_half_width
    walks = {e: paths[e] for e in legs if e in paths} | flights
    spans = np.array([plan_span(q) for q in walks.values()]).reshape(-1, 4)
    ends_xy = np.array([end[:2] for end in ends])
    near = spans_meet(spans, ends_xy.min(axis=0) - reach, ends_xy.max(axis=0) + reach)
    order: dict[Edge, tuple[float, float]] = {}
    for e, q in (item for item, meets in zip(walks.items(), near, strict=True) if meets):
        pts, _ = samples(q, p.cell)
        gap = np.array([np.hypot(*(pts[:, :2] - end[:2]).T) for end in ends])  # (2, n)
        dz = np.abs(pts[:, 2] - np.array([[end[2]] for end in ends]))
        other = (dz > p.max_grade * gap + p.step) & (dz < p.headroom)
        if gap.min() < reach:
            order[e] = (np.where(other, gap, np.inf).min(), gap.min())
    return sorted(order, key=order.get)[:_MOVES]


def plan_span(points: np.ndarray) -> np.ndarray:
    """``[x_min, y_min, x_max, y_max]`` of a polyline's points in plan."""
    return np.concatenate([points[:, :2].min(axis=0), points[:, :2].max(axis=0)])


def spans_meet(spans: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Whether each plan span (rows of :func:`plan_span`) meets the box ``lo..hi``."""
    return np.all(spans[:, :2] <= hi, axis=1) & np.all(spans[:, 2:] >= lo, axis=1)
