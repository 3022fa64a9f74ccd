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
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

COLLISION_DISTANCE = 1.0  # metres, HA-VLN's threshold
SAMPLE_HZ = 16.0
NEAR_M = 3.0  # metres: people farther than this from an action are not sampled


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


@dataclass(frozen=True)
class Proximity:
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
    times = np.union1d(t, np.linspace(t[0], t[-1], n))
    positions = np.column_stack([np.interp(times, t, knots[:, i]) for i in (1, 2, 3)])
    return times, positions


def _near(crowd: Crowd, path: np.ndarray, reach: float) -> list[int]:
    """Indices of people whose pelvis track comes within ``reach`` of the polyline ``path``."""
    centres, radii = crowd.footprint()
    legs = [
        (float(a[0]), float(a[1]), float(b[0]) - float(a[0]), float(b[1]) - float(a[1]))
        for a, b in itertools.pairwise(path)
    ] or [(float(path[0][0]), float(path[0][1]), 0.0, 0.0)]
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
    if len(crowd) == 0:
        return NO_PROXIMITY
    knots = np.asarray(knots, float).reshape(-1, 4)
    near = _near(crowd, knots[:, 1:], max(NEAR_M, distance))
    if not near:
        return NO_PROXIMITY
    times, positions = sample_knots(knots)
    return track_proximity(crowd, times, positions, distance, near)


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
