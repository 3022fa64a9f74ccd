"""Furniture drawn from primitives inside each item's collision boxes.

An item is drawn in its local frame (footprint ``[-w/2, w/2] × [-d/2, d/2]``, back at +y,
z up from the floor; see :mod:`~havln_mj.scene.procedural.furnish`), then turned and moved
where the item stands. The drawing keeps to the item's boxes, save for soft details that
stand on them (pillows on a bed, a television on its stand, cabinets above a counter).

Builders return lists of pieces: ``(sub, material, solid)``; ``sub`` is None for the
item itself, or ``(category, key)`` for a part that is an object of its own (a throw pillow
is a cushion, books are objects, a dining chair is a chair), drawn as its own instance.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from havln_mj.scene.procedural import fittings
from havln_mj.scene.procedural.dresser import Dresser
from havln_mj.scene.procedural.furnish import Item
from havln_mj.scene.procedural.materials import Material, Palette
from havln_mj.scene.procedural.primitives import (
    Solid,
    box,
    cylinder,
    ellipsoid,
    frustum,
    rotation_z,
    rounded_box,
)

Piece = tuple[tuple[str, int] | None, Material, Solid]

# mpcat40 class of the sub-objects builders draw.
SUB_CLASSES = {
    "pillow": "cushion",
    "books": "objects",
    "boxes": "objects",
    "chair": "chair",
    "stand": "cabinet",
    "sink": "sink",
    "mirror": "mirror",
    "wall cabinet": "cabinet",
    "clothes": "clothes",
    "lamp": "lighting",
}


def legs(hw: float, hd: float, inset: float, top: float, mat: Material, r: float = 0.025) -> list:
    """Four round legs under the corners of a ``2hw × 2hd`` footprint."""
    return [
        (
            None,
            mat,
            cylinder(r, 0.0, top, 6).moved(np.eye(3), [sx * (hw - inset), sy * (hd - inset), 0]),
        )
        for sx in (-1, 1)
        for sy in (-1, 1)
    ]


def _sofa(p: Palette, w: float, d: float, h: float, spec: dict, room: int) -> list[Piece]:
    hw, hd, sh = w / 2, d / 2, spec.get("seat_height", 0.44)
    cloth, wood = p.fabric(f"room{room}"), p.wood(f"room{room}")
    out: list[Piece] = [
        (
            None,
            cloth,
            rounded_box([-hw + 0.1, -hd + 0.03, 0.08], [hw - 0.1, hd - 0.1, sh - 0.13], 0.03),
        ),
        (None, cloth, rounded_box([-hw, hd - 0.12, 0.08], [hw, hd, h - 0.02], 0.05)),
        *legs(hw, hd, 0.06, 0.08, wood, 0.022),
    ]
    for side in (-1, 1):
        x0, x1 = sorted((side * hw, side * (hw - 0.16)))
        out.append((None, cloth, rounded_box([x0, -hd + 0.01, 0.08], [x1, hd - 0.05, 0.62], 0.06)))
    n = max(1, round((w - 0.32) / 0.62))
    step = (w - 0.32) / n
    for k in range(n):
        x0 = -hw + 0.16 + k * step
        seat = rounded_box(
            [x0 + 0.005, -hd + 0.02, sh - 0.14], [x0 + step - 0.005, hd - 0.12, sh], 0.05
        )
        back = rounded_box(
            [x0 + 0.005, hd - 0.22, sh - 0.03], [x0 + step - 0.005, hd - 0.1, h - 0.06], 0.06
        )
        out += [(None, cloth, seat), (None, cloth, back)]
    if w > 1.4:
        for k, side in enumerate((-1, 1)):
            x = side * (hw - 0.4)
            pillow = rounded_box(
                [x - 0.2, hd - 0.34, sh - 0.02], [x + 0.2, hd - 0.2, sh + 0.34], 0.06
            )
            out.append((("pillow", k), p.accent(f"room{room}_{k}"), pillow))
    return out


def _dining_chair(
    x: float, seat_y: tuple, back_y: tuple, sh: float, wood: Material, seat: Material
) -> list[tuple[Material, Solid]]:
    """A dining chair at ``x``: seat over ``seat_y``, back posts and rail over ``back_y``."""
    hw, (y0, y1), (b0, b1) = 0.21, seat_y, back_y
    yc, hd = (y0 + y1) / 2, (y1 - y0) / 2
    out = [(wood, solid.moved(np.eye(3), [x, yc, 0])) for _, _, solid in
           legs(hw, hd, 0.03, sh - 0.04, wood, 0.018)]  # fmt: skip
    out.append((seat, rounded_box([x - hw, y0, sh - 0.05], [x + hw, y1, sh], 0.02)))
    out.append((wood, box([x - hw, b0, 0.0], [x - hw + 0.04, b1, 0.95])))
    out.append((wood, box([x + hw - 0.04, b0, 0.0], [x + hw, b1, 0.95])))
    out.append((wood, box([x - hw, b0, 0.72], [x + hw, b1, 0.95])))
    return out


def _chair(p: Palette, w: float, d: float, h: float, spec: dict, room: int) -> list[Piece]:
    hw, hd, sh = w / 2, d / 2, spec.get("seat_height", 0.46)
    black, cloth = p.metal("black"), p.fabric(f"room{room}")
    out: list[Piece] = [(None, black, cylinder(0.025, 0.08, sh - 0.05))]
    for k in range(5):
        a = 2 * np.pi * k / 5
        rot = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
        out.append(
            (
                None,
                black,
                box([0.0, -0.015, 0.05], [min(hw, hd) - 0.03, 0.015, 0.08]).moved(rot, [0, 0, 0]),
            )
        )
        out.append(
            (
                None,
                black,
                cylinder(0.025, 0.0, 0.05).moved(np.eye(3), rot @ [min(hw, hd) - 0.05, 0, 0]),
            )
        )
    out.append(
        (
            None,
            cloth,
            rounded_box([-hw + 0.02, -hd + 0.02, sh - 0.08], [hw - 0.02, hd - 0.1, sh], 0.04),
        )
    )
    out.append((None, black, box([-0.03, hd - 0.1, sh - 0.06], [0.03, hd - 0.04, sh + 0.2])))
    out.append(
        (
            None,
            cloth,
            rounded_box(
                [-hw + 0.04, hd - 0.07, sh + 0.12], [hw - 0.04, hd - 0.005, h - 0.01], 0.04
            ),
        )
    )
    return out


def _table(
    p: Palette, w: float, d: float, h: float, spec: dict, room: int, name: str
) -> list[Piece]:
    hw, hd = w / 2, d / 2
    wood = p.wood(f"room{room}")
    if name == "pool_table":
        felt = p.plain("felt", (0.12, 0.45, 0.24))
        return [
            (None, wood, box([-hw, -hd, h - 0.16], [hw, hd, h - 0.02])),
            (None, felt, box([-hw + 0.1, -hd + 0.1, h - 0.02], [hw - 0.1, hd - 0.1, h - 0.01])),
            *[
                (None, wood, s)
                for s in (
                    box([-hw, -hd, h - 0.02], [hw, -hd + 0.1, h]),
                    box([-hw, hd - 0.1, h - 0.02], [hw, hd, h]),
                    box([-hw, -hd, h - 0.02], [-hw + 0.1, hd, h]),
                    box([hw - 0.1, -hd, h - 0.02], [hw, hd, h]),
                )
            ],
            *legs(hw, hd, 0.15, h - 0.16, wood, 0.07),
        ]
    top = 0.05 if name == "workbench" else 0.035
    out: list[Piece] = [(None, wood, box([-hw, -hd, h - top], [hw, hd, h]))]
    out += [
        (None, wood, s)
        for s in (
            box([-hw + 0.05, -hd + 0.05, h - top - 0.08], [hw - 0.05, -hd + 0.07, h - top]),
            box([-hw + 0.05, hd - 0.07, h - top - 0.08], [hw - 0.05, hd - 0.05, h - top]),
        )
    ]
    out += legs(hw, hd, 0.06, h - top, wood, 0.028 if name != "coffee_table" else 0.03)
    if name in ("coffee_table", "workbench"):
        out.append((None, wood, box([-hw + 0.06, -hd + 0.06, 0.1], [hw - 0.06, hd - 0.06, 0.13])))
    if name == "desk":  # a drawer pedestal under one end
        front = p.painted(f"room{room}")
        out.append((None, wood, box([hw - 0.45, -hd + 0.04, 0.0], [hw - 0.04, hd - 0.04, h - top])))
        for k in range(3):
            z = 0.06 + k * (h - top - 0.08) / 3
            out.append(
                (
                    None,
                    front,
                    box(
                        [hw - 0.44, -hd + 0.035, z],
                        [hw - 0.05, -hd + 0.04, z + (h - top - 0.08) / 3 - 0.015],
                    ),
                )
            )
    return out


def _dining(p: Palette, w: float, d: float, h: float, spec: dict, room: int) -> list[Piece]:
    """A table with chairs along both long sides, where the recipe's boxes put them."""
    sh = spec.get("seat_height", 0.46)
    tw, td = w, d - 1.0
    out = _table(p, tw, td, h, spec, room, "dining_table")
    wood, seat = p.wood(f"room{room}"), p.fabric(f"room{room}")
    n = max(1, int(tw // 0.6))
    k = 0
    for i in range(n):
        x = -tw / 2 + (i + 0.5) * tw / n
        for sy in (-1, 1):
            y0, y1 = sorted((sy * (td / 2 + 0.05), sy * (td / 2 + 0.5)))
            back = (y1 - 0.05, y1) if sy > 0 else (y0, y0 + 0.05)
            seat_y = (y0, y1 - 0.06) if sy > 0 else (y0 + 0.06, y1)
            for mat, solid in _dining_chair(x, seat_y, back, sh, wood, seat):
                out.append((("chair", k), mat, solid))
            k += 1
    return out


def _bed(p: Palette, w: float, d: float, h: float, spec: dict, room: int) -> list[Piece]:
    hw, hd, sh = w / 2, d / 2, spec.get("seat_height", 0.48)
    wood = p.wood(f"room{room}")
    sheet, cover = (
        p.fabric(f"room{room}_sheet", "bedding"),
        p.fabric(f"room{room}_cover", "bedding"),
    )
    out: list[Piece] = [
        (None, wood, box([-hw, -hd, 0.12], [hw, hd - 0.08, 0.3])),
        *legs(hw, hd - 0.04, 0.05, 0.12, wood, 0.03),
        (
            None,
            sheet,
            rounded_box([-hw + 0.03, -hd + 0.03, 0.28], [hw - 0.03, hd - 0.1, sh - 0.04], 0.05),
        ),
        (
            None,
            cover,
            rounded_box([-hw + 0.01, -hd + 0.01, sh - 0.2], [hw - 0.01, hd - 0.62, sh], 0.05),
        ),
        (None, wood, box([-hw, hd - 0.08, 0.0], [hw, hd, h])),
    ]
    count = 2 if w > 1.2 else 1
    for k in range(count):
        x0 = -hw + 0.08 + k * (w - 0.16) / count
        x1 = x0 + (w - 0.16) / count - 0.04
        pillow = rounded_box([x0, hd - 0.52, sh - 0.06], [x1, hd - 0.14, sh + 0.08], 0.06)
        out.append((("pillow", k), sheet, pillow))
    return out


def _tv(p: Palette, w: float, d: float, h: float, spec: dict, room: int) -> list[Piece]:
    hw, hd = w / 2, d / 2
    wood, front = p.wood(f"room{room}"), p.painted(f"room{room}")
    screen = p.plain("screen", (0.03, 0.03, 0.035), shine=0.9)
    bezel = p.plain("bezel", (0.08, 0.08, 0.09), shine=0.4)
    sw = 0.8 * w
    out: list[Piece] = [
        (("stand", 0), wood, box([-hw, -hd, 0.06], [hw, hd, 0.5])),
        (
            ("stand", 0),
            p.metal("black"),
            box([-hw + 0.03, -hd + 0.03, 0.0], [hw - 0.03, hd - 0.03, 0.06]),
        ),
        (("stand", 0), front, box([-hw + 0.03, -hd - 0.005, 0.1], [-0.01, -hd, 0.46])),
        (("stand", 0), front, box([0.01, -hd - 0.005, 0.1], [hw - 0.03, -hd, 0.46])),
        (None, bezel, box([-0.08, -0.1, 0.5], [0.08, 0.1, 0.52])),
        (None, bezel, box([-0.03, -0.01, 0.52], [0.03, 0.02, 0.62])),
        (None, bezel, box([-sw / 2, -0.03, 0.58], [sw / 2, 0.03, h])),
        (None, screen, box([-sw / 2 + 0.015, -0.035, 0.595], [sw / 2 - 0.015, -0.03, h - 0.015])),
    ]
    return out


def _toilet(p: Palette, w: float, d: float, h: float, spec: dict, room: int) -> list[Piece]:
    hw, hd, sh = w / 2, d / 2, spec.get("seat_height", 0.42)
    white = p.ceramic()
    cy = -hd + (d - 0.18) / 2 - 0.03
    squash = np.diag([1.0, 1.25, 1.0])
    bowl = frustum(0.11, 0.17, 0.0, sh - 0.05, 14).moved(squash, [0, cy, 0])
    rim = ellipsoid([0.18, 0.18, 0.05], 14, 6).moved(squash, [0, cy, sh - 0.05])
    return [
        (None, white, bowl),
        (None, white, rim),
        (
            None,
            white,
            rounded_box([-hw + 0.02, cy - 0.2, sh - 0.03], [hw - 0.02, hd - 0.17, sh], 0.015),
        ),
        (None, white, rounded_box([-hw, hd - 0.17, 0.4], [hw, hd, h], 0.03)),
        (None, white, box([-0.09, hd - 0.2, 0.0], [0.09, hd - 0.05, 0.42])),
        (None, p.metal("steel"), box([-0.03, hd - 0.12, h], [0.03, hd - 0.06, h + 0.008])),
    ]


_BUILDERS: dict[str, Callable[..., list[Piece]]] = {
    "sofa": _sofa,
    "chair": _chair,
    "dining": _dining,
    "bed": _bed,
    "tv": _tv,
    "toilet": _toilet,
}


def item_pieces(palette: Palette, item: Item, spec: dict[str, Any]) -> list[Piece]:
    """The pieces of ``item`` in its local frame (see the module docstring)."""
    w, d, h = spec["size"]
    shape = spec["shape"]
    if shape == "table":
        return _table(palette, w, d, h, spec, item.room, item.name)
    if shape in _BUILDERS:
        return _BUILDERS[shape](palette, w, d, h, spec, item.room)
    return fittings.block_pieces(palette, item.name, w, d, h, spec, item.room)


def draw_item(dresser: Dresser, item: Item, index: int, spec: dict[str, Any]) -> None:
    """Draws ``item`` (object ``index`` of the house) into ``dresser`` where it stands."""
    bbox = item.bbox
    centre = np.array([(bbox[0] + bbox[3]) / 2, (bbox[1] + bbox[4]) / 2, 0.0])
    turn = rotation_z(round(item.yaw / (np.pi / 2)))
    main = dresser.instance(item.name.replace("_", " "), item.mpcat40, item.room, index)
    subs: dict[tuple[str, int], int] = {}
    for sub, material, solid in item_pieces(dresser.palette, item, spec):
        iid = main
        if sub is not None:
            if sub not in subs:
                subs[sub] = dresser.instance(sub[0], SUB_CLASSES[sub[0]], item.room, index)
            iid = subs[sub]
        dresser.add(iid, material, solid.moved(turn, centre))
