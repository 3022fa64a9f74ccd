"""Anny people in a MuJoCo model: textured rigid pieces on the joint bodies, or one skinned mesh.

**Pieces** (the default): each joint's mocap body ``human<k>/<joint>`` carries the part of
the person's mesh that joint moves (:func:`havln_mj.humans.anny_rig.rigid_pieces`), so posing
is writing the 24 mocap poses, as for the capsule bodies: no mesh is re-sent to the renderer.
Pieces overlap where joints blend, which closes creases when limbs bend. **Skinned**: one
mesh on ``human<k>/anny`` whose vertices are recomputed by linear blend skinning every frame
and re-uploaded (:class:`AnnySkinWriter`). Both use the person's painted texture and hair
shell (:mod:`havln_mj.humans.outfits`); a skirt hangs from the pelvis body.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import mujoco
import numpy as np

from havln_mj import groups
from havln_mj.humans import rotations as rot
from havln_mj.humans.anny_rig import AnnyRig, rigid_pieces
from havln_mj.humans.outfits import Outfit, hair_layer, paint, skirt_mesh
from havln_mj.humans.skeleton import JOINT_NAMES
from havln_mj.humans.skinned import vertex_normals
from havln_mj.render.texels import halvings, shrink, surface_areas

_MESH = mujoco.mjtGeom.mjGEOM_MESH


@dataclass(frozen=True)
class AnnyLook:
    """A person drawn as an Anny body.

    Attributes:
        rig: The catalog body fitted to our skeleton.
        outfit: Clothes, hair and skin.
        seed: Seed of the fabric patterns.
    """

    rig: AnnyRig
    outfit: Outfit
    seed: int = 0

    @cached_property
    def mesh(self) -> PersonMesh:
        """The body with its hair shell, at rest."""
        return person_mesh(self)


@dataclass(frozen=True)
class PersonMesh:
    """A person's drawable mesh: the body's vertices plus hair copies.

    Attributes:
        rest: Rest positions of the geometric vertices ``(G, 3)`` (body frame).
        weights: Dense joint weights ``(G, 24)``.
        faces: Triangles on geometric vertices ``(F, 3)``.
        render_vertex: The geometric vertex of each render vertex ``(R,)``.
        uv: UVs of the render vertices ``(R, 2)`` (OBJ convention).
        render_faces: Triangles on render vertices ``(F, 3)``.
        top_index: The 4 joints weighing on each geometric vertex ``(G, 4)``.
        top_weight: Their weights ``(G, 4)``.
    """

    rest: np.ndarray
    weights: np.ndarray
    faces: np.ndarray
    render_vertex: np.ndarray
    uv: np.ndarray
    render_faces: np.ndarray
    top_index: np.ndarray
    top_weight: np.ndarray


def person_mesh(look: AnnyLook) -> PersonMesh:
    """The body mesh of ``look`` with its hair shell appended."""
    body = look.rig.body
    topo = body.topology
    rest, faces = body.vertices, topo.faces
    top_i, top_w = topo.joint_index, topo.joint_weight
    render_vertex, uv, render_faces = topo.uv_vertex, topo.uv, topo.uv_faces
    hair = hair_layer(body, look.outfit)
    if hair is not None:
        ids, lift = hair
        remap = np.full(len(rest), -1)
        remap[ids] = len(rest) + np.arange(len(ids))
        keep = np.all(remap[faces] >= 0, axis=1)
        rest = np.concatenate([rest, rest[ids] + lift])
        faces = np.concatenate([faces, remap[faces[keep]]])
        top_i = np.concatenate([top_i, top_i[ids]])
        top_w = np.concatenate([top_w, top_w[ids]])
        # Render copies of the hair vertices, with their UVs (the scalp's hair-coloured texels).
        copies = np.flatnonzero(remap[render_vertex] >= 0)
        r_remap = np.full(len(render_vertex), -1)
        r_remap[copies] = len(render_vertex) + np.arange(len(copies))
        render_faces = np.concatenate([render_faces, r_remap[render_faces[keep]]])
        render_vertex = np.concatenate([render_vertex, remap[render_vertex[copies]]])
        uv = np.concatenate([uv, uv[copies]])
    weights = np.zeros((len(rest), len(JOINT_NAMES)))
    np.put_along_axis(weights, top_i, top_w, axis=1)
    return PersonMesh(rest, weights, faces, render_vertex, uv, render_faces, top_i, top_w)


def _texcoords(uv: np.ndarray) -> np.ndarray:
    """OBJ UVs as MuJoCo's flat float32 texcoords (v flipped: image rows run top first)."""
    out = np.asarray(uv, np.float32).copy()
    out[:, 1] = 1.0 - out[:, 1]
    return out.ravel()


