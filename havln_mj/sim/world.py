"""World builder: a scan becomes a MuJoCo model through ``mujoco.MjSpec``.

Visual geometry is the scan's mesh, one mesh geom per look (texture, colour, finish; group
``VISUAL``, no contacts): a CPU renderer pays per geom drawn, so a building's parts are
merged. In a building with a room plan (:mod:`havln_mj.scene.rooms`) they are merged per
look and room, so that frames leave out the rooms a camera cannot see
(:mod:`havln_mj.render.culling`). Label geometry (group ``render.labels.LABELS``, hidden
from cameras) holds one mesh per object instance of a scan that has labels, and people's
geoms are labelled, for the segmentation pass (:mod:`havln_mj.render.labels`). Collision
geometry (group ``COLLISION``, hidden from cameras) is the exact boxes of a procedural house,
or the CoACD convex decomposition of the mesh for scans without boxes. Lighting is a soft
headlight, a warm key light from above and a cool fill, all directional and without
shadows: MuJoCo's renderer lights per vertex, so lamps would not pool on large faces, and
each light or shadow map costs frame rate on a CPU. Windows and lamp shades glow by
emission instead.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from havln_mj import groups
from havln_mj.errors import InvalidArgumentError
from havln_mj.render.culling import rooms_tag
from havln_mj.render.labels import add_label_meshes, label_people
from havln_mj.render.texels import REACH_M, resolved_density
from havln_mj.robot.point_body import add_point_body
from havln_mj.scene.collision import CoacdParams, decompose
from havln_mj.scene.matterport.labelmesh import scan_label_meshes
from havln_mj.scene.mesh import MeshPart, merge_by_look
from havln_mj.scene.rooms import split_by_rooms
from havln_mj.scene.scan import Scan, floor_heights
from havln_mj.sim.visual import add_visual_parts, safe_name

if TYPE_CHECKING:
    import trimesh

    from havln_mj.humans.body import BodyShape
    from havln_mj.humans.skinned import Skin

COLLISION_MODES = ("auto", "boxes", "coacd", "none")
"""How a world's collision geometry can be made, ``auto`` (exact boxes where the scan has them,
else CoACD hulls of the mesh), ``boxes``, ``coacd``, or ``none``."""


@dataclass(frozen=True)
class WorldOptions:
    """How to build a world.

    Attributes:
        collision: "auto" (boxes when the scan has them, else CoACD), "boxes", "coacd" or
            "none".
        coacd: CoACD parameters for mesh decomposition.
        collision_band: Heights (below, above) each level's floor kept for CoACD collision.
        collision_chunk: Tile size (m) for CoACD pieces when the scan has no regions.
        offscreen: (width, height) of the offscreen buffer (renderers enlarge it as needed).
        vfov_deg: Vertical field of view of the agent camera.
        people_style: How people are drawn: ``"pieces"`` (dressed bodies as rigid pieces
            on their joints; the default, no per-frame upload), ``"skinned"`` (the same
            bodies skinned every frame) or ``"capsules"`` (mannequins).
        texel_reach_m: Textures keep the detail an ``offscreen``-sized frame at ``vfov_deg``
            resolves on a surface this far away (metres); finer ones are halved at build
            (:mod:`havln_mj.render.texels`). None keeps every texture as it is.
        labels: Whether the scan's label meshes are built (segmentation needs them); a
            world that never renders labels leaves out this copy of the building.
    """

    collision: str = "auto"
    coacd: CoacdParams = field(default_factory=CoacdParams)
    collision_band: tuple[float, float] = (-0.3, 2.2)
    collision_chunk: float = 6.0
    offscreen: tuple[int, int] = (640, 480)
    vfov_deg: float = 60.0
    people_style: str = "pieces"
    texel_reach_m: float | None = REACH_M
    labels: bool = True

    def __post_init__(self) -> None:
        if self.collision not in COLLISION_MODES:
            raise InvalidArgumentError(
                f"collision mode {self.collision!r} unknown; valid: {', '.join(COLLISION_MODES)}"
            )
        from havln_mj.humans.mujoco_people import DRAW_STYLES  # people: not on import

        if self.people_style not in DRAW_STYLES:
            raise InvalidArgumentError(
                f"people style {self.people_style!r} unknown; valid: {', '.join(DRAW_STYLES)}"
            )
        reach = self.texel_reach_m
        if reach is not None and not (isinstance(reach, int | float) and reach > 0.0):
            raise InvalidArgumentError(
                f"texel_reach_m must be a positive number of metres or None, got {reach!r}"
            )

    def texel_limit(self) -> float | None:
        """Texels per metre a texture keeps at most (None: textures are kept as they are)."""
        if self.texel_reach_m is None:
            return None
        return resolved_density(int(self.offscreen[1]), self.vfov_deg, self.texel_reach_m)


@dataclass(frozen=True)
class World:
    """A compiled world and how it was made."""

    model: mujoco.MjModel
    scan: Scan
    collision: str  # "boxes", "coacd" or "none"
    n_collision_geoms: int
    build_seconds: float


def _add_mesh_geom(
    spec: mujoco.MjSpec, name: str, vertices: np.ndarray, faces: np.ndarray, **geom: object
) -> None:
    """Adds a mesh asset and a world geom showing it, both called ``name``."""
    spec.add_mesh(
        name=name,
        uservert=vertices.astype(np.float32).ravel(),
        userface=faces.ravel(),
        inertia=mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL,  # open meshes have no volume
    )
    spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name, **geom)


def _add_boxes(spec: mujoco.MjSpec, scan: Scan) -> int:
    boxes = scan.boxes
    assert boxes is not None
    for k in range(len(boxes)):
        spec.worldbody.add_geom(
            name=f"collision/{boxes.kind[k]}_{k}",
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=(boxes.hi[k] - boxes.lo[k]) / 2,
            pos=(boxes.hi[k] + boxes.lo[k]) / 2,
            group=groups.COLLISION,
            rgba=(0.8, 0.3, 0.3, 0.3),
        )
    return len(boxes)


def _slice_box(mesh: trimesh.Trimesh, lo: np.ndarray, hi: np.ndarray) -> trimesh.Trimesh:
    """The part of ``mesh`` inside the axis-aligned box [lo, hi] (open cuts, no caps)."""
    import trimesh  # a large import: only when a mesh is decomposed

    for axis in range(3):
        for sign, value in ((1.0, lo[axis]), (-1.0, hi[axis])):
            normal = np.zeros(3)
            normal[axis] = sign
            origin = np.zeros(3)
            origin[axis] = value
            mesh = trimesh.intersections.slice_mesh_plane(mesh, normal, origin)
            if len(mesh.faces) == 0:
                return mesh
    return mesh


def collision_chunks(scan: Scan, band: tuple[float, float], chunk: float) -> list[trimesh.Trimesh]:
    """The mesh cut into pieces for convex decomposition, one per region (or grid tile).

    Each level keeps only ``band`` metres around its floor: geometry a ground robot can touch.
    Cutting off ceilings also opens each storey, so CoACD does not read a closed building as
    one solid block, and small pieces keep thin walls that a whole-house remesh would lose.
    Pieces are regions grown by 0.25 m when the scan has regions, else ``chunk``-metre tiles.
    """
    mesh = scan.mesh
    pieces = []
    for z in floor_heights(scan):
        z_lo, z_hi = z + band[0], z + band[1]
        boxes = []
        if scan.regions is not None:
            for rg in scan.regions.regions:
                if abs(scan.regions.levels[rg.level].z_floor - z) < 0.5:
                    boxes.append((rg.polygon.min(axis=0) - 0.25, rg.polygon.max(axis=0) + 0.25))
        if not boxes:
            xy_lo, xy_hi = mesh.bounds[0, :2], mesh.bounds[1, :2]
            n = np.maximum(1, np.ceil((xy_hi - xy_lo) / chunk)).astype(int)
            size = (xy_hi - xy_lo) / n
            boxes = [
                (xy_lo + size * (i, j), xy_lo + size * (i + 1, j + 1))
                for i in range(n[0])
                for j in range(n[1])
            ]
        for lo, hi in boxes:
            piece = _slice_box(mesh, np.array([lo[0], lo[1], z_lo]), np.array([hi[0], hi[1], z_hi]))
            if len(piece.faces):
                pieces.append(piece)
    return pieces


def _add_hulls(spec: mujoco.MjSpec, scan: Scan, options: WorldOptions) -> int:
    # One decomposition (and one cache entry) per piece: a re-run is instant and a crash
    # loses at most one piece.
    pieces = collision_chunks(scan, options.collision_band, options.collision_chunk)
    hulls = [h for piece in pieces for h in decompose(piece, options.coacd)]
    for k, hull in enumerate(hulls):
        _add_mesh_geom(
            spec,
            f"collision/hull_{k}",
            hull.vertices,
            hull.faces,
            group=groups.COLLISION,
            rgba=(0.3, 0.3, 0.8, 0.3),
        )
    return len(hulls)


def visual_parts(scan: Scan) -> list[MeshPart]:
    """The scan's visual parts: one per look, and per room where the scan has a room plan.

    A part split by room carries its rooms in its name (:func:`~havln_mj.render.culling.rooms_tag`),
    so a frame can leave out the rooms its camera cannot see.
    """
    parts = merge_by_look(scan.mesh_parts)
    plan = scan.room_plan
    if plan is None:
        return parts
    return [
        replace(part, name=part.name + rooms_tag(rooms))
        for rooms, part in split_by_rooms(parts, plan)
    ]


def world_spec(scan: Scan, options: WorldOptions | None = None) -> tuple[mujoco.MjSpec, str, int]:
    """The uncompiled world: building, lights and the point-body agent with its camera.

    Callers add bodies (robots, props, people) to the spec before compiling it, then call
    :func:`havln_mj.render.labels.label_people` so people segment as people;
    ``build_world`` is this plus people, their labels and ``compile``.

    Returns:
        (spec, collision mode used, number of collision geoms).
    """
    options = options or WorldOptions()
    spec = mujoco.MjSpec()
    spec.modelname = safe_name(scan.scene_id)
    spec.compiler.degree = False
    spec.option.gravity = (0.0, 0.0, -9.81)
    # MuJoCo's sleep feature treats the world body as asleep, so the poses of the building's
    # thousands of static geoms are computed once instead of every step (a graph proxy has up
    # to ~12k boxes: most of a step's time went there). Actuated trees (the GO1) never sleep;
    # mocap bodies (people) move as before; a passive free body may sleep while at rest.
    spec.option.enableflags |= mujoco.mjtEnableBit.mjENBL_SLEEP
    spec.visual.global_.offwidth = int(options.offscreen[0])
    spec.visual.global_.offheight = int(options.offscreen[1])
    spec.visual.headlight.ambient = (0.4, 0.4, 0.4)
    spec.visual.headlight.diffuse = (0.3, 0.3, 0.3)
    spec.visual.headlight.specular = (0.08, 0.08, 0.08)
    spec.visual.quality.shadowsize = 0
    # Capsules and spheres (people) tessellated coarser than MuJoCo's default 28 × 16: on a
    # CPU renderer this more than doubles the frame rate with people in view.
    spec.visual.quality.numslices = 12
    spec.visual.quality.numstacks = 6
    # A key light from above and a weaker fill from below, so floors, walls and ceilings all
    # read clearly without shadows.
    for name, direction, level in (
        ("sun", (0.3, 0.2, -1.0), 0.5),
        ("fill", (-0.2, -0.3, 1.0), 0.25),
    ):
        spec.worldbody.add_light(
            name=name,
            type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL,
            dir=direction,
            diffuse=(level, level, level * 0.95),
            specular=(0.0, 0.0, 0.0),
            castshadow=False,
        )
    add_visual_parts(spec, visual_parts(scan), texel_limit=options.texel_limit())
    if options.labels:
        add_label_meshes(spec, scan_label_meshes(scan))
    mode = options.collision
    if mode == "auto":
        mode = "boxes" if scan.boxes is not None else "coacd"
    if mode == "boxes" and scan.boxes is None:
        raise InvalidArgumentError(
            f"scan {scan.scene_id!r} has no boxes.json; use collision 'coacd'"
        )
    n = 0
    if mode == "boxes":
        n = _add_boxes(spec, scan)
    elif mode == "coacd":
        n = _add_hulls(spec, scan, options)
    add_point_body(spec, options.vfov_deg)
    return spec, mode, n


def build_world(
    scan: Scan,
    options: WorldOptions | None = None,
    people: Sequence[BodyShape] = (),
    skins: Sequence[Skin | None] = (),
) -> World:
    """Compiles a scan into a MuJoCo model with the point-body agent and its camera.

    Args:
        scan: The building.
        options: Build options (collision mode, CoACD parameters, buffer size, camera FOV).
        people: Bodies of the scene's people (mocap bodies ``human<k>/<joint>``, parked
            until posed; see :mod:`havln_mj.humans.mujoco_people`).
        skins: Per person, an SMPL skin to draw instead of the built-in body (or None).

    Returns:
        The compiled world.
    """
    from havln_mj.humans.mujoco_people import add_people  # people: not on import

    t0 = time.perf_counter()
    options = options or WorldOptions()
    spec, mode, n = world_spec(scan, options)
    add_people(
        spec, list(people), skins, style=options.people_style, texel_limit=options.texel_limit()
    )
    label_people(spec)
    model = spec.compile()
    return World(model, scan, mode, n, time.perf_counter() - t0)
