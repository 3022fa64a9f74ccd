"""Boxes of a procedural house: floors, ceilings, walls with door openings, furniture parts."""

from __future__ import annotations

import numpy as np

from havln_mj.scene.boxes import BoxSet, interval_gaps
from havln_mj.scene.procedural.furnish import Item
from havln_mj.scene.procedural.layout import FloorPlan, Room
from havln_mj.scene.procedural.recipe import Recipe

SLAB = 0.1  # floor and ceiling thickness


def _wall_box(
    vertical: bool, n0: float, n1: float, a: float, b: float, z0: float, z1: float
) -> tuple[np.ndarray, np.ndarray]:
    """A wall box spanning [n0, n1] across the wall line and [a, b] along it."""
    if vertical:
        return np.array([n0, a, z0]), np.array([n1, b, z1])
    return np.array([a, n0, z0]), np.array([b, n1, z1])


def room_walls(room: Room, plan: FloorPlan, recipe: Recipe) -> list[tuple[np.ndarray, np.ndarray]]:
    """Wall and lintel boxes lining the inside of one room (each room paints its own side)."""
    t_in, t_out = recipe["interior_wall_half"], recipe["exterior_wall"]
    height = plan.wall_height
    outer = {
        "south": (room.y0, 0.0),
        "north": (room.y1, plan.depth),
        "west": (room.x0, 0.0),
        "east": (room.x1, plan.width),
    }
    thick = {s: t_out if abs(c - o) < 1e-6 else t_in for s, (c, o) in outer.items()}
    spans = {
        "south": (room.x0, room.x1),
        "north": (room.x0, room.x1),
        "west": (room.y0 + thick["south"], room.y1 - thick["north"]),
        "east": (room.y0 + thick["south"], room.y1 - thick["north"]),
    }
    boxes = []
    for side, (lo, hi) in spans.items():
        vertical = side in ("west", "east")
        coord = outer[side][0]
        holes = [
            (d.lo, d.hi, d.height)
            for d in plan.doors
            if room.index in (d.a, d.b) and d.vertical == vertical and abs(d.coord - coord) < 1e-6
        ]
        t = thick[side]
        n0, n1 = (coord, coord + t) if side in ("south", "west") else (coord - t, coord)

        for a, b in interval_gaps(lo, hi, [(h[0], h[1]) for h in holes]):
            boxes.append(_wall_box(vertical, n0, n1, a, b, 0.0, height))
        for a, b, door_h in holes:
            boxes.append(_wall_box(vertical, n0, n1, max(a, lo), min(b, hi), door_h, height))
    return boxes


def house_boxes(plan: FloorPlan, recipe: Recipe, items: list[Item]) -> BoxSet:
    """All boxes of the house, with kinds, material names and colours.

    Args:
        plan: The floor plan.
        recipe: The procedural recipe (colours, wall thickness).
        items: Placed furniture.

    Returns:
        The house geometry.
    """
    lo, hi, kind, material, rgba = [], [], [], [], []

    def add(b_lo: np.ndarray, b_hi: np.ndarray, k: str, mat: str, colour: list[float]) -> None:
        lo.append(b_lo)
        hi.append(b_hi)
        kind.append(k)
        material.append(mat)
        rgba.append(colour)

    ceiling = recipe["ceiling_rgba"]
    for room in plan.rooms:
        spec = recipe.room(room.kind)
        add(
            np.array([room.x0, room.y0, -SLAB]),
            np.array([room.x1, room.y1, 0.0]),
            "floor",
            f"floor_{room.kind}",
            spec["floor"],
        )
        add(
            np.array([room.x0, room.y0, plan.wall_height]),
            np.array([room.x1, room.y1, plan.wall_height + SLAB]),
            "ceiling",
            "ceiling",
            ceiling,
        )
        for b_lo, b_hi in room_walls(room, plan, recipe):
            add(b_lo, b_hi, "wall", f"wall_{room.kind}", spec["wall"])
    for item in items:
        for part in item.parts:
            hexcode = "".join(f"{round(c * 255):02x}" for c in part.rgba[:3])
            add(part.lo, part.hi, "furniture", f"furniture_{hexcode}", list(part.rgba))
    return BoxSet(
        np.array(lo, dtype=float),
        np.array(hi, dtype=float),
        tuple(kind),
        tuple(material),
        np.array(rgba, dtype=float),
    )
