"""The people in a scene, as the simulator needs them, and the HA-VLN collision signal.

The simulator asks a crowd where each person's pelvis is at given simulated times (for the
collision signal), their full pose at one time (for drawing) and their states; the humans
package (:class:`havln_mj.humans.crowd.Crowd`) implements :class:`Crowd`. A scene without
people uses :data:`NO_CROWD`.

Collision (the HA-VLN signal): the agent is within ``distance`` (default 1 m) of a person,
measured horizontally from the agent's base to the person's pelvis, at any time during an
action. A body reports its base's track over the action as knots (piecewise linear: a point
body's straight move then its turn in place, a robot's trunk at every controller tick); the
track is sampled at :data:`SAMPLE_HZ` or faster, every knot included, so a person passing
through the agent's path mid-action is caught. Only people whose whole pelvis track
(:meth:`Crowd.footprint`) comes within :data:`NEAR_M` of the track are sampled; the smallest
distance reported is exact below ``NEAR_M`` and ``inf`` above.

The signal runs on every action, so it is computed as a lookup: a crowd that offers
``pelvis_table()`` (the humans package's does, see :mod:`havln_mj.humans.tracks`) has its
people's pelvis tracks tabulated once and read at all of an action's samples, for all people
and all of a batch's tracks among them, in one vectorised pass; who is near a straight track
is remembered (:class:`NearMemo`). Other crowds are asked for :meth:`Crowd.positions`.

HA3D measured otherwise (see :mod:`havln_mj.sim.rules`): only in each state, in 3-D from the
agent's camera to one tracked point per person (:func:`ha3d_points`,
:func:`state_proximity`).
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Sequence
from typing import NamedTuple, Protocol

import numpy as np

from havln_mj.errors import InvalidArgumentError

COLLISION_DISTANCE = 1.0
"""HA-VLN's collision threshold in metres (horizontal, from the agent's base to a pelvis)."""
SAMPLE_HZ = 16.0
"""The lowest rate, per simulated second, at which an action's track is checked for people."""
NEAR_M = 3.0
"""People farther than this (metres) from an action's whole track are not sampled."""


