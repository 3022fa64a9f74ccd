"""Room dressing: doors, windows, skirting, lamps, pictures, rugs and shading overlays.

Everything here lies within a few centimetres of a wall, floor or ceiling (an open door leaf
stands 4.5 cm off its wall, a ceiling lamp hangs 15 cm) and clear of the furniture, so the
exact boxes stay the collision. Overlays are blended quads a few millimetres off their
surface: dark ramps where walls meet floors and ceilings and in corners (the shading a
renderer without global illumination leaves out), soft contact shadows under furniture, and
patches of daylight below windows. An overlay carries the label of the surface it lies on,
so the segmentation still sees a floor, a wall or a ceiling there.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from havln_mj.scene.procedural import textures as tx
from havln_mj.scene.procedural.dresser import Dresser
from havln_mj.scene.procedural.furnish import inner_rect
from havln_mj.scene.procedural.house import ProceduralHouse
from havln_mj.scene.procedural.layout import Door, Room
from havln_mj.scene.procedural.materials import Material, Palette
from havln_mj.scene.procedural.primitives import Solid, box, cylinder, frustum, quad

_NO_WINDOWS = {"c", "u", "h"}
_FROSTED = {"a", "t"}
_PICTURES = {"l": 2, "f": 2, "b": 1, "d": 1, "o": 1, "n": 1, "i": 1, "v": 1, "e": 1, "h": 1}
_TRIM = 0.07  # width of door casings
_OFF = 0.003  # overlay offset from its surface
_UP = np.array([0.0, 0.0, 1.0])


@dataclass
class Side:
    """One wall of a room, seen from inside.

    ``axis`` is the coordinate the wall runs along (0: x, 1: y); ``face`` the position of its
    inner face on the other axis; ``normal`` +1 or -1, pointing into the room along that axis.
    ``used`` holds the stretches already taken by openings, windows, doors and pictures.
    """

    room: Room
    axis: int
    face: float
    normal: float
    lo: float
    hi: float
    exterior: bool
    openings: list[tuple[float, float, float]]  # (lo, hi, height)
    used: list[tuple[float, float]] = field(default_factory=list)

    def point(self, along: float, off: float, z: float) -> np.ndarray:
        """World point ``along`` the wall, ``off`` metres into the room, at height ``z``."""
        p = np.zeros(3)
        p[self.axis], p[1 - self.axis], p[2] = along, self.face + self.normal * off, z
        return p

    @property
    def inward(self) -> np.ndarray:
        """Unit vector from the wall into the room."""
        return self.point(0.0, 1.0, 0.0) - self.point(0.0, 0.0, 0.0)

    def slab(self, a: float, b: float, off0: float, off1: float, z0: float, z1: float) -> Solid:
        """A box along the wall from ``a`` to ``b``, ``off0``..``off1`` into the room."""
        p, q = self.point(a, off0, z0), self.point(b, off1, z1)
        return box(np.minimum(p, q), np.maximum(p, q))

    def panel(self, a: float, b: float, z0: float, z1: float, off: float) -> Solid:
        """A quad facing into the room over ``[a, b] × [z0, z1]``, texture spanning it once."""
        along = self.point(b, off, z0) - self.point(a, off, z0)
        return decal(self.point(a, off, z0), along, _UP * (z1 - z0), self.inward)

    def segments(self) -> list[tuple[float, float]]:
        """The stretches of wall between openings."""
        out, start = [], self.lo
        for a, b, _ in sorted(self.openings):
            if a > start:
                out.append((start, a))
            start = max(start, b)
        if self.hi > start:
            out.append((start, self.hi))
        return [(a, b) for a, b in out if b - a > 0.05]

    def free(self, a: float, b: float) -> bool:
        """Whether ``[a, b]`` lies on this wall clear of everything placed on it."""
        return self.lo <= a and b <= self.hi and all(b <= s or a >= e for s, e in self.used)


def decal(corner: np.ndarray, u_edge: np.ndarray, v_edge: np.ndarray, normal: np.ndarray) -> Solid:
    """A quad from ``corner`` along ``u_edge`` and ``v_edge`` facing ``normal``; uv in [0, 1]."""
    solid = quad(corner, u_edge, v_edge)
    if np.dot(np.cross(u_edge, v_edge), normal) < 0:
        solid = Solid(solid.vertices, solid.faces[:, [0, 2, 1]], solid.uv)
    return solid


def room_sides(house: ProceduralHouse, room: Room) -> list[Side]:
    """The four walls of ``room`` with their door openings."""
    plan = house.plan
    inner = inner_rect(room, (plan.width, plan.depth), house.recipe)
    out = []
    for axis, coord, face, normal, outer in (
        (0, room.y0, inner[1], 1.0, 0.0),
        (0, room.y1, inner[3], -1.0, plan.depth),
        (1, room.x0, inner[0], 1.0, 0.0),
        (1, room.x1, inner[2], -1.0, plan.width),
    ):
        openings = [
            (d.lo, d.hi, d.height)
            for d in plan.doors
            if room.index in (d.a, d.b)
            and d.vertical == (axis == 1)
            and abs(d.coord - coord) < 1e-6
        ]
        lo, hi = (inner[0], inner[2]) if axis == 0 else (inner[1], inner[3])
        side = Side(room, axis, face, normal, lo, hi, abs(coord - outer) < 1e-6, openings)
        side.used += [(a - _TRIM, b + _TRIM) for a, b, _ in openings]
        out.append(side)
    return out


class _Room:
    """One room being dressed: its walls, items and the instances of its surfaces."""

    def __init__(self, house: ProceduralHouse, dresser: Dresser, room: Room) -> None:
        self.house, self.d, self.room = house, dresser, room
        self.sides = room_sides(house, room)
        self.items = [it for it in house.items if it.room == room.index]
        ids = {i.category: i.id for i in dresser.instances if i.region == room.index}
        self.floor_id, self.wall_id, self.ceiling_id = ids["floor"], ids["wall"], ids["ceiling"]
        self.height = house.plan.wall_height

    def against(self, side: Side, a: float, b: float) -> float:
        """Height of the tallest item within 0.4 m of ``side`` between ``a`` and ``b`` (or 0)."""
        top = 0.0
        for item in self.items:
            bb = item.bbox
            across = (bb[1 - side.axis], bb[4 - side.axis])
            near = min(abs(across[0] - side.face), abs(across[1] - side.face)) < 0.4
            if near and bb[side.axis] < b and a < bb[side.axis + 3]:
                top = max(top, float(bb[5]))
        return top

    def floor_decal(self, lo: np.ndarray, hi: np.ndarray, z: float, material: Material) -> None:
        """An overlay on this room's floor over the rectangle ``lo``..``hi`` (x, y)."""
        corner = np.array([lo[0], lo[1], z])
        solid = decal(corner, [hi[0] - lo[0], 0, 0], [0, hi[1] - lo[1], 0], _UP)
        self.d.add(self.floor_id, material, solid)


