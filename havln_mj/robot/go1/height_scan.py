"""Terrain heights around the GO1, cast from the world's collision geometry.

The scan casts vertical rays down onto the collision geoms (group ``COLLISION``: the building's
boxes or hulls, a flat floor) from a little above the trunk, as a height map built from a
depth camera or lidar would give; the robot's own geoms are seen through, people (group
``HUMANS``) are not terrain. A ray that starts inside a solid (a wall, the steps of a stair
well above the robot) finds its underside; such a cell is ``inf``: something stands there
higher than the ray's start. The building is static, so each cast is kept in a map of 1 cm
cells: the robot asks for the same ground many times while it walks over it.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from havln_mj import groups

CELL = 0.01  # metres: heights are cast at the centres of cells this size
RAY_START = 0.2  # metres above the trunk the rays start (under table tops and upper storeys)
RAY_LENGTH = 3.0  # metres: farther than this below the start there is no ground
_MAX_CELLS = 200_000  # the map starts over past this many cells


class HeightScan:
    """Ground heights under world points, for one robot in one model.

    Args:
        model: The compiled world.
        data: The robot's data (geometry poses come from it).
        robot_body: Any body of the robot; every geom in its tree is seen through.
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, robot_body: int) -> None:
        self.model, self.data = model, data
        root = model.body_rootid[robot_body]
        self._robot = model.body_rootid[model.geom_bodyid] == root
        self._group = np.zeros(mujoco.mjNGROUP, dtype=np.uint8)
        self._group[groups.COLLISION] = 1
        self._geom = np.zeros(1, dtype=np.int32)
        self._normal = np.zeros(3)
        self._down = np.array([0.0, 0.0, -1.0])
        self._up = np.array([0.0, 0.0, 1.0])
        self._pnt = np.zeros(3)
        self._map: dict[tuple[int, int, int], float] = {}
        self.rays = 0  # rays cast so far (for benchmarks)

    def clear(self) -> None:
        """Forgets the map (after the world changed)."""
        self._map.clear()

    def height(self, x: float, y: float, top: float) -> float:
        """The highest ground at (x, y) below ``top`` + ``RAY_START``; ``-inf`` when none.

        ``inf`` where the ray starts inside a solid (the ground there is higher still).

        ``top`` is a height near the robot (its trunk), so that floors of storeys above are not
        taken for ground. Cells are keyed by their 10 cm band of ``top`` as well.
        """
        key = (round(x / CELL), round(y / CELL), math.floor(top * 10.0))
        h = self._map.get(key)
        if h is None:
            if len(self._map) > _MAX_CELLS:
                self._map.clear()
            h = self._cast(key[0] * CELL, key[1] * CELL, (key[2] + 1) * 0.1 + RAY_START)
            self._map[key] = h
        return h

    def heights(self, xy: np.ndarray, top: float) -> np.ndarray:
        """:meth:`height` of each row of an ``(n, 2)`` array."""
        return np.array([self.height(x, y, top) for x, y in xy.tolist()])

    def _cast(self, x: float, y: float, z: float) -> float:
        if self._ray(x, y, z, self._up) is not None and self._normal[2] > 0.0:
            return math.inf  # a ray up leaves a solid through its top: (x, y, z) is inside
        dist = self._ray(x, y, z, self._down)
        if dist is None or dist > RAY_LENGTH:
            return -math.inf
        return z - dist

    def _ray(self, x: float, y: float, z: float, vec: np.ndarray) -> float | None:
        """Distance along ``vec`` from (x, y, z) to the first collision geom not the robot's."""
        p = self._pnt
        p[0], p[1], p[2] = x, y, z
        travelled = 0.0
        while travelled < RAY_LENGTH:
            self.rays += 1
            dist = mujoco.mj_ray(
                self.model, self.data, p, vec, self._group, 1, -1, self._geom, self._normal
            )
            if dist < 0:
                return None
            travelled += dist
            if not self._robot[self._geom[0]]:
                return travelled
            travelled += 1e-4  # through the robot's own geom: on from just past the hit
            p[2] = z + vec[2] * travelled
        return None