def _add_mesh(
    spec: mujoco.MjSpec, name: str, verts: np.ndarray, normals: np.ndarray, faces: np.ndarray,
    uv: np.ndarray | None,
) -> None:  # fmt: skip
    mesh = spec.add_mesh(name=name)
    mesh.uservert = np.asarray(verts, np.float32).ravel()
    mesh.usernormal = np.asarray(normals, np.float32).ravel()
    mesh.userface = np.asarray(faces, np.int32).ravel()
    if uv is not None:
        mesh.usertexcoord = _texcoords(uv)
    mesh.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL  # open surfaces are fine


def _add_material(
    spec: mujoco.MjSpec, prefix: str, look: AnnyLook, mesh: PersonMesh, texel_limit: float | None
) -> str:
    image = paint(look.rig.body, look.outfit, look.seed)
    if texel_limit is not None:  # clothes finer than the camera resolves are halved
        areas = surface_areas(mesh.rest[mesh.render_vertex], mesh.render_faces, mesh.uv)
        image = shrink(image, halvings(image.shape, *areas, texel_limit))
    tex = spec.add_texture(
        name=f"{prefix}/skin_tex",
        type=mujoco.mjtTexture.mjTEXTURE_2D,
        width=image.shape[1],
        height=image.shape[0],
        nchannel=3,
    )
    tex.data = np.ascontiguousarray(image).tobytes()
    mat = spec.add_material(name=f"{prefix}/skin_mat", rgba=(1, 1, 1, 1), specular=0.1)
    mat.shininess = 0.1
    mat.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = f"{prefix}/skin_tex"
    return f"{prefix}/skin_mat"


def _geom(body: mujoco.MjsBody, name: str, mesh: str, **kw: object) -> None:
    body.add_geom(
        name=name, type=_MESH, meshname=mesh, contype=0, conaffinity=0,
        group=groups.HUMANS, mass=0.0, **kw,
    )  # fmt: skip


def add_anny_pieces(
    spec: mujoco.MjSpec,
    prefix: str,
    joint_bodies: list[mujoco.MjsBody],
    look: AnnyLook,
    texel_limit: float | None = None,
) -> None:
    """Adds ``look``'s rigid pieces (and skirt) to the person's 24 joint bodies.

    ``texel_limit``: most texels per metre the clothes texture keeps (None: its full size).
    """
    # Made for this build, not kept on the look: once compiled, the pieces need none of its
    # arrays (several MB a person), unlike a skinned body that re-skins them every frame.
    mesh, rig = person_mesh(look), look.rig
    material = _add_material(spec, prefix, look, mesh, texel_limit)
    normals = vertex_normals(mesh.rest, mesh.faces)
    for piece in rigid_pieces(mesh.weights, mesh.faces):
        faces = mesh.render_faces[piece.faces]
        used, local_faces = np.unique(faces, return_inverse=True)
        geo = mesh.render_vertex[used]
        c = rig.correction[piece.joint]
        verts = rot.rotate(c, mesh.rest[geo] - rig.anchors[piece.joint])
        name = f"{prefix}/{JOINT_NAMES[piece.joint]}/anny"
        _add_mesh(spec, name, verts, rot.rotate(c, normals[geo]), local_faces.reshape(-1, 3),
                  mesh.uv[used])  # fmt: skip
        _geom(joint_bodies[piece.joint], name, name, material=material)
    _add_skirt(spec, prefix, joint_bodies[0], look)


