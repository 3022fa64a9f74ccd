"""Rooms a camera cannot see, left out of its frame (the image is the same).

A CPU renderer pays for every fragment it rasterises, hidden or not, and in a house most of
them belong to rooms behind walls. The world builder splits the building's visual geoms by
room (:func:`~havln_mj.scene.rooms.split_by_rooms`, the rooms named in each geom's name);
before a frame, :class:`RoomCulling` asks the house's :class:`~havln_mj.scene.rooms.RoomPlan`
which rooms the camera may see and hides the geoms of none of them (alpha 0, which MuJoCo
does not draw) until :meth:`RoomCulling.show_all`. What is left out lies wholly behind walls,
so every pixel and depth comes out as without it.
"""

from __future__ import annotations

import math
import re

import mujoco
import numpy as np

from havln_mj.scene.rooms import FULL, RoomPlan, Wedge

ROOMS_TAG = "__rooms_"
"""Geom names end in this and the rooms' indices joined by dots (``visual/3_wood__rooms_2.5``)."""

_TAG = re.compile(re.escape(ROOMS_TAG) + r"([0-9.]+)$")


def rooms_tag(rooms: tuple[int, ...]) -> str:
    """The name suffix of a geom in ``rooms`` (empty for none: such a geom is always drawn)."""
    return ROOMS_TAG + ".".join(map(str, rooms)) if rooms else ""


def view_wedge(xmat: np.ndarray, vfov: float, aspect: float) -> Wedge:
    """The plan directions (``(centre, half width)`` of azimuths) a camera's view spans.

    Args:
        xmat: The camera's orientation (``data.cam_xmat`` row, 9 values; it looks along −z).
        vfov: Vertical field of view (radians).
        aspect: Image width / height.

    Returns:
        The wedge, or :data:`~havln_mj.scene.rooms.FULL` when the view holds a vertical
        direction or spans half the plan or more.
    """
    rot = np.asarray(xmat, dtype=float).reshape(3, 3)
    tan_v = math.tan(vfov / 2)
    tan_h = tan_v * aspect
    for up in (rot[2], -rot[2]):  # world ±z in the camera's frame
        if up[2] < 0.0 and abs(up[0]) <= -up[2] * tan_h and abs(up[1]) <= -up[2] * tan_v:
            return FULL
    ahead = -rot[:, 2]
    if math.hypot(ahead[0], ahead[1]) < 1e-9:
        return FULL
    centre = math.atan2(ahead[1], ahead[0])
    angles = []
    for sx in (-tan_h, tan_h):
        for sy in (-tan_v, tan_v):
            d = rot @ (sx, sy, -1.0)
            if math.hypot(d[0], d[1]) < 1e-12:
                return FULL
            angles.append(math.remainder(math.atan2(d[1], d[0]) - centre, math.tau))
    lo, hi = min(angles), max(angles)
    if hi - lo >= math.pi - 1e-9:
        return FULL
    return centre + (lo + hi) / 2, (hi - lo) / 2 + 1e-9


class RoomCulling:
    """Hides, frame by frame, the building's geoms in rooms the camera cannot see.

    Args:
        model: The compiled world, its visual geoms named with :func:`rooms_tag`.
        plan: The building's rooms and portals.
    """

    def __init__(self, model: mujoco.MjModel, plan: RoomPlan) -> None:
        self.model, self.plan = model, plan
        ids, rooms = [], []
        for g in range(model.ngeom):
            match = _TAG.search(model.geom(g).name)
            if match is not None:
                ids.append(g)
                rooms.append([int(r) for r in match.group(1).split(".")])
        self._ids = np.array(ids, dtype=int)
        self._in = np.zeros((len(ids), plan.n_rooms), dtype=bool)
        for row, these in enumerate(rooms):
            self._in[row, these] = True
        self._alpha = model.geom_rgba[self._ids, 3].copy()
        self._seen: np.ndarray | None = None  # the rooms the last frame's camera may see

    @property
    def n_geoms(self) -> int:
        """How many geoms are tied to rooms."""
        return len(self._ids)

    def hide_unseen(self, data: mujoco.MjData, camera: int, vfov: float, aspect: float) -> bool:
        """Leaves out of the next frame the geoms of rooms camera ``camera`` cannot see.

        Call after kinematics; ``vfov`` is the frame's vertical field of view (radians) and
        ``aspect`` its width / height. Returns whether anything was left out (then call
        :meth:`show_all` after the frame).
        """
        self._seen = None
        if not len(self._ids):
            return False
        wedge = view_wedge(data.cam_xmat[camera], vfov, aspect)
        seen = self._seen = self.plan.visible(data.cam_xpos[camera], wedge)
        if seen is None:
            return False
        hidden = ~self._in[:, seen].any(axis=1)
        if not hidden.any():
            return False
        self.model.geom_rgba[self._ids, 3] = np.where(hidden, 0.0, self._alpha)
        return True

    def walled(self, centres: np.ndarray, radii: np.ndarray) -> np.ndarray | None:
        """Which spheres lie wholly in rooms the last :meth:`hide_unseen` found unseen.

        A sphere that meets no room at all is not among them.

        Args:
            centres: (N, 3) sphere centres.
            radii: (N,) their radii.

        Returns:
            (N,) bool, or None when that frame's camera could not tell (it sees everything).
        """
        if self._seen is None:
            return None
        reach = np.asarray(radii, dtype=float)[:, None]
        meets = self.plan.rooms_meeting(centres[:, :2] - reach, centres[:, :2] + reach, 0.0)
        # A sphere out of every room (outdoors) is nobody's to hide.
        return meets.any(axis=1) & ~meets[:, self._seen].any(axis=1)

    def show_all(self) -> None:
        """Puts back every geom :meth:`hide_unseen` left out."""
        self.model.geom_rgba[self._ids, 3] = self._alpha
