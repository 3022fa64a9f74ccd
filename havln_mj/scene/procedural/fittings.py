"""Furniture whose collision is one block, drawn from primitives in the item's local frame.

Storage, kitchen and bathroom fittings, appliances, gym equipment and plants.

See :mod:`~havln_mj.scene.procedural.furniture` for the frame and the piece format. Every
builder draws inside the block ``[-w/2, w/2] × [-d/2, d/2] × [0, h]``, except wall
cabinets and a mirror, which hang above a counter or a basin on the wall behind it.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from typing import Any

import numpy as np

from havln_mj.scene.procedural.materials import Material, Palette
from havln_mj.scene.procedural.primitives import (
    Solid,
    box,
    cylinder,
    ellipsoid,
    frustum,
    merge,
    rounded_box,
)

Piece = tuple[tuple[str, int] | None, Material, Solid]
_I = np.eye(3)
_ALONG_X = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # z axis -> x axis
_ALONG_Y = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # z axis -> -y axis


def _fronts(x0: float, x1: float, z0: float, z1: float, y: float, cols: int, rows: int) -> Solid:
    """A grid of door or drawer fronts standing 1 cm proud of the face at ``y`` (facing -y)."""
    gap = 0.006
    cells = []
    for i in range(cols):
        for j in range(rows):
            a, b = x0 + (x1 - x0) * i / cols + gap, x0 + (x1 - x0) * (i + 1) / cols - gap
            c, e = z0 + (z1 - z0) * j / rows + gap, z0 + (z1 - z0) * (j + 1) / rows - gap
            cells.append(box([a, y - 0.01, c], [b, y, e]))
    return merge(cells)


def _knobs(x0: float, x1: float, z0: float, z1: float, y: float, cols: int, rows: int) -> Solid:
    """One small handle per front of a :func:`_fronts` grid."""
    out = []
    for i in range(cols):
        for j in range(rows):
            x = x0 + (x1 - x0) * (i + 0.5) / cols
            z = z0 + (z1 - z0) * (j + (0.8 if rows == 1 else 0.5)) / rows
            out.append(box([x - 0.05, y - 0.03, z - 0.008], [x + 0.05, y - 0.01, z + 0.008]))
    return merge(out)


def _case(p: Palette, key: str, w: float, d: float, h: float, cols: int, rows: int,
          plinth: float = 0.08) -> list[Piece]:  # fmt: skip
    """A carcass on a recessed plinth with a grid of fronts and handles (cabinets, drawers)."""
    hw, hd = w / 2, d / 2
    fy = -hd + 0.03  # the carcass face: fronts and handles stand in front of it, inside d
    body, front = p.wood(key), p.painted(key)
    return [
        (None, body, box([-hw, fy, plinth], [hw, hd, h])),
        (
            None,
            p.metal("black"),
            box([-hw + 0.04, fy + 0.04, 0.0], [hw - 0.04, hd - 0.02, plinth]),
        ),
        (None, front, _fronts(-hw, hw, plinth, h - 0.02, fy, cols, rows)),
        (None, p.metal("steel"), _knobs(-hw, hw, plinth, h - 0.02, fy, cols, rows)),
    ]


def _shelves(p: Palette, name: str, w: float, d: float, h: float, room: int) -> list[Piece]:
    hw, hd = w / 2, d / 2
    wood = p.wood(f"room{room}") if name == "bookshelf" else p.painted(f"shelf{room}")
    out: list[Piece] = [
        (None, wood, box([-hw, -hd, 0.0], [-hw + 0.025, hd, h])),
        (None, wood, box([hw - 0.025, -hd, 0.0], [hw, hd, h])),
        (None, wood, box([-hw, hd - 0.015, 0.0], [hw, hd, h])),
    ]
    levels = np.linspace(0.04, h - 0.025, max(3, int(h / 0.36)))
    books = p.image("books", "books", 256)
    boxes = p.fabric(f"boxes{room}")
    for z in levels:
        out.append((None, wood, box([-hw, -hd, z - 0.025], [hw, hd, z])))
    for k, (z, above) in enumerate(itertools.pairwise(levels)):
        gap, x = above - z - 0.065, -hw + 0.03
        while x < hw - 0.12 and gap > 0.12:
            span = min(float(p.rng.uniform(0.2, 0.5)), hw - 0.03 - x)
            if p.rng.random() < 0.7:
                if name == "bookshelf":  # the spines image spans 0.4 m by 0.28 m
                    block = box([0, 0, 0], [span, d - 0.06, min(0.28, gap)])
                    block = Solid(block.vertices, block.faces, block.uv / [0.4, 0.28])
                    out.append((("books", k), books, block.moved(_I, [x, -hd + 0.03, z])))
                else:
                    block = box([0, 0, 0], [span, d - 0.08, 0.7 * gap])
                    out.append((("boxes", k), boxes, block.moved(_I, [x, -hd + 0.04, z])))
            x += span + 0.02
    return out


def _plant(p: Palette, w: float, d: float, h: float) -> list[Piece]:
    r = min(w, d) / 2
    pot = p.plain(f"pot{int(p.rng.integers(3))}", p.lib["pots"][int(p.rng.integers(3))], 0.3)
    foliage = p.image("leaves", "leaves", 128)
    out: list[Piece] = [
        (None, pot, frustum(0.6 * r, 0.85 * r, 0.0, 0.3 * h)),
        (
            None,
            p.plain("soil", (0.22, 0.16, 0.11)),
            cylinder(0.8 * r, 0.3 * h - 0.03, 0.3 * h - 0.01),
        ),
        (None, p.wood("stem"), cylinder(0.03, 0.3 * h - 0.02, 0.7 * h, 6)),
    ]
    for k in range(3):
        c = [p.rng.uniform(-0.3, 0.3) * r, p.rng.uniform(-0.3, 0.3) * r, (0.62 + 0.12 * k) * h]
        radii = [0.65 * r, 0.65 * r, (0.22 - 0.03 * k) * h]
        out.append((None, foliage, ellipsoid(radii, 10, 6).moved(_I, c)))
    return out


def _counter(p: Palette, name: str, w: float, d: float, h: float, room: int) -> list[Piece]:
    hw, hd = w / 2, d / 2
    out = _case(p, f"kitchen{room}", w, d - 0.03, h - 0.04, max(1, round(w / 0.6)), 1, 0.1)
    out = [(s, m, solid.moved(_I, [0, -0.015, 0])) for s, m, solid in out]
    top = p.stone(f"top{room}") if name == "counter" else p.wood(f"bar{room}")
    out.append((None, top, box([-hw, -hd, h - 0.04], [hw, hd, h])))
    if name == "counter" and w >= 1.5:
        steel = p.metal("steel")
        out.append(
            (("sink", 0), steel, box([-0.3, -hd + 0.08, h - 0.002], [0.3, hd - 0.1, h + 0.004]))
        )
        out.append(
            (
                ("sink", 0),
                p.plain("basin", (0.35, 0.36, 0.38), 0.6),
                box([-0.26, -hd + 0.12, h + 0.004], [0.26, hd - 0.14, h + 0.006]),
            )
        )
        out.append((("sink", 0), steel, cylinder(0.015, h, h + 0.3).moved(_I, [0, hd - 0.06, 0])))
        out.append(
            (("sink", 0), steel, box([-0.012, hd - 0.26, h + 0.27], [0.012, hd - 0.06, h + 0.3]))
        )
        wall = _case(p, f"kitchen{room}", w, 0.34, 0.7, max(1, round(w / 0.6)), 1, 0.0)
        for _, mat, solid in wall:
            out.append((("wall cabinet", 0), mat, solid.moved(_I, [0, hd - 0.17, 1.45])))
    return out


def _appliance(p: Palette, name: str, w: float, d: float, h: float) -> list[Piece]:
    hw, hd = w / 2, d / 2
    white, steel, black = (
        p.plain("enamel", (0.93, 0.93, 0.94), 0.5),
        p.metal("steel"),
        p.metal("black"),
    )
    shell = steel if name == "fridge" else white
    fy = -hd + 0.04  # the front: doors, handles and dials stand in front of it, inside d
    out: list[Piece] = [(None, shell, rounded_box([-hw, fy, 0.02], [hw, hd, h], 0.02))]
    out.append((None, black, box([-hw + 0.03, -hd + 0.03, 0.0], [hw - 0.03, hd - 0.03, 0.02])))
    if name == "fridge":
        out.append(
            (None, black, box([-hw + 0.01, fy - 0.002, 0.62 * h], [hw - 0.01, fy, 0.63 * h]))
        )
        for z0, z1 in ((0.66 * h, 0.8 * h), (0.35 * h, 0.58 * h)):
            out.append((None, steel, box([-hw + 0.05, fy - 0.04, z0], [-hw + 0.07, fy, z1])))
    elif name == "stove":
        glass = p.plain("oven glass", (0.06, 0.06, 0.07), 0.8)
        out.append((None, glass, box([-hw + 0.06, fy - 0.004, 0.12], [hw - 0.06, fy, h - 0.2])))
        out.append(
            (
                None,
                steel,
                box([-hw + 0.08, fy - 0.04, h - 0.17], [hw - 0.08, fy - 0.01, h - 0.15]),
            )
        )
        out.append(
            (None, black, box([-hw + 0.01, -hd + 0.01, h], [hw - 0.01, hd - 0.01, h + 0.01]))
        )
        for sx in (-1, 1):
            for sy in (-1, 1):
                ring = cylinder(0.085, h + 0.01, h + 0.025, 14)
                out.append((None, black, ring.moved(_I, [sx * hw / 2, sy * hd / 2.2, 0])))
    else:  # washer / dryer: a round door and a control strip
        glass = p.plain("porthole", (0.25, 0.3, 0.35), 0.8)
        door = cylinder(0.2, -0.005, 0.015, 20).moved(_ALONG_Y, [0, fy, 0.42])
        out.append((None, p.plain("door ring", (0.7, 0.71, 0.73), 0.5), door))
        inner = cylinder(0.15, 0.0, 0.02, 20).moved(_ALONG_Y, [0, fy - 0.004, 0.42])
        out.append((None, glass, inner))
        out.append(
            (None, black, box([-hw + 0.04, fy - 0.004, h - 0.14], [hw - 0.04, fy, h - 0.04]))
        )
    return out


def _bath(p: Palette, name: str, w: float, d: float, h: float, room: int) -> list[Piece]:
    hw, hd = w / 2, d / 2
    white, steel = p.ceramic(), p.metal("steel")
    if name == "bathtub":
        water = p.plain("bath inside", (0.82, 0.88, 0.9), 0.8)
        return [
            (None, white, rounded_box([-hw, -hd, 0.0], [hw, hd, h], 0.04)),
            (
                None,
                water,
                rounded_box(
                    [-hw + 0.08, -hd + 0.08, h - 0.01], [hw - 0.08, hd - 0.08, h + 0.001], 0.1
                ),
            ),
            (None, steel, cylinder(0.02, h, h + 0.12).moved(_I, [-hw + 0.15, hd - 0.05, 0])),
        ]
    out = _case(p, f"vanity{room}", w, d - 0.02, h - 0.04, 2, 1, 0.1)
    out.append((None, white, box([-hw, -hd, h - 0.04], [hw, hd, h])))
    basin = rounded_box([-0.22, -hd + 0.08, h - 0.002], [0.22, hd - 0.1, h + 0.01], 0.05)
    out.append((("sink", 0), p.plain("basin inside", (0.85, 0.87, 0.9), 0.8), basin))
    out.append((("sink", 0), steel, cylinder(0.015, h, h + 0.22).moved(_I, [0, hd - 0.06, 0])))
    out.append(
        (("sink", 0), steel, box([-0.012, hd - 0.2, h + 0.19], [0.012, hd - 0.06, h + 0.22]))
    )
    mirror = p.plain("mirror", (0.62, 0.7, 0.74), 0.95)
    out.append((("mirror", 0), mirror, box([-0.35, hd - 0.012, h + 0.3], [0.35, hd, h + 1.1])))
    return out


def _gym(p: Palette, name: str, w: float, d: float, h: float) -> list[Piece]:
    hw, hd = w / 2, d / 2
    black, steel = p.metal("black"), p.metal("steel")
    rubber = p.plain("rubber", (0.12, 0.12, 0.13))
    if name == "treadmill":
        return [
            (None, black, box([-hw, -hd, 0.0], [hw, hd - 0.2, 0.16])),
            (None, rubber, box([-hw + 0.08, -hd + 0.02, 0.16], [hw - 0.08, hd - 0.25, 0.17])),
            (None, steel, box([-hw, hd - 0.2, 0.0], [-hw + 0.05, hd - 0.1, h - 0.15])),
            (None, steel, box([hw - 0.05, hd - 0.2, 0.0], [hw, hd - 0.1, h - 0.15])),
            (None, black, box([-hw, hd - 0.3, h - 0.2], [hw, hd, h])),
        ]
    if name == "exercise_bike":
        wheel = cylinder(0.25, -0.03, 0.03, 20).moved(_ALONG_X, [0, hd - 0.3, 0.32])
        return [
            (None, black, box([-0.04, -hd, 0.0], [0.04, hd, 0.06])),
            (None, steel, box([-0.03, -hd + 0.25, 0.06], [0.03, -hd + 0.3, 0.85])),
            (None, rubber, rounded_box([-0.12, -hd + 0.15, 0.85], [0.12, -hd + 0.4, 0.92], 0.03)),
            (None, steel, box([-0.03, hd - 0.15, 0.06], [0.03, hd - 0.1, h - 0.1])),
            (None, black, box([-hw, hd - 0.2, h - 0.1], [hw, hd - 0.05, h])),
            (None, black, wheel),
        ]
    out: list[Piece] = [
        (None, black, box([-hw, -hd, 0.0], [-hw + 0.05, hd, h])),
        (None, black, box([hw - 0.05, -hd, 0.0], [hw, hd, h])),
    ]
    for z in (0.3, 0.75, 1.2):
        out.append((None, steel, box([-hw, -hd + 0.05, z - 0.02], [hw, hd - 0.05, z])))
        for x in np.linspace(-hw + 0.2, hw - 0.2, 3):
            bell = cylinder(0.07, -0.16, 0.16, 12).moved(_ALONG_X, [x, 0, z + 0.07])
            out.append((None, rubber, bell))
    return out


def _rack(p: Palette, w: float, d: float, h: float, room: int) -> list[Piece]:
    wood = p.wood(f"room{room}")
    out: list[Piece] = [
        (None, wood, cylinder(0.16, 0.0, 0.03, 14)),
        (None, wood, cylinder(0.025, 0.03, h, 8)),
    ]
    for k in range(4):
        a = np.pi / 2 * k + 0.4
        hook = box([0.0, -0.01, h - 0.12], [0.12, 0.01, h - 0.1])
        rot = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
        out.append((None, wood, hook.moved(rot, [0, 0, 0])))
    coat = ellipsoid([0.15, 0.12, 0.4], 10, 6).moved(_I, [0.04, 0.0, h - 0.55])
    out.append((("clothes", 0), p.fabric(f"coat{room}"), coat))
    return out


def _bench(p: Palette, w: float, d: float, h: float, room: int) -> list[Piece]:
    hw, hd = w / 2, d / 2
    wood = p.wood(f"room{room}")
    return [
        (None, p.fabric(f"room{room}"), rounded_box([-hw, -hd, h - 0.08], [hw, hd, h], 0.03)),
        (None, wood, box([-hw, -hd, h - 0.1], [hw, hd, h - 0.07])),
        *[(None, wood, box([x - 0.03, -hd + 0.02, 0.0], [x + 0.03, hd - 0.02, h - 0.1]))
          for x in (-hw + 0.08, hw - 0.08)],
    ]  # fmt: skip


_CASES = {  # name: (columns, rows) of fronts
    "sideboard": (3, 1),
    "nightstand": (1, 2),
    "dresser": (2, 3),
    "wardrobe": (2, 1),
}


def block_pieces(
    p: Palette, name: str, w: float, d: float, h: float, spec: dict[str, Any], room: int
) -> list[Piece]:
    """The pieces of a one-block item called ``name`` (a generic cabinet if unknown)."""
    builders: dict[str, Callable[[], list[Piece]]] = {
        "bookshelf": lambda: _shelves(p, name, w, d, h, room),
        "shelving": lambda: _shelves(p, name, w, d, h, room),
        "plant": lambda: _plant(p, w, d, h),
        "counter": lambda: _counter(p, name, w, d, h, room),
        "bar_counter": lambda: _counter(p, name, w, d, h, room),
        "fridge": lambda: _appliance(p, name, w, d, h),
        "stove": lambda: _appliance(p, name, w, d, h),
        "washer": lambda: _appliance(p, name, w, d, h),
        "dryer": lambda: _appliance(p, name, w, d, h),
        "bathtub": lambda: _bath(p, name, w, d, h, room),
        "sink": lambda: _bath(p, name, w, d, h, room),
        "treadmill": lambda: _gym(p, name, w, d, h),
        "exercise_bike": lambda: _gym(p, name, w, d, h),
        "weight_rack": lambda: _gym(p, name, w, d, h),
        "coat_rack": lambda: _rack(p, w, d, h, room),
        "bench": lambda: _bench(p, w, d, h, room),
    }
    if name in builders:
        return builders[name]()
    cols, rows = _CASES.get(name, (max(1, round(w / 0.5)), 1))
    out = _case(p, f"room{room}", w, d, h, cols, rows)
    if name == "nightstand":  # a bedside lamp
        r = 0.4 * min(w, d) / 2
        glow = p.plain("lamp shade", (1.0, 0.97, 0.9), emission=1.0)
        out.append((("lamp", 0), p.metal("brass"), cylinder(0.05, h, h + 0.2, 8)))
        out.append((("lamp", 0), glow, frustum(1.4 * r, r, h + 0.18, h + 0.36, 12)))
    return out