class Crowd(Protocol):
    """People whose positions are a function of simulated time."""

    def __len__(self) -> int:
        """Number of people."""
        ...

    @property
    def shapes(self) -> list:
        """Each person's body (``havln_mj.humans.body.BodyShape``), for drawing."""
        ...

    @property
    def skins(self) -> list:
        """Each person's SMPL skin (``havln_mj.humans.skinned.Skin``) or None."""
        ...

    def positions(self, times: np.ndarray, people: np.ndarray | None = None) -> np.ndarray:
        """Pelvis positions ``(len(times), P, 3)`` at the given simulated seconds.

        ``people`` indexes the people wanted (default: everyone, in order).
        """
        ...

    def footprint(self) -> tuple[np.ndarray, np.ndarray]:
        """Circles ``(centres (P, 2), radii (P,))`` holding each pelvis at all times."""
        ...

    def skin_vertices(self, t: float) -> dict:
        """World mesh vertices of each skinned person at ``t``, by person index."""
        ...

    def pose(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """World joint positions ``(N, 24, 3)`` and orientations ``(N, 24, 4)`` at ``t``."""
        ...

    def states(self, t: float) -> list:
        """Each person's state at ``t`` (position, heading, velocity, activity, region)."""
        ...


class _NoCrowd:
    """A scene without people."""

    def __len__(self) -> int:
        return 0

    @property
    def shapes(self) -> list:
        return []

    @property
    def skins(self) -> list:
        return []

    def skin_vertices(self, t: float) -> dict:
        return {}

    def positions(self, times: np.ndarray, people: np.ndarray | None = None) -> np.ndarray:
        return np.zeros((len(np.atleast_1d(times)), 0, 3))

    def footprint(self) -> tuple[np.ndarray, np.ndarray]:
        return np.zeros((0, 2)), np.zeros(0)

    def pose(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        return np.zeros((0, 24, 3)), np.zeros((0, 24, 4))

    def states(self, t: float) -> list:
        return []


NO_CROWD: Crowd = _NoCrowd()
"""The crowd of a scene without people."""


class Proximity(NamedTuple):
    """How close an action brought the agent to people.

    Attributes:
        crushed: Whether any person came within the collision distance.
        people: Indices of those people.
        min_distance: Smallest horizontal distance to anyone, if under :data:`NEAR_M`, else
            ``inf``.
    """

    crushed: bool
    people: tuple[int, ...]
    min_distance: float


NO_PROXIMITY = Proximity(False, (), math.inf)


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
) -> Proximity:
    """The collision signal of a body's track, people far from it left out.

    Args:
        crowd: The people.
        knots: The track of the body's base: rows ``(t, x, y, z)``, linear between rows (one
            row: an instant, e.g. an episode's start state).
        distance: Collision threshold (metres, horizontal).
    """
    return batch_proximity([(crowd, knots)], distance)[0]


class NearMemo:
    """Remembers who is near each straight track met before, per crowd.

    A point body walks the graph's edges, so the same few hundred straight tracks come back
    all the time; which people come within reach of one depends only on its two ends and the
    people's footprints. Long tracks (a robot's) are not remembered.
    """

    LIMIT = 1 << 16  # tracks remembered per crowd

    def __init__(self) -> None:
        self._seen: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()

    def near(self, crowd: Crowd, rows: Sequence[Sequence[float]], reach: float) -> list[int]:
        """:func:`_near_rows`, remembered for straight tracks of up to three knots."""
        n = len(rows)
        a, b = rows[0], rows[-1]
        if n > 3 or (n == 3 and (rows[1][1] != b[1] or rows[1][2] != b[2])):
            return _near_rows(crowd, rows, reach)
        seen = self._seen.get(crowd)
        if seen is None:
            seen = self._seen[crowd] = {}
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
    out = [NO_PROXIMITY] * len(tracks)
    reach = max(NEAR_M, distance)
    groups: dict[int, tuple[Crowd, list]] = {}
    for slot, (crowd, knots) in enumerate(tracks):
        if not len(crowd):
            continue
        rows = knots if isinstance(knots, tuple | list) else np.asarray(knots, float).tolist()
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


def _samples(rows: Sequence[Sequence[float]]) -> tuple[np.ndarray, np.ndarray]:
    """Sample times of a track (as :func:`sample_knots`, unordered) and its ``x + iy`` then."""
    t0, t1 = rows[0][0], rows[-1][0]
    if len(rows) == 1 or t1 <= t0:
        last = rows[-1]
        return np.array([t1]), np.array([complex(last[1], last[2])])
    n = max(2, math.ceil((t1 - t0) * SAMPLE_HZ) + 1)
    times = _linspace(t0, t1, n, [r[0] for r in rows[1:-1]])  # inner knots are samples too
    knot_t = np.array([r[0] for r in rows])
    knot_xy = np.array([complex(r[1], r[2]) for r in rows])
    return times, np.interp(times, knot_t, knot_xy)


def _tabulated(table, items: list, distance: float, out: list[Proximity]) -> None:
    """The signal of ``items`` ``(slot, knots, near)`` among one crowd, read from its table.

    The people near any of the tracks are measured along all of them in one pass: people the
    pruning left out of a track are farther than :data:`NEAR_M` from it, so measuring them
    changes neither its flags nor its reported distance.
    """
    if len(items) == 1:
        _, rows, people = items[0]
        times, agent = _samples(rows)
        earliest, starts = rows[0][0], None
    else:
        parts = [_samples(rows) for _, rows, _ in items]
        times = np.concatenate([p[0] for p in parts])
        agent = np.concatenate([p[1] for p in parts])
        starts = np.cumsum([0] + [len(p[0]) for p in parts[:-1]])
        earliest = min(rows[0][0] for _, rows, _ in items)
        people = sorted(set().union(*(near for _, _, near in items)))
    # Few people: all of them (no subset to look up); many: those near.
    who = None if table.size <= _VECTOR_NEAR else people
    gap = table.xy(times, earliest, who)  # (people, samples)
    gap -= agent
    d = np.abs(gap)
    if starts is None:
        closest = [d.min(axis=1).tolist()]
    else:
        closest = np.minimum.reduceat(d, starts, axis=1).T.tolist()
    index = range(table.size) if who is None else who
    for (slot, _, _), row in zip(items, closest, strict=True):
        smallest = min(row)
        if smallest <= distance:
            hit = tuple([k for k, v in zip(index, row, strict=True) if v <= distance])
            out[slot] = Proximity(True, hit, smallest if smallest < NEAR_M else math.inf)
        elif smallest < NEAR_M:
            out[slot] = Proximity(False, (), smallest)


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
    smallest = float(closest.min())
    return Proximity(bool(hit), hit, smallest if smallest < NEAR_M else math.inf)


# ---------------------------------------------------------------------- HA3D's distance

HA3D_TRACK_HEIGHT = 1.36
"""How high above a person's floor HA3D's tracked point is, in metres.

HA3D stands each body 1.36 m below its viewpoint's camera and tracks the mesh vertex nearest
the body's floor origin, mapped back up by 1.36 m (``src/utils/get_info.py``,
``getHumanLocations``)."""


def person_floors(crowd: Crowd) -> np.ndarray:
    """Each person's floor height ``(P,)``: the z of their anchor (the floor point placed).

    Raises:
        InvalidArgumentError: The crowd does not say where its people stand
            (``crowd.people[k].anchor``), which HA3D's distance needs.
    """
    people = getattr(crowd, "people", None)
    if people is None:
        if len(crowd) == 0:
            return np.zeros(0)
        raise InvalidArgumentError(
            f"{type(crowd).__name__} does not give its people's floor points "
            "(people[k].anchor); HA3D's collision distance needs them"
        )
    return np.array([float(p.anchor[2]) for p in people])


def ha3d_points(crowd: Crowd, pelvis: np.ndarray) -> np.ndarray:
    """HA3D's tracked point of each person: ``(P, 3)``.

    The pelvis's horizontal position at :data:`HA3D_TRACK_HEIGHT` above the person's floor
    (HA3D tracked a foot-level vertex of each body and lifted it to camera height).

    Args:
        crowd: The people.
        pelvis: Their pelvis positions ``(P, 3)`` at one time (``crowd.positions``).
    """
    points = np.array(pelvis, float).reshape(-1, 3)
    points[:, 2] = person_floors(crowd) + HA3D_TRACK_HEIGHT
    return points


def state_proximity(
    points: np.ndarray, camera: np.ndarray | Sequence[float], distance: float = COLLISION_DISTANCE
) -> Proximity:
    """HA3D's collision signal of one state: the 3-D distance from the camera to each point.

    Args:
        points: The people's tracked points ``(P, 3)`` (:func:`ha3d_points`).
        camera: The agent's camera position (HA3D: the viewpoint it stands on).
        distance: Collision when a point is at most this far (metres).

    Returns:
        The people within ``distance`` and the smallest distance to anyone (exact below
        :data:`NEAR_M`, else ``inf``).
    """
    if len(points) == 0:
        return NO_PROXIMITY
    d = np.linalg.norm(np.asarray(points, float) - np.asarray(camera, float), axis=1)
    hit = tuple(int(k) for k in np.flatnonzero(d <= distance))
    smallest = float(d.min())
    return Proximity(bool(hit), hit, smallest if smallest < NEAR_M else math.inf)
