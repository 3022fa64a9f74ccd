"""People drawn as skinned SMPL meshes, from a model file the user supplies.

With an SMPL model (see :mod:`havln_mj.humans.smpl_model`) a person is one mesh geom, its
vertices recomputed every frame by linear blend skinning and written into the compiled
model, then re-uploaded to the renderer (``mjr_uploadMesh``); normals are recomputed too, so
lighting follows the pose. The mesh hangs on a mocap body ``human<k>/skin`` that follows the
mesh's centre (parked far below until posed); vertices are written relative to it.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from havln_mj import groups
from havln_mj.humans import rotations as rot
from havln_mj.humans.skeleton import SMPL_TO_BODY
from havln_mj.humans.smpl_model import SmplModel


@dataclass(frozen=True)
class Skin:
    """A person's SMPL model and shape.

    Attributes:
        model: The user's SMPL model.
        betas: Shape coefficients (None: the mean shape).
    """

    model: SmplModel
    betas: np.ndarray | None = None

    @property
    def offsets(self) -> np.ndarray:
        """Rest joint offsets of this shape in our body frame."""
        return self.model.rest_offsets(self.betas)


def skin_body_name(person: int) -> str:
    """The mocap body carrying person ``person``'s mesh."""
    return f"human{person}/skin"


def add_skin(
    spec: mujoco.MjSpec, person: int, skin: Skin, rgb: tuple[float, ...], park_z: float
) -> None:
    """Adds person ``person``'s mesh (rest shape) on its own mocap body, parked at ``park_z``."""
    name = skin_body_name(person)
    mesh = spec.add_mesh(name=f"{name}_mesh")
    rest = skin.model.shaped(skin.betas) @ SMPL_TO_BODY.T
    mesh.uservert = (rest - rest.mean(axis=0)).ravel().tolist()
    mesh.userface = np.asarray(skin.model.faces, int).ravel().tolist()
    mesh.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL  # open surfaces are fine
    body = spec.worldbody.add_body(name=name, mocap=True, pos=(0.0, 0.0, park_z))
    body.add_geom(
        name=f"{name}/mesh",
        type=mujoco.mjtGeom.mjGEOM_MESH,
        meshname=f"{name}_mesh",
        contype=0,
        conaffinity=0,
        group=groups.HUMANS,
        rgba=(*rgb, 1.0),
        mass=0.0,
    )


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unit per-vertex normals (area-weighted face normals)."""
    v = vertices[faces]
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    out = np.zeros_like(vertices)
    for k in range(3):
        np.add.at(out, faces[:, k], n)
    return out / np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-12)


class SkinWriter:
    """Writes skinned vertices into a compiled model's meshes."""

    def __init__(self, model: mujoco.MjModel, people: list[int]) -> None:
        self._people = {}
        for k in people:
            body = model.body(skin_body_name(k))
            geom = int(model.body_geomadr[body.id])
            mesh = int(model.geom_dataid[geom])
            adr, num = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
            face_adr, nface = int(model.mesh_faceadr[mesh]), int(model.mesh_facenum[mesh])
            faces = model.mesh_face[face_adr : face_adr + nface]
            # Normals can be rewritten only when they are stored one per vertex.
            per_vertex = int(model.mesh_normalnum[mesh]) == num and np.array_equal(
                model.mesh_facenormal[face_adr : face_adr + nface], faces
            )
            rot_t = rot.to_matrix(model.geom_quat[geom]).T
            self._people[k] = (int(body.mocapid[0]), mesh, adr, num, faces, per_vertex,
                               model.geom_pos[geom].copy(), rot_t)  # fmt: skip

    def write(self, model: mujoco.MjModel, data: mujoco.MjData, vertices: dict) -> list[int]:
        """Poses the meshes: ``vertices[k]`` are person k's world vertices ``(V, 3)``.

        Returns:
            The ids of the meshes that changed (to upload to the renderer).
        """
        changed = []
        for k, world in vertices.items():
            mocap, mesh, adr, num, faces, per_vertex, pos, rot_t = self._people[k]
            # The body follows the mesh, so vertices stay near the compiled geom frame.
            centre = world.mean(axis=0)
            data.mocap_pos[mocap] = centre
            data.mocap_quat[mocap] = (1.0, 0.0, 0.0, 0.0)
            local = (world - centre - pos) @ rot_t.T
            model.mesh_vert[adr : adr + num] = local
            if per_vertex:
                nadr = int(model.mesh_normaladr[mesh])
                model.mesh_normal[nadr : nadr + num] = vertex_normals(local, faces)
            changed.append(mesh)
        return changed
