"""The HA-VLN collision signal: how close an action's track brings the agent to people.

The agent is within ``distance`` (default 1 m) of a person, measured horizontally from the
agent's base to the person's pelvis, at any time during an action. A body reports its base's
track over the action as knots (piecewise linear: a point body's straight move then its turn
in place, a robot's trunk at every controller tick); the track is sampled at
:data:`SAMPLE_HZ` or faster, every knot included, so a person passing through the agent's path
mid-action is caught. Only people whose whole pelvis track
(:meth:`~havln_mj.sim.crowd.Crowd.footprint`) comes within
:data:`~havln_mj.sim.crowd.NEAR_M` of the track are sampled; the smallest distance reported is
exact below ``NEAR_M`` and ``inf`` above.

The signal runs on every action, so it is computed as a lookup: a crowd that offers
``pelvis_table()`` (the humans package's does, see :mod:`havln_mj.humans.tracks`) has its
people's pelvis tracks tabulated once and read at all of an action's samples, for all people
and all of a batch's tracks among them, in one vectorised pass; who is near a straight track
is remembered (:class:`NearMemo`). Where the package was installed with a C compiler at hand,
the table is read by a compiled loop (``havln_mj.sim._closest``) with the same arithmetic;
otherwise by numpy. Other crowds are asked for :meth:`~havln_mj.sim.crowd.Crowd.positions`.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Sequence

import numpy as np

from havln_mj.humans.tracks import UNROLLED_S
from havln_mj.sim.crowd import (
    COLLISION_DISTANCE,
    NEAR_M,
    NO_PROXIMITY,
    Crowd,
    Proximity,
    proximity_of,
)

SAMPLE_HZ = 16.0
"""The lowest rate, per simulated second, at which an action's track is checked for people."""

try:  # numpy's compiled interpolation, without np.interp's argument handling
    from numpy._core.multiarray import interp_complex as _interp_complex
except ImportError:  # numpy < 2
    _interp_complex = np.interp

try:  # the table read compiled (built where a C compiler was at hand): the same numbers
    from havln_mj.sim._closest import closest as _closest
except ImportError:
    _closest = None

_STEPS = np.arange(4096, dtype=float)  # sample indices, for sample times


def _linspace(t0: float, t1: float, n: int, extra: Sequence[float] = ()) -> np.ndarray:
    """``numpy.linspace(t0, t1, n)`` (the same values) then ``extra``, in one array.

    Without linspace's argument handling and a concatenation: this runs on every action.
    """
    if n > len(_STEPS):
        return np.concatenate([np.linspace(t0, t1, n), extra])
    times = np.empty(n + len(extra))
    np.multiply(_STEPS[:n], (t1 - t0) / (n - 1), out=times[:n])
    times[:n] += t0
    times[n - 1] = t1
    if extra:
        times[n:] = extra
    return times


