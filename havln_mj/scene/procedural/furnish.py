"""Furniture: recipe items placed in rooms as composite boxes, clear of doorways.

Each item has a local frame with its footprint ``[-w/2, w/2] × [-d/2, d/2]``, its back at +y
(against a wall for wall items) and z up from the floor; it is turned by a multiple of 90°
when placed, so all parts stay axis-aligned.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from havln_mj.scene.procedural.layout import Door, Room
from havln_mj.scene.procedural.recipe import Recipe

# Quarter turns that put an item's back (+y) against the wall on each side.
_YAW_FOR_SIDE = {"south": 2, "north": 0, "west": 1, "east": 3}
_DOOR_KEEPOUT = 1.2  # metres in front of a door kept free
_MAX_COVER = 0.4  # fraction of a room's floor furniture may cover


@dataclass(frozen=True)
class Part:
    """One axis-aligned box of an item, in world coordinates."""

    lo: np.ndarray
    hi: np.ndarray
    rgba: tuple[float, ...]


@dataclass(frozen=True)
class Item:
    """A placed furniture item."""

    name: str
    mpcat40: str
    room: int
    parts: tuple[Part, ...]
    yaw: float
    seat_height: float | None

    @property
    def bbox(self) -> np.ndarray:
        """(6,) union of the parts' extents."""
        lo = np.min([p.lo for p in self.parts], axis=0)
        hi = np.max([p.hi for p in self.parts], axis=0)
        return np.concatenate([lo, hi])


def _shade(rgba: list[float], f: float) -> tuple[float, ...]:
    return (*(min(1.0, c * f) for c in rgba[:3]), rgba[3])


