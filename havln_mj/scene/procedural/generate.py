"""``proc-<seed>``: a procedural house drawn from its seed and written as a scan folder."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from havln_mj.cache import atomic_write_json
from havln_mj.errors import InvalidArgumentError
from havln_mj.scene.connectivity import Connectivity, write_connectivity
from havln_mj.scene.mesh import write_glb
from havln_mj.scene.procedural.build import house_boxes
from havln_mj.scene.procedural.furnish import Item, door_keepouts, furnish_room, inner_rect
from havln_mj.scene.procedural.house import ProceduralHouse
from havln_mj.scene.procedural.layout import plan_house
from havln_mj.scene.procedural.look import dress_house
from havln_mj.scene.procedural.materials import library_digest
from havln_mj.scene.procedural.recipe import Recipe, load_recipe
from havln_mj.scene.procedural.viewpoints import place_viewpoints, room_is_passable
from havln_mj.scene.regions import Level, Region, Regions, SceneObject
from havln_mj.scene.scanfolder import BOXES, CONNECTIVITY, MESH_GLB, META, REGIONS, SEMANTICS

# Bump when generator code changes what a seed produces: cached scans are rebuilt.
GENERATOR_VERSION = 2


def _camera_pose(position: np.ndarray) -> np.ndarray:
    """Matterport skybox camera-to-world pose facing +y (x right, y down, z look)."""
    pose = np.array([[1.0, 0, 0, 0], [0, 0, 1, 0], [0, -1, 0, 0], [0, 0, 0, 1]])
    pose[:3, 3] = position
    return pose


def generate_house(
    seed: int, recipe: Recipe | None = None, area: float | None = None
) -> ProceduralHouse:
    """Draws the house of ``seed``: plan, furniture, boxes, viewpoints, graph and regions.

    Args:
        seed: Non-negative integer; the same seed always gives the same house.
        recipe: Procedural recipe; the built-in one by default.
        area: Target floor area in m² (default: drawn from the recipe's 40–250 m² range).

    Returns:
        The house, ready for ``write_scan``.
    """
    if not isinstance(seed, int | np.integer) or seed < 0:
        raise InvalidArgumentError(f"procedural seed must be a non-negative integer, got {seed!r}")
    recipe = recipe or load_recipe()
    rng = np.random.default_rng(np.random.SeedSequence([0x4A5C, int(seed)]))
    plan = plan_house(rng, recipe, area)
    size = (plan.width, plan.depth)
    inners = [inner_rect(room, size, recipe) for room in plan.rooms]
    walls = house_boxes(plan, recipe, []).of_kind("wall")
    items: list[Item] = []
    for room, inner in zip(plan.rooms, inners, strict=True):
        placed = furnish_room(rng, recipe, room, inner, door_keepouts(room, list(plan.doors)))
        # Furniture may not cut a room in two: drop the latest items until it is passable.
        while placed and not room_is_passable(recipe, plan, room, inner, placed, walls):
            placed.pop()
        items += placed
    boxes = house_boxes(plan, recipe, items)
    vg = place_viewpoints(rng, recipe, plan, inners, items, boxes)
    ids = tuple(rng.bytes(16).hex() for _ in range(len(vg.height)))
    scene_id = f"proc-{seed}"
    connectivity = Connectivity(
        ids=ids,
        poses=np.stack([_camera_pose(p) for p in vg.camera]),
        included=np.ones(len(ids), dtype=bool),
        visible=vg.visible,
        unobstructed=vg.unobstructed,
        heights=vg.height,
        source=scene_id,
    )
    h = plan.wall_height
    regions = Regions(
        levels=(Level(0, 0.0, h),),
        regions=tuple(
            Region(
                index=r.index,
                level=0,
                label=r.kind,
                polygon=np.array([[r.x0, r.y0], [r.x1, r.y0], [r.x1, r.y1], [r.x0, r.y1]]),
                bbox=np.array([r.x0, r.y0, 0.0, r.x1, r.y1, h]),
                height=h,
            )
            for r in plan.rooms
        ),
        objects=tuple(
            SceneObject(k, it.room, it.name, it.mpcat40, it.bbox, it.yaw, it.seat_height)
            for k, it in enumerate(items)
        ),
        viewpoint_region={vp: int(r) for vp, r in zip(ids, vg.room, strict=True)},
    )
    return ProceduralHouse(
        scene_id, int(seed), plan, tuple(items), boxes, vg, connectivity, regions, recipe
    )


def write_scan(house: ProceduralHouse, folder: Path, *, with_boxes: bool = True) -> None:
    """Writes the scan folder: mesh, part labels, connectivity, regions, metadata (and boxes).

    Args:
        house: The generated house.
        folder: Target folder (created if missing).
        with_boxes: Also write ``boxes.json`` so the builder can use exact box collision;
            without it, the world builder decomposes the mesh with CoACD like a real scan.
    """
    folder.mkdir(parents=True, exist_ok=True)
    parts, labels = dress_house(house)
    write_glb(parts, folder / MESH_GLB)
    labels.write(folder / SEMANTICS)
    write_connectivity(folder / CONNECTIVITY, house.connectivity)
    house.regions.write(folder / REGIONS)
    if with_boxes:
        house.boxes.write(folder / BOXES)
    atomic_write_json(
        folder / META,
        {
            "scene_id": house.scene_id,
            "kind": "procedural",
            "seed": house.seed,
            "generator_version": GENERATOR_VERSION,
            "recipe": house.recipe_digest,
            "materials": library_digest(),
            "area_m2": round(house.area, 2),
        },
        indent=1,
    )
