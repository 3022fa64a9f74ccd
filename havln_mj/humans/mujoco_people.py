"""People in a MuJoCo world: one mocap body per joint, posed every frame from world poses.

Each person ``k`` adds 24 mocap bodies ``human<k>/<joint>`` (direct children of the world,
as MuJoCo requires of mocap bodies) carrying the body's geoms (``human<k>/<joint>/<i>``).
The geoms make no contacts (``contype = conaffinity = 0``; the HA-VLN collision signal is a
distance, computed analytically) unless asked to be solid, and sit in their own geom group,
``groups.HUMANS``, so cameras see them and collision queries can leave them out. Until
posed, people are parked far below the building.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

from havln_mj import groups
from havln_mj.humans.body import BodyShape
from havln_mj.humans.skeleton import JOINT_NAMES, NUM_JOINTS
from havln_mj.humans.skinned import Skin, add_skin

PARK_Z = -100.0  # metres: where unposed people wait, out of every camera's view
_GEOM = {
    "capsule": mujoco.mjtGeom.mjGEOM_CAPSULE,
    "sphere": mujoco.mjtGeom.mjGEOM_SPHERE,
    "box": mujoco.mjtGeom.mjGEOM_BOX,
}


def body_name(person: int, joint: int) -> str:
    """The MuJoCo body name of a person's joint."""
    return f"human{person}/{JOINT_NAMES[joint]}"


def add_people(
    spec: mujoco.MjSpec,
    shapes: list[BodyShape],
    skins: Sequence[Skin | None] = (),
    solid: bool = False,
) -> None:
    """Adds the mocap bodies and geoms of ``shapes`` (person k = ``shapes[k]``) to ``spec``.

    A person with a skin (``skins[k]``) is drawn as that mesh (in their top's colour) and
    their joint bodies carry no geoms. ``solid`` makes the built-in bodies' geoms collide
    (``contype = conaffinity = 1``), so they push a simulated robot; it must be chosen before
    compiling, since MuJoCo aggregates contact bits per body then.
    """
    skins = list(skins) + [None] * (len(shapes) - len(skins))
    for k, (shape, skin) in enumerate(zip(shapes, skins, strict=True)):
        if skin is not None:
            add_skin(spec, k, skin, shape.top, PARK_Z)
        pieces = shape.pieces() if skin is None else []
        for j in range(NUM_JOINTS):
            body = spec.worldbody.add_body(name=body_name(k, j), mocap=True, pos=(0.0, 0.0, PARK_Z))
            for i, piece in enumerate(p for p in pieces if p.joint == j):
                geom = body.add_geom(
                    name=f"{body_name(k, j)}/{i}",
                    type=_GEOM[piece.kind],
                    contype=int(solid),
                    conaffinity=int(solid),
                    group=groups.HUMANS,
                    rgba=(*shape.colour(piece.part), 1.0),
                    mass=0.0,
                )
                if piece.kind == "capsule":
                    geom.fromto = (*piece.a, *piece.b)
                    geom.size = (piece.size[0], 0.0, 0.0)
                else:
                    geom.pos = piece.a
                    geom.size = (*piece.size, *(0.0,) * (3 - len(piece.size)))


class PeopleWriter:
    """Writes people's joint poses into a compiled model's mocap arrays."""

    def __init__(self, model: mujoco.MjModel, n_people: int) -> None:
        ids = [
            int(model.body(body_name(k, j)).mocapid[0])
            for k in range(n_people)
            for j in range(NUM_JOINTS)
        ]
        self._mocap = np.array(ids, dtype=int)
        self._contiguous = bool(
            len(ids) and np.array_equal(self._mocap, np.arange(ids[0], ids[0] + len(ids)))
        )
        self.n_people = n_people

    def write(self, data: mujoco.MjData, positions: np.ndarray, quats: np.ndarray) -> None:
        """Poses everyone: world joint positions ``(N, 24, 3)`` and orientations ``(N, 24, 4)``."""
        if self.n_people == 0:
            return
        pos = positions.reshape(-1, 3)
        quat = quats.reshape(-1, 4)
        if self._contiguous:
            s = slice(self._mocap[0], self._mocap[0] + len(self._mocap))
            data.mocap_pos[s] = pos
            data.mocap_quat[s] = quat
        else:
            data.mocap_pos[self._mocap] = pos
            data.mocap_quat[self._mocap] = quat
