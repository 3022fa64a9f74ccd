"""Visual mesh parts as MuJoCo assets and geoms, with their textures.

Each part becomes one mesh asset and one world geom named ``visual/<k>_<part name>``:
no contacts, in the visual geom group. A textured part gets a 2-D texture holding its image
(RGB, or RGBA for a blended overlay), a material using it, and the mesh's per-vertex texture
coordinates; the material's colour is the part's ``rgba``, which MuJoCo multiplies with the
texture. An untextured part keeps its ``rgba`` on the geom, or on a material when it shines or
glows. Parts that look alike share one material, and an image shared by parts is uploaded
once. Given a texel limit, an image finer on its parts than the camera resolves is halved
first (:mod:`havln_mj.render.texels`).

Texture orientation: :class:`~havln_mj.scene.mesh.MeshPart` stores images top row first and
UVs in the OBJ convention (``v = 0`` at the image's bottom). MuJoCo puts the first row of a
texture's data at ``v = 0``, so ``v`` is flipped (``v' = 1 - v``) when the coordinates are
handed to MuJoCo; the image bytes are passed unchanged (no copy of large images is flipped).

MuJoCo rejects meshes with fewer than 4 vertices or no surface area: a part with 3 vertices
gets a repeated, unused vertex; a part with no triangles or zero area is skipped (logged).
"""

from __future__ import annotations

import logging

import mujoco
import numpy as np

from havln_mj import groups
from havln_mj.errors import InvalidArgumentError
from havln_mj.render.texels import halvings, shrink, surface_areas
from havln_mj.scene.mesh import MeshPart

log = logging.getLogger(__name__)

_MIN_AREA = 1e-12  # m²; MuJoCo refuses meshes whose surface area is below its tolerance


def safe_name(text: str) -> str:
    """``text`` with every character other than letters, digits and ``_-.`` replaced by ``_``."""
    return "".join(c if c.isalnum() or c in "_-." else "_" for c in text)


def _add_texture(spec: mujoco.MjSpec, name: str, image: np.ndarray) -> None:
    """Adds a 2-D texture called ``name`` holding ``image`` (H×W×3 or ×4 uint8, top row first)."""
    if image.ndim != 3 or image.shape[2] not in (3, 4) or image.dtype != np.uint8:
        raise InvalidArgumentError(
            f"texture {name!r} must be an H×W×3 or H×W×4 uint8 array, "
            f"got {image.dtype} {image.shape}"
        )
    height, width, channels = image.shape
    texture = spec.add_texture(
        name=name,
        type=mujoco.mjtTexture.mjTEXTURE_2D,
        width=width,
        height=height,
        nchannel=channels,
    )
    # The attribute takes bytes (the constructor keyword wants a list of ints: far slower).
    texture.data = np.ascontiguousarray(image).tobytes()


def _check_part(part: MeshPart, vertices: np.ndarray, faces: np.ndarray) -> None:
    """Raises InvalidArgumentError when the part's arrays do not fit together."""
    where = f"visual part {part.name!r}"
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise InvalidArgumentError(
            f"{where}: vertices have shape {vertices.shape}, expected (V, 3)"
        )
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise InvalidArgumentError(f"{where}: faces have shape {faces.shape}, expected (F, 3)")
    if len(faces) and (faces.min() < 0 or faces.max() >= len(vertices)):
        raise InvalidArgumentError(
            f"{where}: face indices span [{faces.min()}, {faces.max()}], "
            f"valid [0, {len(vertices) - 1}]"
        )
    if part.uv is not None and part.uv.shape != (len(vertices), 2):
        raise InvalidArgumentError(
            f"{where}: uv has shape {part.uv.shape}, expected ({len(vertices)}, 2)"
        )