def _door_leaf(pair: list[_Room], door: Door, paint: Material, steel: Material, iid: int) -> None:
    """An open leaf flat against a wall beside ``door``, where a wall has room for it."""
    width, height = door.hi - door.lo, door.height - 0.01
    for r in pair:
        for side in r.sides:
            if (door.lo, door.hi, door.height) not in side.openings:
                continue
            a, b = door.lo, door.hi
            for s, e in ((b, b + width), (a - width, a)):
                if side.free(s, e) and r.against(side, s, e) == 0.0:
                    r.d.add(iid, paint, side.slab(s, e, 0.005, 0.045, 0.0, height))
                    knob = e - 0.07 if s == b else s + 0.07
                    r.d.add(iid, steel, side.slab(knob - 0.01, knob + 0.01, 0.045, 0.1, 1.0, 1.02))
                    side.used.append((s, e))
                    return


def _doors(house: ProceduralHouse, dresser: Dresser, rooms: list[_Room], trim: Material) -> None:
    """Casings on both sides of every opening, and open leaves for ordinary doors."""
    palette = dresser.palette
    paint = palette.plain("door", palette.pick(palette.lib["trim"]), 0.3)
    steel = palette.metal("steel")
    for door in house.plan.doors:
        iid = dresser.instance("door", "door", door.a)
        pair = [rooms[door.a], rooms[door.b]]
        a, b, h = door.lo, door.hi, door.height
        for r in pair:
            for side in r.sides:
                if (a, b, h) in side.openings:
                    dresser.add(iid, trim, side.slab(a - _TRIM, a, 0.0, 0.015, 0.0, h + _TRIM))
                    dresser.add(iid, trim, side.slab(b, b + _TRIM, 0.0, 0.015, 0.0, h + _TRIM))
                    dresser.add(
                        iid, trim, side.slab(a - _TRIM, b + _TRIM, 0.0, 0.015, h, h + _TRIM)
                    )
        if door.width < 1.2 and palette.rng.random() < 0.85:
            _door_leaf(pair if palette.rng.random() < 0.5 else pair[::-1], door, paint, steel, iid)