def _local_parts(shape: str, w: float, d: float, h: float, spec: dict) -> list[tuple]:
    """Parts as (xl, yl, zl, xh, yh, zh, rgba) in the item's local frame."""
    c = spec["rgba"]
    dark = _shade(c, 0.7)
    sh = spec.get("seat_height", 0.45)
    hw, hd = w / 2, d / 2
    if shape == "table":
        parts = [(-hw, -hd, h - 0.04, hw, hd, h, tuple(c))]
        for sx in (-1, 1):
            for sy in (-1, 1):
                x, y = sx * (hw - 0.07), sy * (hd - 0.07)
                parts.append((x - 0.03, y - 0.03, 0.0, x + 0.03, y + 0.03, h - 0.04, dark))
        return parts
    if shape == "chair":
        parts = [(-hw, -hd, sh - 0.05, hw, hd - 0.06, sh, tuple(c))]
        parts.append((-hw, hd - 0.06, 0.0, hw, hd, h, tuple(c)))
        parts.append((-0.04, -0.04, 0.0, 0.04, 0.04, sh - 0.05, dark))
        return parts
    if shape == "sofa":
        return [
            (-hw + 0.15, -hd, 0.0, hw - 0.15, hd - 0.2, sh, tuple(c)),  # seat between the arms
            (-hw, hd - 0.2, 0.0, hw, hd, h, dark),
            (-hw, -hd, 0.0, -hw + 0.15, hd - 0.2, 0.62, dark),
            (hw - 0.15, -hd, 0.0, hw, hd - 0.2, 0.62, dark),
        ]
    if shape == "bed":
        return [
            (-hw, -hd, 0.0, hw, hd - 0.08, sh, tuple(c)),
            (-hw, hd - 0.08, 0.0, hw, hd, h, (0.45, 0.32, 0.22, 1.0)),
        ]
    if shape == "tv":
        return [
            (-hw, -hd, 0.0, hw, hd, 0.5, tuple(c)),
            (-0.4 * w, -0.03, 0.55, 0.4 * w, 0.03, h, (0.05, 0.05, 0.06, 1.0)),
        ]
    if shape == "toilet":
        return [
            (-hw, -hd, 0.0, hw, hd - 0.18, sh, tuple(c)),
            (-hw, hd - 0.18, 0.0, hw, hd, h, tuple(c)),
        ]
    if shape == "dining":
        tw, td = w, d - 1.0
        parts = [(-tw / 2, -td / 2, h - 0.04, tw / 2, td / 2, h, tuple(c))]
        for sx in (-1, 1):
            for sy in (-1, 1):
                x, y = sx * (tw / 2 - 0.07), sy * (td / 2 - 0.07)
                parts.append((x - 0.03, y - 0.03, 0.0, x + 0.03, y + 0.03, h - 0.04, dark))
        n = max(1, int(tw // 0.6))
        for k in range(n):
            x = -tw / 2 + (k + 0.5) * tw / n
            for sy in (-1, 1):
                y0 = sy * (td / 2 + 0.05)
                y1 = sy * (td / 2 + 0.5)
                ylo, yhi = min(y0, y1), max(y0, y1)
                parts.append((x - 0.22, ylo, 0.0, x + 0.22, yhi - 0.06 * (sy > 0), sh, dark))
                back = (yhi - 0.06, yhi) if sy > 0 else (ylo, ylo + 0.06)
                parts.append((x - 0.22, back[0], sh, x + 0.22, back[1], 0.95, dark))
        return parts
    return [(-hw, -hd, 0.0, hw, hd, h, tuple(c))]


def _turn(box: tuple, quarter: int) -> tuple[float, float, float, float]:
    """Rotates a local footprint (xl, yl, xh, yh) by ``quarter`` × 90° counter-clockwise."""
    xl, yl, xh, yh = box
    for _ in range(quarter % 4):
        xl, yl, xh, yh = -yh, xl, -yl, xh
    return xl, yl, xh, yh


def _overlaps(a: np.ndarray, b: np.ndarray, gap: float = 0.0) -> bool:
    return bool(np.all(a[:2] < b[2:] + gap) and np.all(b[:2] < a[2:] + gap))


def inner_rect(room: Room, plan_size: tuple[float, float], recipe: Recipe) -> np.ndarray:
    """The room's floor inside its walls, as (x0, y0, x1, y1)."""
    w_in, w_out = recipe["interior_wall_half"], recipe["exterior_wall"]
    width, depth = plan_size

    def t(coord: float, outer: float) -> float:
        return w_out if abs(coord - outer) < 1e-6 else w_in

    return np.array(
        [
            room.x0 + t(room.x0, 0.0),
            room.y0 + t(room.y0, 0.0),
            room.x1 - t(room.x1, width),
            room.y1 - t(room.y1, depth),
        ]
    )


def door_keepouts(room: Room, doors: list[Door]) -> list[np.ndarray]:
    """Footprints in front of the room's doors that furniture must leave free."""
    out = []
    for door in doors:
        if room.index not in (door.a, door.b):
            continue
        lo, hi = door.lo - 0.2, door.hi + 0.2
        c, k = door.coord, _DOOR_KEEPOUT
        if door.vertical:
            out.append(np.array([c - k, lo, c + k, hi]))
        else:
            out.append(np.array([lo, c - k, hi, c + k]))
    return out


def furnish_room(
    rng: np.random.Generator,
    recipe: Recipe,
    room: Room,
    inner: np.ndarray,
    keepouts: list[np.ndarray],
) -> list[Item]:
    """Places the room kind's furniture; items that do not fit are skipped.

    Args:
        rng: The house's generator.
        recipe: The procedural recipe.
        room: The room to furnish.
        inner: The floor inside the walls (x0, y0, x1, y1).
        keepouts: Footprints to leave free (door approaches).

    Returns:
        The placed items.
    """
    x0, y0, x1, y1 = inner
    area = (x1 - x0) * (y1 - y0)
    taken: list[np.ndarray] = []
    covered = 0.0
    items = []
    for name, lo_n, hi_n in recipe.room(room.kind)["furniture"]:
        spec = recipe.furniture(name)
        w, d, _ = spec["size"]
        for _ in range(int(rng.integers(lo_n, hi_n + 1))):
            if covered + w * d > _MAX_COVER * area:
                break
            for _try in range(25):
                if spec["place"] == "centre":
                    spot = _centre_spot(rng, w, d, inner)
                    if spot is None:
                        break  # the room is too small for it away from the walls
                else:
                    spot = _wall_spot(rng, spec["place"], w, d, inner)
                    if spot is None:
                        continue
                quarter, cx, cy, foot = spot
                if not _free(foot, inner, taken, keepouts):
                    continue
                items.append(_item(name, spec, room.index, quarter, cx, cy))
                taken.append(foot)
                covered += w * d
                break
    return items


_Spot = tuple[int, float, float, np.ndarray]
"""Quarter turns, centre x and y, and the footprint (x0, y0, x1, y1) of a proposed place."""


def _centre_spot(rng: np.random.Generator, w: float, d: float, inner: np.ndarray) -> _Spot | None:
    """A random place at least 0.6 m from the walls (None: the room is too small)."""
    x0, y0, x1, y1 = inner
    quarter = int(rng.integers(0, 4))
    fx0, fy0, fx1, fy1 = _turn((-w / 2, -d / 2, w / 2, d / 2), quarter)
    cx = rng.uniform(x0 - fx0 + 0.6, x1 - fx1 - 0.6) if x1 - x0 > fx1 - fx0 + 1.2 else None
    cy = rng.uniform(y0 - fy0 + 0.6, y1 - fy1 - 0.6) if y1 - y0 > fy1 - fy0 + 1.2 else None
    if cx is None or cy is None:
        return None
    return quarter, cx, cy, np.array([cx + fx0, cy + fy0, cx + fx1, cy + fy1])


def _wall_spot(
    rng: np.random.Generator, place: str, w: float, d: float, inner: np.ndarray
) -> _Spot | None:
    """A place with the item's back against a random wall.

    Anywhere along the wall for ``place="wall"``, else at one of its ends (None: the item is
    wider than that wall).
    """
    x0, y0, x1, y1 = inner
    side = ("south", "north", "west", "east")[int(rng.integers(0, 4))]
    quarter = _YAW_FOR_SIDE[side]
    fx0, fy0, fx1, fy1 = _turn((-w / 2, -d / 2, w / 2, d / 2), quarter)
    along_x = side in ("south", "north")
    lo_a, hi_a = (x0 - fx0, x1 - fx1) if along_x else (y0 - fy0, y1 - fy1)
    if hi_a < lo_a:
        return None
    t = rng.uniform(lo_a, hi_a) if place == "wall" else (lo_a, hi_a)[int(rng.integers(2))]
    gap = 0.01
    if side == "south":
        cx, cy = t, y0 - fy0 + gap
    elif side == "north":
        cx, cy = t, y1 - fy1 - gap
    elif side == "west":
        cx, cy = x0 - fx0 + gap, t
    else:
        cx, cy = x1 - fx1 - gap, t
    return quarter, cx, cy, np.array([cx + fx0, cy + fy0, cx + fx1, cy + fy1])


def _free(
    foot: np.ndarray, inner: np.ndarray, taken: list[np.ndarray], keepouts: list[np.ndarray]
) -> bool:
    """Whether a footprint lies inside the room, clear of the items placed and the keepouts."""
    x0, y0, x1, y1 = inner
    if foot[0] < x0 - 1e-6 or foot[1] < y0 - 1e-6 or foot[2] > x1 + 1e-6 or foot[3] > y1 + 1e-6:
        return False
    return not (
        any(_overlaps(foot, o, 0.05) for o in taken) or any(_overlaps(foot, k) for k in keepouts)
    )


def _item(name: str, spec: dict, room: int, quarter: int, cx: float, cy: float) -> Item:
    """The item ``name`` placed at (cx, cy), turned by ``quarter`` quarter turns."""
    w, d, h = spec["size"]
    parts = []
    for xl, yl, zl, xh, yh, zh, rgba in _local_parts(spec["shape"], w, d, h, spec):
        bx0, by0, bx1, by1 = _turn((xl, yl, xh, yh), quarter)
        lo, hi = np.array([cx + bx0, cy + by0, zl]), np.array([cx + bx1, cy + by1, zh])
        parts.append(Part(lo, hi, rgba))
    yaw = quarter * np.pi / 2
    return Item(name, spec["mpcat40"], room, tuple(parts), yaw, spec.get("seat_height"))
