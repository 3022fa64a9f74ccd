"""The people in a scene, as the simulator needs them, and the HA-VLN collision signal.

The simulator asks a crowd where each person's pelvis is at given simulated times (for the
collision signal), their full pose at one time (for drawing) and their states; the humans
package (:class:`havln_mj.humans.crowd.Crowd`) implements :class:`Crowd`. A scene without
people uses :data:`NO_CROWD`.

Collision (the HA-VLN signal): the agent is within ``distance`` (default 1 m) of a person,
measured horizontally from the agent's base to the person's pelvis, at any time during an
action. Actions are sampled at :data:`SAMPLE_HZ` or faster, both ends included, so a person
passing through the agent's path mid-action is caught.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

COLLISION_DISTANCE = 1.0  # metres, HA-VLN's threshold
SAMPLE_HZ = 16.0


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

    def positions(self, times: np.ndarray) -> np.ndarray:
        """Pelvis positions ``(len(times), len(self), 3)`` at the given simulated seconds."""
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

    def positions(self, times: np.ndarray) -> np.ndarray:
        return np.zeros((len(np.atleast_1d(times)), 0, 3))

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
        min_distance: Smallest horizontal distance to anyone (``inf`` without people).
    """

    crushed: bool
    people: tuple[int, ...]
    min_distance: float


NO_PROXIMITY = Proximity(False, (), math.inf)


def action_samples(
    start: np.ndarray, end: np.ndarray, t0: float, move_s: float, total_s: float
) -> tuple[np.ndarray, np.ndarray]:
    """Times and agent positions along an action: a straight move, then turning in place.

    Returns:
        ``(times (n,), positions (n, 3))`` at :data:`SAMPLE_HZ` or faster, both ends included.
    """
    n = max(2, math.ceil(total_s * SAMPLE_HZ) + 1)
    times = np.linspace(0.0, total_s, n)
    frac = np.clip(times / move_s, 0.0, 1.0) if move_s > 0 else np.ones(n)
    positions = start + frac[:, None] * (np.asarray(end) - np.asarray(start))
    return t0 + times, positions


def proximity(
    crowd: Crowd, times: np.ndarray, positions: np.ndarray, distance: float = COLLISION_DISTANCE
) -> Proximity:
    """The collision signal for an agent at ``positions`` at ``times``."""
    if len(crowd) == 0:
        return NO_PROXIMITY
    people = crowd.positions(times)  # (n, P, 3)
    d = np.hypot(people[..., 0] - positions[:, None, 0], people[..., 1] - positions[:, None, 1])
    closest = d.min(axis=0)
    hit = tuple(int(k) for k in np.flatnonzero(closest <= distance))
    return Proximity(bool(hit), hit, float(closest.min()))
