"""The people in a scene, as the simulator needs them, and the HA-VLN collision signal.

The simulator asks a crowd where each person's pelvis is at given simulated times (for the
collision signal), their full pose at one time (for drawing) and their states; the humans
package (:class:`havln_mj.humans.crowd.Crowd`) implements :class:`Crowd`. A scene without
people uses :data:`NO_CROWD`.

Collision (the HA-VLN signal): the agent is within ``distance`` (default 1 m) of a person,
measured horizontally from the agent's base to the person's pelvis, at any time during an
action. Actions are sampled at :data:`SAMPLE_HZ` or faster, both ends included, so a person
passing through the agent's path mid-action is caught. An action's move is a straight segment,
or a polyline where the edge is walked by a route (graph proxies). Only people whose whole
pelvis track (:meth:`Crowd.footprint`) comes within :data:`NEAR_M` of the action's path are
sampled; the smallest distance reported is exact below ``NEAR_M`` and ``inf`` above.
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


def action_samples(
    path: np.ndarray, t0: float, move_s: float, total_s: float
) -> tuple[np.ndarray, np.ndarray]:
    """Times and agent positions along an action: a move, then turning in place.

    Args:
        path: ``(K, 3)`` points, K ≥ 2: the move runs along this polyline (a straight move is
            its two ends) at constant speed.
        t0: Simulated time at the action's start.
        move_s: How long the move lasts.
        total_s: How long the action lasts (the turn follows the move).

    Returns:
        ``(times (n,), positions (n, 3))`` at :data:`SAMPLE_HZ` or faster, both ends included.
    """
    path = np.asarray(path, float)
    n = max(2, math.ceil(total_s * SAMPLE_HZ) + 1)
    times = np.arange(n) * (total_s / (n - 1))
    frac = np.clip(times / move_s, 0.0, 1.0) if move_s > 0 else np.ones(n)
    if len(path) == 2:
        positions = path[0] + frac[:, None] * (path[1] - path[0])
    else:
        run = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
        at = frac * run[-1]
        positions = np.column_stack([np.interp(at, run, path[:, i]) for i in range(3)])
    return t0 + times, positions


def _near(crowd: Crowd, path: np.ndarray, reach: float) -> list[int]:
    """Indices of people whose pelvis track comes within ``reach`` of the polyline ``path``."""
    centres, radii = crowd.footprint()
    legs = [
        (float(a[0]), float(a[1]), float(b[0]) - float(a[0]), float(b[1]) - float(a[1]))
        for a, b in itertools.pairwise(path)
    ]
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


def proximity(
    crowd: Crowd,
    path: np.ndarray | Sequence[Sequence[float]],
    t0: float,
    move_s: float,
    total_s: float,
    distance: float = COLLISION_DISTANCE,
) -> Proximity:
    """The collision signal of an action, people far from it left out.

    Args:
        crowd: The people.
        path: ``(K, 3)`` points, K ≥ 2: the action moves along this polyline from its first
            point to its last (a straight move is its two ends) in ``move_s`` seconds, then
            turns in place until ``total_s``.
        t0: Simulated time at the action's start.
        move_s: How long the move lasts.
        total_s: How long the action lasts.
        distance: Collision threshold (metres, horizontal).
    """
    if len(crowd) == 0:
        return NO_PROXIMITY
    near = _near(crowd, path, max(NEAR_M, distance))
    if not near:
        return NO_PROXIMITY
    times, positions = action_samples(path, t0, move_s, total_s)
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