def _add_skirt(spec: mujoco.MjSpec, prefix: str, pelvis: mujoco.MjsBody, look: AnnyLook) -> None:
    if look.outfit.bottom != "skirt":
        return
    verts, faces = skirt_mesh(look.rig.body)
    name = f"{prefix}/skirt"
    _add_mesh(spec, name, verts, vertex_normals(verts, faces), faces, None)
    _geom(pelvis, name, name, rgba=(*look.outfit.bottom_rgb, 1.0))


def skinned_body_name(prefix: str) -> str:
    """The mocap body carrying a skinned Anny mesh."""
    return f"{prefix}/anny"


def add_anny_skinned(
    spec: mujoco.MjSpec,
    prefix: str,
    pelvis: mujoco.MjsBody,
    look: AnnyLook,
    park_z: float,
    texel_limit: float | None = None,
) -> None:
    """Adds ``look`` as one mesh (rest pose) on its own mocap body, re-skinned every frame.

    ``texel_limit``: most texels per metre the clothes texture keeps (None: its full size).
    """
    mesh = look.mesh
    material = _add_material(spec, prefix, look, mesh, texel_limit)
    rest = mesh.rest[mesh.render_vertex]
    normals = vertex_normals(mesh.rest, mesh.faces)[mesh.render_vertex]
    name = skinned_body_name(prefix)
    _add_mesh(spec, f"{name}_mesh", rest - rest.mean(axis=0), normals, mesh.render_faces, mesh.uv)
    body = spec.worldbody.add_body(name=name, mocap=True, pos=(0.0, 0.0, park_z))
    _geom(body, f"{name}/mesh", f"{name}_mesh", material=material)
    _add_skirt(spec, prefix, pelvis, look)


def _normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unit area-weighted vertex normals (``bincount`` sums: many times faster than add.at)."""
    v = vertices[faces]
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    idx = faces.ravel()
    rep = np.repeat(n, 3, axis=0)
    out = np.stack([np.bincount(idx, rep[:, c], minlength=len(vertices)) for c in range(3)], axis=1)
    return out / np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-12)


class AnnySkinWriter:
    """Writes skinned Anny vertices and normals into a compiled model's meshes."""

    def __init__(self, model: mujoco.MjModel, people: dict[int, tuple[str, AnnyLook]]) -> None:
        """``people``: person index → (name prefix, look) of each skinned Anny person."""
        self._people = {}
        for k, (prefix, look) in people.items():
            body = model.body(skinned_body_name(prefix))
            geom = int(model.body_geomadr[body.id])
            mesh = int(model.geom_dataid[geom])
            adr, num = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
            nadr = int(model.mesh_normaladr[mesh])
            if num != len(look.mesh.render_vertex) or int(model.mesh_normalnum[mesh]) != num:
                raise RuntimeError(f"MuJoCo rearranged the mesh of person {k}: cannot skin it")
            frame = (model.geom_pos[geom].copy(), rot.to_matrix(model.geom_quat[geom]))
            self._people[k] = (look, int(body.mocapid[0]), mesh, adr, num, nadr, frame)

    @property
    def people(self) -> list[int]:
        """The people this writer skins."""
        return list(self._people)

    def write(
        self, model: mujoco.MjModel, data: mujoco.MjData, positions: np.ndarray,
        quats: np.ndarray,
    ) -> list[int]:  # fmt: skip
        """Skins everyone it holds at the joint poses ``(N, 24, 3)``, ``(N, 24, 4)``.

        Returns:
            Ids of the meshes that changed (to upload to each renderer).
        """
        changed = []
        for k, (look, mocap, mesh, adr, num, nadr, (pos, rmat)) in self._people.items():
            m = look.mesh
            world = look.rig.skin(positions[k], quats[k], m.rest, m.top_index, m.top_weight)
            centre = world.mean(axis=0)
            data.mocap_pos[mocap] = centre
            data.mocap_quat[mocap] = (1.0, 0.0, 0.0, 0.0)
            local = (world - centre - pos) @ rmat
            normals = _normals(local, m.faces)
            model.mesh_vert[adr : adr + num] = local[m.render_vertex]
            model.mesh_normal[nadr : nadr + num] = normals[m.render_vertex]
            changed.append(mesh)
        return changed