def _windows(r: _Room, trim: Material, sky: Material, frosted: Material, sun: Material) -> None:
    kind = r.room.kind
    if kind in _NO_WINDOWS:
        return
    head = min(2.2, r.height - 0.3)
    for side in r.sides:
        if not side.exterior:
            continue
        for a, b in side.segments():
            length = b - a
            count = int(length // 2.6) + (length >= 1.3)
            for k in range(count):
                c = a + length * (k + 0.5) / count
                half = min(0.75, 0.28 * length / count) if kind not in _FROSTED else 0.3
                sill = 1.45 if kind in _FROSTED else 0.9
                top = r.against(side, c - half - 0.1, c + half + 0.1)
                if top > sill - 0.02:
                    sill = top + 0.05
                if head - sill < 0.55 or not side.free(c - half - 0.1, c + half + 0.1):
                    continue
                side.used.append((c - half - 0.1, c + half + 0.1))
                _window(
                    r, side, c, half, sill, head, trim, frosted if kind in _FROSTED else sky, sun
                )


def _window(r: _Room, side: Side, c: float, half: float, sill: float, head: float,
            trim: Material, glass: Material, sun: Material) -> None:  # fmt: skip
    iid = r.d.instance("window", "window", r.room.index)
    a, b, f = c - half, c + half, 0.05
    r.d.add(iid, glass, side.panel(a, b, sill, head, 0.004))
    for s, e, z0, z1 in (
        (a - f, a, sill, head + f),
        (b, b + f, sill, head + f),
        (a - f, b + f, head, head + f),
    ):
        r.d.add(iid, trim, side.slab(s, e, 0.0, 0.04, z0, z1))
    r.d.add(iid, trim, side.slab(a - f - 0.04, b + f + 0.04, 0.0, 0.07, sill - 0.035, sill))
    if half > 0.45:
        r.d.add(iid, trim, side.slab(c - 0.018, c + 0.018, 0.0, 0.03, sill, head))
    reach = 0.9 * (head - sill)
    p, q = side.point(a + 0.1, 0.15, 0.0), side.point(b + 0.1, 0.15 + reach, 0.0)
    r.floor_decal(np.minimum(p, q), np.maximum(p, q), 0.004, sun)


def _shading(r: _Room, trim: Material, shade: Material) -> None:
    """Skirting along every stretch of wall, and dark ramps along its corners."""
    h = r.height
    for side in r.sides:
        n = side.inward
        for a, b in side.segments():
            along = side.point(b, 0, 0) - side.point(a, 0, 0)
            r.d.add(r.wall_id, trim, side.slab(a, b, 0.0, 0.012, 0.0, 0.09))
            r.d.add(r.floor_id, shade, decal(side.point(a, 0.0, _OFF), along, 0.25 * n, _UP))
        for end, sign in ((side.lo, 1.0), (side.hi, -1.0)):
            if any(x - 0.1 < end < y + 0.1 for x, y, _ in side.openings):
                continue
            away = side.point(end + 0.15 * sign, 0, 0) - side.point(end, 0, 0)
            r.d.add(r.wall_id, shade, decal(side.point(end, _OFF, 0.0), h * _UP, away, n))


def _lamps(r: _Room, palette: Palette) -> None:
    """Flush ceiling lamps: one per room, two or three along long rooms."""
    room, h = r.room, r.height
    long_x = room.x1 - room.x0 >= room.y1 - room.y0
    length = max(room.x1 - room.x0, room.y1 - room.y0)
    count = 1 + int(length > 4.5) + int(length > 8.0)
    glow = palette.plain("lamp shade", (1.0, 0.97, 0.9), emission=1.0)
    base = palette.metal("brass" if room.kind in "ldbn" else "steel")
    cx, cy = (room.x0 + room.x1) / 2, (room.y0 + room.y1) / 2
    for k in range(count):
        t = (k + 0.5) / count
        x = room.x0 + t * (room.x1 - room.x0) if long_x else cx
        y = cy if long_x else room.y0 + t * (room.y1 - room.y0)
        iid = r.d.instance("ceiling lamp", "lighting", room.index)
        r.d.add(iid, base, cylinder(0.17, h - 0.03, h, 10).moved(np.eye(3), [x, y, 0]))
        r.d.add(iid, glow, frustum(0.1, 0.16, h - 0.13, h - 0.03, 10).moved(np.eye(3), [x, y, 0]))


def _pictures(r: _Room, palette: Palette, frame: Material) -> None:
    rng = palette.rng
    for _ in range(_PICTURES.get(r.room.kind, 0)):
        w, h = float(rng.uniform(0.5, 1.0)), float(rng.uniform(0.4, 0.7))
        for _try in range(8):
            side = r.sides[int(rng.integers(4))]
            if side.hi - side.lo < w + 0.6:
                continue
            c = float(rng.uniform(side.lo + w / 2 + 0.3, side.hi - w / 2 - 0.3))
            a, b = c - w / 2, c + w / 2
            bottom = max(1.55 - h / 2, r.against(side, a - 0.1, b + 0.1) + 0.2)
            if not side.free(a - 0.2, b + 0.2) or bottom + h > r.height - 0.25:
                continue
            side.used.append((a - 0.2, b + 0.2))
            art = palette.image(f"art{int(rng.integers(4))}", "art", 256, shine=0.2)
            iid = r.d.instance("picture", "picture", r.room.index)
            r.d.add(iid, frame, side.slab(a, b, 0.0, 0.03, bottom, bottom + h))
            r.d.add(
                iid, art, side.panel(a + 0.04, b - 0.04, bottom + 0.04, bottom + h - 0.04, 0.031)
            )
            break


def _rug(r: _Room, palette: Palette) -> None:
    rng, room = palette.rng, r.room
    if rng.random() >= palette.rug_odds(room.kind):
        return
    inner = inner_rect(room, (r.house.plan.width, r.house.plan.depth), r.house.recipe)
    anchor = next((it for it in r.items if it.name in ("coffee_table", "bed", "dining_set")), None)
    if anchor is not None:
        bb = anchor.bbox
        grow = 0.3 if anchor.name == "bed" else 0.6
        lo, hi = bb[:2] - grow, bb[3:5] + grow
    else:
        centre, size = (
            (inner[:2] + inner[2:]) / 2,
            np.minimum((inner[2:] - inner[:2]) * 0.55, [3.0, 2.2]),
        )
        lo, hi = centre - size / 2, centre + size / 2
    lo, hi = np.maximum(lo, inner[:2] + 0.25), np.minimum(hi, inner[2:] - 0.25)
    if np.any(hi - lo < 0.8):
        return
    colours = palette.pick(palette.lib["rugs"])
    k = int(rng.integers(3))
    image = palette.image(f"rug{k}", "rug", 256, *colours)
    solid = box([lo[0], lo[1], 0.0], [hi[0], hi[1], 0.008])
    uv = (solid.vertices[:, :2] - lo) / (hi - lo)
    iid = r.d.instance("rug", "floor", room.index)
    r.d.add(iid, image, Solid(solid.vertices, solid.faces, uv))


def dress_rooms(dresser: Dresser, house: ProceduralHouse) -> None:
    """Dresses every room of ``house`` (the architecture is drawn already)."""
    p = dresser.palette
    trim = p.plain("trim", p.pick(p.lib["trim"]), 0.3)
    frame = p.plain("picture frame", (0.12, 0.1, 0.09), 0.3)
    shade = p.decal("shade", tx.shade_ramp(64, 0.4))
    contact = p.decal("contact shadow", tx.soft_patch(64, (0.0, 0.0, 0.0), 0.55))
    sun = p.decal("daylight", tx.soft_patch(64, (1.0, 0.96, 0.86), 0.3), emission=1.0)
    sky = p.image("sky", "sky", 256, emission=0.9)
    frosted = p.plain("frosted glass", (0.9, 0.94, 0.96), emission=0.85)
    rooms = [_Room(house, dresser, room) for room in house.plan.rooms]
    _doors(house, dresser, rooms, trim)
    for r in rooms:
        _windows(r, trim, sky, frosted, sun)
        _shading(r, trim, shade)
        for item in r.items:
            bb = item.bbox
            r.floor_decal(bb[:2] - 0.08, bb[3:5] + 0.08, 0.01, contact)
        _lamps(r, p)
        _pictures(r, p, frame)
        _rug(r, p)