def sample_knots(knots: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Times and positions along a track given by its knots, at :data:`SAMPLE_HZ` or faster.

    Args:
        knots: ``(n, 4)`` rows ``(t, x, y, z)`` with non-decreasing ``t``; the track is linear
            between rows.

    Returns:
        ``(times (m,), positions (m, 3))``: every knot, plus evenly spaced samples between
        the first and the last time at least :data:`SAMPLE_HZ` per second.
    """
    t = knots[:, 0]
    if len(knots) == 1 or t[-1] <= t[0]:
        return t[-1:], knots[-1:, 1:]
    n = max(2, math.ceil((t[-1] - t[0]) * SAMPLE_HZ) + 1)
    times = np.union1d(t, _linspace(float(t[0]), float(t[-1]), n))
    positions = np.column_stack([np.interp(times, t, knots[:, i]) for i in (1, 2, 3)])
    return times, positions


def _near(crowd: Crowd, path: np.ndarray, reach: float) -> list[int]:
    """Indices of people whose pelvis track comes within ``reach`` of the polyline ``path``."""
    return _near_rows(crowd, [(0.0, float(p[0]), float(p[1])) for p in path], reach)


def _near_rows(crowd: Crowd, rows: Sequence[Sequence[float]], reach: float) -> list[int]:
    """As :func:`_near`, for the polyline through knots ``(t, x, y, ...)``."""
    centres, radii = crowd.footprint()
    ax, ay = rows[0][1], rows[0][2]
    legs = []
    for row in rows[1:]:
        bx, by = row[1], row[2]
        if bx != ax or by != ay:
            legs.append((ax, ay, bx - ax, by - ay))
            ax, ay = bx, by
    if not legs:
        legs.append((ax, ay, 0.0, 0.0))
    if len(radii) > _VECTOR_NEAR:
        return _near_vector(centres, radii, legs, reach)
    out = []
    # Plain floats: a handful of people is faster this way than through numpy.
    for k, ((cx, cy), r) in enumerate(zip(centres.tolist(), radii.tolist(), strict=True)):
        for ax, ay, dx, dy in legs:
            length2 = dx * dx + dy * dy
            t = ((cx - ax) * dx + (cy - ay) * dy) / length2 if length2 > 0 else 0.0
            t = min(max(t, 0.0), 1.0)
            if math.hypot(cx - ax - t * dx, cy - ay - t * dy) - r <= reach:
                out.append(k)
                break
    return out


_VECTOR_NEAR = 8  # more people than this are pruned with numpy


def _near_vector(centres: np.ndarray, radii: np.ndarray, legs: list, reach: float) -> list[int]:
    legs_a = np.asarray(legs, float)  # (L, 4): ax, ay, dx, dy
    rel = centres[:, None, :] - legs_a[None, :, :2]  # (P, L, 2)
    d = legs_a[:, 2:]
    length2 = (d * d).sum(axis=1)
    t = np.clip((rel * d).sum(axis=2) / np.where(length2 > 0, length2, 1.0), 0.0, 1.0)
    gap = np.hypot(*(rel - t[..., None] * d).transpose(2, 0, 1)).min(axis=1) - radii
    return np.flatnonzero(gap <= reach).tolist()


def knots_proximity(
    crowd: Crowd,
    knots: np.ndarray | Sequence[Sequence[float]],
    distance: float = COLLISION_DISTANCE,
    memo: NearMemo | None = None,
) -> Proximity:
    """The collision signal of a body's track, people far from it left out.

    Args:
        crowd: The people.
        knots: The track of the body's base: rows ``(t, x, y, z)``, linear between rows (one
            row: an instant, e.g. an episode's start state).
        distance: Collision threshold (metres, horizontal).
        memo: Remembers who is near which track.
    """
    reach = NEAR_M if distance <= NEAR_M else distance
    rows = knots if type(knots) is tuple or type(knots) is list else _rows(knots)
    near = memo.near(crowd, rows, reach) if memo else _near_rows(crowd, rows, reach)
    if not near:
        return NO_PROXIMITY
    table = getattr(crowd, "pelvis_table", None)
    if table is None:
        times, positions = sample_knots(np.asarray(rows, float).reshape(-1, 4))
        return track_proximity(crowd, times, positions, distance, near)
    if rows[-1][0] <= UNROLLED_S:
        if _closest is not None:
            return _compiled(table(), rows, near, distance)
        if len(near) == 1:
            return _one_person(table(), rows, near[0], distance)
    out = [NO_PROXIMITY]
    _tabulated(table(), [(0, rows, near)], distance, out)
    return out[0]


def _compiled(table, rows: Sequence[Sequence[float]], people: list[int], distance: float):
    """The signal of one track near ``people``, read from the unrolled tracks in compiled code.

    Only for tracks within :data:`UNROLLED_S`, where the package's C extension is built.
    """
    smallest, hit = _closest(
        rows, people, table.unrolled_frames, table.unrolled_axis, table.unrolled, distance
    )
    return proximity_of(hit, smallest)


def _one_person(table, rows: Sequence[Sequence[float]], k: int, distance: float) -> Proximity:
    """The signal of one track near one person, read from the table's unrolled tracks.

    :func:`_tabulated` for this one case (the usual one) with the same arithmetic, value for
    value, in fewer array operations.
    """
    times, agent = _samples(rows)
    fps, at, _ = table.unrolled_frames[k]
    times *= fps  # frames on the unrolled axis (the times are not needed after this)
    times += at
    gap = _interp_complex(times, table.unrolled_axis, table.unrolled)
    gap -= agent
    smallest = min(np.abs(gap, out=times).tolist())
    return proximity_of((k,) if smallest <= distance else (), smallest)


class NearMemo:
    """Remembers who is near each straight track met before, per crowd.

    A point body walks the graph's edges, so the same few hundred straight tracks come back
    all the time; which people come within reach of one depends only on its two ends and the
    people's footprints. Long tracks (a robot's) are not remembered.
    """

    LIMIT = 1 << 16  # tracks remembered per crowd

    def __init__(self) -> None:
        self._seen: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
        # The last crowd asked about and its tracks: consecutive actions share a crowd.
        self._last: tuple[Crowd | None, dict] = (None, {})

    def near(self, crowd: Crowd, rows: Sequence[Sequence[float]], reach: float) -> list[int]:
        """:func:`_near_rows`, remembered for straight tracks of up to three knots."""
        n = len(rows)
        a, b = rows[0], rows[-1]
        if n > 3 or (n == 3 and (rows[1][1] != b[1] or rows[1][2] != b[2])):
            return _near_rows(crowd, rows, reach)
        last, seen = self._last
        if last is not crowd:
            seen = self._seen.get(crowd)
            if seen is None:
                seen = self._seen[crowd] = {}
            self._last = (crowd, seen)
        key = (reach, a[1], a[2], b[1], b[2])
        near = seen.get(key)
        if near is None:
            near = _near_rows(crowd, rows, reach)
            if len(seen) < self.LIMIT:
                seen[key] = near
        return near


def batch_proximity(
    tracks: Sequence[tuple[Crowd, np.ndarray | Sequence[Sequence[float]]]],
    distance: float = COLLISION_DISTANCE,
    memo: NearMemo | None = None,
) -> list[Proximity]:
    """The collision signal of several tracks (a batch's actions) at once.

    Each ``(crowd, knots)`` is answered as :func:`knots_proximity` answers it. Tracks among
    the same people whose crowd offers a tabulated pelvis track (``pelvis_table()``, see
    :mod:`havln_mj.humans.tracks`) are sampled together in one vectorised pass; other crowds
    are asked for positions track by track. ``memo`` remembers who is near which track.
    """
    if len(tracks) == 1:  # a batch of one: no grouping
        return [knots_proximity(*tracks[0], distance, memo)]
    reach = NEAR_M if distance <= NEAR_M else distance
    out = [NO_PROXIMITY] * len(tracks)
    groups: dict[int, tuple[Crowd, list]] = {}
    for slot, (crowd, knots) in enumerate(tracks):
        if not len(crowd):
            continue
        rows = knots if isinstance(knots, tuple | list) else _rows(knots)
        near = memo.near(crowd, rows, reach) if memo else _near_rows(crowd, rows, reach)
        if near:
            groups.setdefault(id(crowd), (crowd, []))[1].append((slot, rows, near))
    for crowd, items in groups.values():
        table = getattr(crowd, "pelvis_table", None)
        if table is None:
            for slot, rows, near in items:
                times, positions = sample_knots(np.asarray(rows, float).reshape(-1, 4))
                out[slot] = track_proximity(crowd, times, positions, distance, near)
        else:
            _tabulated(table(), items, distance, out)
    return out


def _rows(knots: np.ndarray) -> list[list[float]]:
    """Knots given as an array, as rows of floats."""
    return np.asarray(knots, float).reshape(-1, 4).tolist()


def _samples(rows: Sequence[Sequence[float]]) -> tuple[np.ndarray, np.ndarray | complex]:
    """Sample times of a track (as :func:`sample_knots`, unordered) and its ``x + iy`` then.

    The times are :func:`sample_knots`'s evenly spaced ones (``numpy.linspace``'s values),
    then the inner knots. A track standing still (a turn in place) gives its one ``x + iy``.
    """
    first, last = rows[0], rows[-1]
    t0, t1 = first[0], last[0]
    knots = len(rows)
    if knots == 1 or t1 <= t0:
        return np.array([t1]), np.array([complex(last[1], last[2])])
    n = max(2, math.ceil((t1 - t0) * SAMPLE_HZ) + 1)
    inner = knots - 2
    if n + inner > len(_STEPS):
        return _long_samples(rows, n)
    times = _STEPS[: n + inner] * ((t1 - t0) / (n - 1))
    times += t0
    times[n - 1] = t1
    a, b = complex(first[1], first[2]), complex(last[1], last[2])
    # Inner knots are samples too. A point body's two or three knots are spelt out (hot).
    if inner == 0:
        if a == b:
            return times, a
        knot_t, knot_xy = (t0, t1), (a, b)
    elif inner == 1:
        mid = rows[1]
        times[n] = mid[0]
        knot_t, knot_xy = (t0, mid[0], t1), (a, complex(mid[1], mid[2]), b)
    else:
        times[n:] = [r[0] for r in rows[1:-1]]
        knot_t, knot_xy = [r[0] for r in rows], [complex(r[1], r[2]) for r in rows]
    return times, _interp_complex(times, knot_t, knot_xy)


def _long_samples(rows: Sequence[Sequence[float]], n: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_samples` of a long track (``n`` evenly spaced samples)."""
    times = _linspace(rows[0][0], rows[-1][0], n, [r[0] for r in rows[1:-1]])
    knot_xy = [complex(r[1], r[2]) for r in rows]
    return times, _interp_complex(times, [r[0] for r in rows], knot_xy)


