"""People in a MuJoCo world: one mocap body per joint, posed every frame from world poses.

Each person ``k`` adds 24 mocap bodies ``human<k>/<joint>`` (direct children of the world,
as MuJoCo requires of mocap bodies) carrying the body's geoms: the capsule body's
(``human<k>/<joint>/<i>``), or for a shape with an Anny look the textured pieces of its mesh
(``human<k>/<joint>/anny``, see :mod:`havln_mj.humans.anny_mujoco`); solid Anny people keep
their capsules for contacts, invisible (alpha 0).
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
from havln_mj.errors import InvalidArgumentError
from havln_mj.humans.anny_mujoco import add_anny_pieces, add_anny_skinned
from havln_mj.humans.body import BodyShape, Piece
from havln_mj.humans.skeleton import JOINT_NAMES, NUM_JOINTS
from havln_mj.humans.skinned import Skin, add_skin

FILLER_SHRINK = 0.6  # capsule fillers inside rigid Anny pieces, relative to the mannequin
FILLER_SLICES = 8  # sides of a filler's low-poly mesh
PARK_Z = -100.0  # metres: where unposed people wait, out of every camera's view
_GEOM = {
    "capsule": mujoco.mjtGeom.mjGEOM_CAPSULE,
    "sphere": mujoco.mjtGeom.mjGEOM_SPHERE,
    "box": mujoco.mjtGeom.mjGEOM_BOX,
}


def body_name(person: int, joint: int) -> str:
    """The MuJoCo body name of a person's joint."""
    return f"human{person}/{JOINT_NAMES[joint]}"


DRAW_STYLES = ("pieces", "skinned", "capsules")
"""How people with an Anny look may be drawn, as rigid textured pieces on the joint bodies (no
per-frame upload), one mesh skinned every frame, or the capsule mannequins."""


def add_people(
    spec: mujoco.MjSpec,
    shapes: list[BodyShape],
    skins: Sequence[Skin | None] = (),
    solid: bool = False,
    style: str = "pieces",
    texel_limit: float | None = None,
) -> None:
    """Adds the mocap bodies and geoms of ``shapes`` (person k = ``shapes[k]``) to ``spec``.

    A person with a skin (``skins[k]``) is drawn as that mesh (in their top's colour) and
    their joint bodies carry no geoms. A shape with an Anny look is drawn as ``style`` says
    (:data:`DRAW_STYLES`). ``solid`` makes the capsule geoms collide (``contype =
    conaffinity = 1``), so they push a simulated robot; it must be chosen before compiling,
    since MuJoCo aggregates contact bits per body then. ``texel_limit`` caps the texels per
    metre of the Anny clothes textures (:mod:`havln_mj.render.texels`; None: full size).

    Raises:
        InvalidArgumentError: ``style`` is not one of :data:`DRAW_STYLES`.
    """
    if style not in DRAW_STYLES:
        raise InvalidArgumentError(f"people style {style!r} unknown; valid: {DRAW_STYLES}")
    skins = list(skins) + [None] * (len(shapes) - len(skins))
    for k, (shape, skin) in enumerate(zip(shapes, skins, strict=True)):
        if skin is not None:
            add_skin(spec, k, skin, shape.top, PARK_Z)
        look = shape.look if skin is None and style != "capsules" else None
        # Rigid Anny pieces keep thinner capsules inside as fillers: where a bent joint opens
        # a crease between two pieces, the filler shows clothes or skin, not the room behind.
        # Seen only there, they are low-poly meshes; solid people's fillers stay MuJoCo
        # capsules, which also take the contacts.
        filler = look is not None and style == "pieces"
        pieces = shape.pieces() if skin is None and (look is None or solid or filler) else []
        bodies = [
            spec.worldbody.add_body(name=body_name(k, j), mocap=True, pos=(0.0, 0.0, PARK_Z))
            for j in range(NUM_JOINTS)
        ]
        if look is not None and style == "pieces":
            add_anny_pieces(spec, f"human{k}", bodies, look, texel_limit)
        elif look is not None:
            add_anny_skinned(spec, f"human{k}", bodies[0], look, PARK_Z, texel_limit)
        alpha = 0.0 if look is not None and not filler else 1.0  # skinned: contacts only
        for j, body in enumerate(bodies):
            for i, piece in enumerate(p for p in pieces if p.joint == j):
                name = f"{body_name(k, j)}/{i}"
                rgba = (*shape.colour(piece.part), alpha)
                if filler and not solid and piece.kind != "box":
                    _add_filler(spec, body, name, piece, rgba)
                    continue
                geom = body.add_geom(
                    name=name,
                    type=_GEOM[piece.kind],
                    contype=int(solid),
                    conaffinity=int(solid),
                    group=groups.HUMANS,
                    rgba=rgba,
                    mass=0.0,
                )
                shrink = FILLER_SHRINK if filler else 1.0
                if piece.kind == "capsule":
                    geom.fromto = (*piece.a, *piece.b)
                    geom.size = (shrink * piece.size[0], 0.0, 0.0)
                else:
                    geom.pos = piece.a
                    size = np.array(piece.size) * shrink
                    geom.size = (*size, *(0.0,) * (3 - len(size)))


