"""The people in a scene, as the simulator needs them, and the HA-VLN collision signal.

The simulator asks a crowd where each person's pelvis is at given simulated times (for the
collision signal), their full pose at one time (for drawing) and their states; the humans
package (:class:`havln_mj.humans.crowd.Crowd`) implements :class:`Crowd`. A scene without
people uses :data:`NO_CROWD`.

Collision (the HA-VLN signal, computed by :mod:`havln_mj.sim.proximity`): the agent is
within ``distance`` (default 1 m) of a person, measured horizontally from the agent's base to
the person's pelvis, at any time during an action; :class:`Proximity` says who and how close.

HA3D measured otherwise (see :mod:`havln_mj.sim.rules`): only in each state, in 3-D from the
agent's camera to one tracked point per person (:func:`ha3d_points`,
:func:`state_proximity`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple, Protocol

import numpy as np

from havln_mj.errors import InvalidArgumentError

COLLISION_DISTANCE = 1.0
"""HA-VLN's collision threshold in metres (horizontal, from the agent's base to a pelvis)."""
NEAR_M = 3.0
"""People farther than this (metres) from an action are reported at distance ``inf``."""


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

_new = tuple.__new__  # a Proximity without its Python-level constructor (hot)


def proximity_of(hit: tuple[int, ...], smallest: float) -> Proximity:
    """The collision signal: the people ``hit`` and the smallest distance to anyone.

    ``hit`` are the people within the collision distance; ``smallest`` is kept when under
    :data:`NEAR_M`, else reported as ``inf``.
    """
    if not hit and smallest >= NEAR_M:
        return NO_PROXIMITY
    return _new(Proximity, (bool(hit), hit, smallest if smallest < NEAR_M else math.inf))


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
    return proximity_of(tuple(int(k) for k in np.flatnonzero(d <= distance)), float(d.min()))