def _tabulated(table, items: list, distance: float, out: list[Proximity]) -> None:
    """The signal of ``items`` ``(slot, knots, near)`` among one crowd, read from its table.

    The people near any of the tracks are measured along all of them in one pass: people the
    pruning left out of a track are farther than :data:`~havln_mj.sim.crowd.NEAR_M` from it,
    so measuring them changes neither its flags nor its reported distance.
    """
    if _closest is not None and all(rows[-1][0] <= UNROLLED_S for _, rows, _ in items):
        for slot, rows, people in items:
            out[slot] = _compiled(table, rows, people, distance)
        return
    if len(items) == 1:
        _, rows, people = items[0]
        times, agent = _samples(rows)
        earliest, latest, starts = rows[0][0], rows[-1][0], None
    else:
        parts = [_samples(rows) for _, rows, _ in items]
        times = np.concatenate([p[0] for p in parts])
        agent = np.concatenate([np.broadcast_to(xy, t.shape) for t, xy in parts])
        starts = np.cumsum([0] + [len(p[0]) for p in parts[:-1]])
        earliest = min(rows[0][0] for _, rows, _ in items)
        latest = max(rows[-1][0] for _, rows, _ in items)
        people = sorted(set().union(*(near for _, _, near in items)))
    # Only those near (people farther than NEAR_M change no result).
    who = None if len(people) == table.size else people
    gap = table.xy(times, earliest, who, latest)  # (people, samples)
    gap -= agent
    d = np.abs(gap)
    if starts is None:
        closest = [d.min(axis=1).tolist()]
    else:
        closest = np.minimum.reduceat(d, starts, axis=1).T.tolist()
    index = range(table.size) if who is None else who
    for (slot, _, _), row in zip(items, closest, strict=True):
        smallest = min(row)
        hit = ()
        if smallest <= distance:
            hit = tuple([k for k, v in zip(index, row, strict=True) if v <= distance])
        out[slot] = proximity_of(hit, smallest)


def track_proximity(
    crowd: Crowd,
    times: np.ndarray,
    positions: np.ndarray,
    distance: float = COLLISION_DISTANCE,
    people: np.ndarray | list[int] | None = None,
) -> Proximity:
    """The collision signal for an agent at ``positions (n, 3)`` at ``times (n,)``.

    Args:
        crowd: The people.
        times: Sample times, dense enough to catch a crossing (≥ :data:`SAMPLE_HZ`).
        positions: The agent's positions at those times.
        distance: Collision threshold (metres, horizontal).
        people: Indices of the people to check (default: everyone).
    """
    if len(crowd) == 0 or (people is not None and len(people) == 0):
        return NO_PROXIMITY
    index = np.arange(len(crowd)) if people is None else np.asarray(people, int)
    track = crowd.positions(times, index)  # (n, P, 3)
    d = np.hypot(track[..., 0] - positions[:, None, 0], track[..., 1] - positions[:, None, 1])
    closest = d.min(axis=0)
    hit = tuple(int(index[k]) for k in np.flatnonzero(closest <= distance))
    return proximity_of(hit, float(closest.min()))