def _add_filler(
    spec: mujoco.MjSpec, body: mujoco.MjsBody, name: str, piece: Piece, rgba: tuple
) -> None:
    """A filler inside rigid Anny pieces: a low-poly capsule (or sphere) mesh.

    Fillers show only in the creases of bent joints, so a few dozen triangles do; MuJoCo's
    own capsules are tessellated for being seen whole and cost several times as much to draw.
    """
    a = np.asarray(piece.a, float)
    b = np.asarray(piece.b, float) if piece.kind == "capsule" else a
    verts, normals, faces = capsule_mesh(a, b, FILLER_SHRINK * piece.size[0])
    mesh = spec.add_mesh(name=f"{name}/mesh")
    mesh.uservert = verts.astype(np.float32).ravel()
    mesh.usernormal = normals.astype(np.float32).ravel()
    mesh.userface = faces.astype(np.int32).ravel()
    mesh.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL
    body.add_geom(
        name=name,
        type=mujoco.mjtGeom.mjGEOM_MESH,
        meshname=f"{name}/mesh",
        contype=0,
        conaffinity=0,
        group=groups.HUMANS,
        rgba=rgba,
        mass=0.0,
    )


def capsule_mesh(
    a: np.ndarray, b: np.ndarray, radius: float, slices: int = FILLER_SLICES, rings: int = 2
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A closed capsule from ``a`` to ``b`` (a sphere when they coincide), outward faces.

    Args:
        a: One end of the axis.
        b: The other end.
        radius: The capsule's radius.
        slices: Vertices around each ring.
        rings: Rings per half-sphere, the equator included.

    Returns:
        Vertices ``(V, 3)``, unit normals ``(V, 3)`` and triangles ``(F, 3)``, counter-
        clockwise seen from outside.
    """
    axis = b - a
    length = float(np.linalg.norm(axis))
    z = axis / length if length > 1e-9 else np.array([0.0, 0.0, 1.0])
    x = np.cross(z, [1.0, 0.0, 0.0] if abs(z[0]) < 0.9 else [0.0, 1.0, 0.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    phi = 2 * np.pi * np.arange(slices) / slices
    around = np.cos(phi)[:, None] * x + np.sin(phi)[:, None] * y  # (S, 3)
    # Rings from just above the bottom pole (around a) to just below the top pole (around
    # b); the equator is a ring on each half-sphere, so the straight part joins them (a
    # sphere has one equator).
    step = np.pi / 2 / rings
    lats = [(-np.pi / 2 + step * i, a) for i in range(1, rings + 1)]
    lats += [(step * i, b) for i in range(0 if length > 1e-9 else 1, rings)]
    normals = [-z[None]]
    centres = [a[None]]
    for lat, centre in lats:
        normals.append(np.sin(lat) * z + np.cos(lat) * around)
        centres.append(np.repeat(centre[None], slices, axis=0))
    normals.append(z[None])
    centres.append(b[None])
    normals, centres = np.vstack(normals), np.vstack(centres)
    k = np.arange(slices)
    k1 = (k + 1) % slices
    first, top = 1, len(normals) - 1
    faces = [np.stack([np.zeros(slices, int), first + k1, first + k], axis=1)]
    for r in range(len(lats) - 1):
        lo, hi = first + r * slices, first + (r + 1) * slices
        faces.append(np.stack([lo + k, lo + k1, hi + k1], axis=1))
        faces.append(np.stack([lo + k, hi + k1, hi + k], axis=1))
    last = first + (len(lats) - 1) * slices
    faces.append(np.stack([np.full(slices, top), last + k, last + k1], axis=1))
    return centres + radius * normals, normals, np.vstack(faces)


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
