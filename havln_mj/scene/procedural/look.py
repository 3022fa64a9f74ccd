"""The look of a procedural house: its visual mesh and the object instance of every part.

The exact boxes (``boxes.json``) stay the house's collision and navigation geometry; the
look only draws on them. Floors, walls and ceilings are the boxes themselves, textured per
room; furniture is drawn from primitives inside each item's boxes
(:mod:`~havln_mj.scene.procedural.furniture`); trims, doors, windows, lamps, pictures,
rugs and shading overlays lie within a few centimetres of the walls, floors and ceilings
(:mod:`~havln_mj.scene.procedural.dressing`).

The look has its own generator, seeded from the house's seed, so dressing a house never
changes its plan, furniture, viewpoints or graph.
"""

from __future__ import annotations

import numpy as np

from havln_mj.scene.matterport.categories import SceneLabels
from havln_mj.scene.mesh import MeshPart
from havln_mj.scene.procedural.build import SLAB, room_walls
from havln_mj.scene.procedural.dresser import Dresser
from havln_mj.scene.procedural.dressing import dress_rooms
from havln_mj.scene.procedural.furniture import draw_item
from havln_mj.scene.procedural.house import ProceduralHouse
from havln_mj.scene.procedural.materials import Palette
from havln_mj.scene.procedural.primitives import box

LOOK_SALT = 0x100C  # the look generator's seed is (house salt, seed, LOOK_SALT)


def _architecture(dresser: Dresser, house: ProceduralHouse) -> None:
    """Floors, walls and ceilings of every room."""
    plan, recipe, palette = house.plan, house.recipe, dresser.palette
    ceiling = palette.ceiling()
    for room in plan.rooms:
        floor = palette.floor(room.kind)
        wall = palette.wall(room.kind, room.index)
        x0, y0, x1, y1 = room.x0, room.y0, room.x1, room.y1
        h = plan.wall_height
        dresser.add(dresser.instance("floor", "floor", room.index), floor, box(
            [x0, y0, -SLAB], [x1, y1, 0.0]))  # fmt: skip
        dresser.add(dresser.instance("ceiling", "ceiling", room.index), ceiling, box(
            [x0, y0, h], [x1, y1, h + SLAB]))  # fmt: skip
        wid = dresser.instance("wall", "wall", room.index)
        for lo, hi in room_walls(room, plan, recipe):
            dresser.add(wid, wall, box(lo, hi, bottom=lo[2] > 0.0, top=hi[2] < h))


def dress_house(house: ProceduralHouse) -> tuple[list[MeshPart], SceneLabels]:
    """The visual mesh of ``house`` and the labels of its parts.

    Returns:
        The mesh parts, one per (object instance, material), named
        ``"<instance>:<material>"``, and their labels (the instances with their mpcat40
        classes).
    """
    rng = np.random.default_rng(np.random.SeedSequence([0x4A5C, house.seed, LOOK_SALT]))
    dresser = Dresser(Palette(rng))
    _architecture(dresser, house)
    for k, item in enumerate(house.items):
        draw_item(dresser, item, k, house.recipe.furniture(item.name))
    dress_rooms(dresser, house)
    return dresser.parts()