def _area(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Total triangle area (0 for no faces)."""
    if len(faces) == 0:
        return 0.0
    tri = vertices[faces].astype(np.float64)
    return 0.5 * float(
        np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum()
    )


def _mujoco_texcoords(uv: np.ndarray) -> np.ndarray:
    """OBJ-convention UVs (V, 2) as MuJoCo's flat float32 texcoords (``v`` flipped)."""
    out = np.empty((len(uv), 2), dtype=np.float32)
    out[:, 0] = uv[:, 0]
    np.subtract(1.0, uv[:, 1], out=out[:, 1])
    return out.ravel()


def _material(
    spec: mujoco.MjSpec,
    part: MeshPart,
    texture: str | None,
    emission: float,
    cache: dict[tuple, str],
) -> str:
    """The name of a material for ``part`` (made once per distinct look)."""
    glow = max(part.emission, emission if texture is not None else 0.0)
    look = (texture, part.rgba, part.shine, glow)
    name = cache.get(look)
    if name is None:
        name = cache[look] = f"visual/mat{len(cache)}"
        material = spec.add_material(
            name=name,
            rgba=part.rgba,
            emission=glow,
            specular=0.5 * part.shine,
            shininess=0.2 + 0.6 * part.shine,
        )
        if texture is not None:
            material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = texture
    return name


def _texture_halvings(
    parts: list[MeshPart], arrays: list[tuple[np.ndarray, np.ndarray]], limit: float | None
) -> dict[int, int]:
    """id(image) -> how many times it is halved to fit ``limit`` on all the parts using it.

    ``arrays`` holds each part's checked ``(vertices, faces)``.
    """
    if limit is None:
        return {}
    areas: dict[int, list[float]] = {}
    for part, (vertices, faces) in zip(parts, arrays, strict=True):
        if part.texture is not None and part.uv is not None:
            uv_area, area = surface_areas(vertices, faces, part.uv)
            sums = areas.setdefault(id(part.texture), [0.0, 0.0])
            sums[0] += uv_area
            sums[1] += area
    shapes = {id(p.texture): p.texture.shape for p in parts if p.texture is not None}
    return {key: halvings(shapes[key], uv, a, limit) for key, (uv, a) in areas.items()}


def add_visual_parts(
    spec: mujoco.MjSpec,
    parts: list[MeshPart],
    *,
    group: int = groups.VISUAL,
    emission: float = 0.0,
    texel_limit: float | None = None,
) -> int:
    """Adds mesh parts to the world body as non-colliding visual geoms.

    Args:
        spec: The model being built.
        parts: The mesh parts (see :func:`havln_mj.scene.mesh.load_mesh_parts`).
        group: Geom group of the new geoms.
        emission: Least emission of textured materials (0 lets the scene's lights alone shade
            them; scan textures already hold baked lighting, so a higher value with dimmer
            lights looks closer to the photographs).
        texel_limit: Most texels per metre a texture keeps on its parts (see
            :func:`havln_mj.render.texels.resolved_density`); None keeps every texture.

    Returns:
        The number of geoms added, one per part, less the parts skipped for having no
        surface (their index ``k`` is left unused, so names stay tied to ``parts``).

    Raises:
        InvalidArgumentError: A part's vertices, faces, UVs or texture do not fit together.
    """
    textures: dict[int, str] = {}  # id(image) -> texture name; shared images upload once
    materials: dict[tuple, str] = {}
    arrays = [
        (np.asarray(part.vertices, dtype=np.float32), np.asarray(part.faces, dtype=np.int32))
        for part in parts
    ]
    for part, (vertices, faces) in zip(parts, arrays, strict=True):
        _check_part(part, vertices, faces)
    halved = _texture_halvings(parts, arrays, texel_limit)
    added = 0
    for k, (part, (vertices, faces)) in enumerate(zip(parts, arrays, strict=True)):
        name = f"visual/{k}_{safe_name(part.name)}"
        if _area(vertices, faces) < _MIN_AREA:
            log.warning("visual part %d (%r) has no surface; skipped", k, part.name)
            continue
        uv = part.uv
        if len(vertices) < 4:  # MuJoCo's minimum; the extra vertex is used by no face
            vertices = np.concatenate([vertices, vertices[:1]])
            uv = None if uv is None else np.concatenate([uv, uv[:1]])
        mesh = spec.add_mesh(
            name=name,
            uservert=vertices.ravel(),
            userface=faces.ravel(),
            inertia=mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL,  # open meshes have no volume
        )
        geom: dict = {"group": group, "contype": 0, "conaffinity": 0}
        texture = None
        if uv is not None and part.texture is not None:
            mesh.usertexcoord = _mujoco_texcoords(uv)
            texture = textures.get(id(part.texture))
            if texture is None:
                texture = textures[id(part.texture)] = f"visual/tex{len(textures)}"
                _add_texture(spec, texture, shrink(part.texture, halved.get(id(part.texture), 0)))
        if texture is not None or part.shine > 0.0 or part.emission > 0.0:
            geom["material"] = _material(spec, part, texture, emission, materials)
        else:
            geom["rgba"] = part.rgba
        spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name, **geom)
        added += 1
    return added
