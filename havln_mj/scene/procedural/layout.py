"""Floor plans: rooms tiling a rectangular footprint, labelled with region codes, and doors.

Larger houses get a hallway with rooms on both sides (and often an open living block at one
end); smaller ones are split by binary space partition. Rooms are labelled by size class
(living room, kitchen, bedroom and bathroom always present), and doors join every room to
the hallway plus a spanning tree of the remaining adjacencies that avoids passing through
bathrooms and closets, with wide openings between open-plan rooms.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from havln_mj.scene.procedural.recipe import Recipe

_EPS = 1e-6
_DOOR_MARGIN = 0.3  # from a door to the corner of the wall it is in


@dataclass(frozen=True)
class Room:
    """A rectangular room ``[x0, x1] × [y0, y1]`` with a region label code."""

    index: int
    kind: str
    x0: float
    y0: float
    x1: float
    y1: float

    @property
    def area(self) -> float:
        """Floor area in m²."""
        return (self.x1 - self.x0) * (self.y1 - self.y0)


@dataclass(frozen=True)
class Door:
    """An opening between rooms ``a`` and ``b`` on a shared wall line.

    ``vertical`` walls lie on ``x = coord`` and the opening spans ``y ∈ [lo, hi]``; otherwise
    the wall lies on ``y = coord`` and the opening spans ``x ∈ [lo, hi]``.
    """

    a: int
    b: int
    vertical: bool
    coord: float
    lo: float
    hi: float
    height: float

    @property
    def width(self) -> float:
        """Opening width in metres."""
        return self.hi - self.lo

    @property
    def center(self) -> np.ndarray:
        """Centre of the opening on the floor plan (x, y)."""
        mid = 0.5 * (self.lo + self.hi)
        return np.array([self.coord, mid] if self.vertical else [mid, self.coord])


@dataclass(frozen=True)
class FloorPlan:
    """Rooms, doors and storey height of a single-level house."""

    rooms: tuple[Room, ...]
    doors: tuple[Door, ...]
    width: float
    depth: float
    wall_height: float


def _shared_wall(r: Room, s: Room) -> tuple[bool, float, float, float] | None:
    """The wall line two rooms share, as (vertical, coord, lo, hi), or None."""
    for vertical, (a1, b0, lo0, hi0, lo1, hi1) in (
        (True, (r.x1, s.x0, r.y0, r.y1, s.y0, s.y1)),
        (True, (s.x1, r.x0, r.y0, r.y1, s.y0, s.y1)),
        (False, (r.y1, s.y0, r.x0, r.x1, s.x0, s.x1)),
        (False, (s.y1, r.y0, r.x0, r.x1, s.x0, s.x1)),
    ):
        if abs(a1 - b0) < _EPS:
            lo, hi = max(lo0, lo1), min(hi0, hi1)
            if hi - lo > _EPS:
                return vertical, a1, lo, hi
    return None


def _split_strip(
    rng: np.random.Generator, x0: float, x1: float, y0: float, y1: float
) -> list[tuple[float, float, float, float]]:
    """Cuts a strip along x into rooms 2.4–5 m wide.

    About one cut in four is a narrow 1.5–2.3 m bay, split across its depth into two small
    rooms (toilets, closets, laundries) when the strip is deep enough.
    """
    out, x = [], x0
    while x1 - x > _EPS:
        narrow = rng.random() < 0.25
        w = rng.uniform(1.5, 2.3) if narrow else rng.uniform(2.4, 5.0)
        if x1 - (x + w) < 2.4:
            w, narrow = x1 - x, False
        xe = min(round(x + w, 2), x1)
        if narrow and y1 - y0 > 3.6:
            ym = round(y0 + (y1 - y0) * rng.uniform(0.4, 0.6), 2)
            out += [(x, y0, xe, ym), (x, ym, xe, y1)]
        else:
            out.append((x, y0, xe, y1))
        x = xe
    return out


def _split_large(
    rng: np.random.Generator, rects: list[tuple[float, float, float, float]]
) -> list[tuple[float, float, float, float]]:
    """Splits rooms over 30 m² (all but the largest) across their long side, mostly."""
    areas = [(r[2] - r[0]) * (r[3] - r[1]) for r in rects]
    keep = int(np.argmax(areas))
    out = []
    for i, r in enumerate(rects):
        if i != keep and areas[i] > 30.0 and rng.random() < 0.7:
            out += _bsp(rng, r, 2)
        else:
            out.append(r)
    return out


def _bsp(
    rng: np.random.Generator, rect: tuple[float, float, float, float], n: int
) -> list[tuple[float, float, float, float]]:
    """Splits ``rect`` into up to ``n`` rooms, always cutting the largest along its long side."""
    rects = [rect]
    while len(rects) < n:
        rects.sort(key=lambda r: (r[2] - r[0]) * (r[3] - r[1]), reverse=True)
        x0, y0, x1, y1 = rects[0]
        along_x = (x1 - x0) >= (y1 - y0)
        length = (x1 - x0) if along_x else (y1 - y0)
        if length < 4.4:
            break
        cut = round(length * rng.uniform(0.35, 0.65), 2)
        cut = min(max(cut, 2.2), length - 2.2)
        rects.pop(0)
        if along_x:
            rects += [(x0, y0, x0 + cut, y1), (x0 + cut, y0, x1, y1)]
        else:
            rects += [(x0, y0, x1, y0 + cut), (x0, y0 + cut, x1, y1)]
    return rects


def _footprint(
    rng: np.random.Generator, recipe: Recipe, area: float
) -> tuple[float, float, list[tuple[float, float, float, float, str | None]]]:
    """Outer size and room rectangles; the hallway (if any) comes labelled ``"h"``."""
    aspect = rng.uniform(*recipe["aspect"])
    width = round(math.sqrt(area * aspect), 1)
    depth = round(area / width, 1)
    if area < recipe["corridor_min_area_m2"] or depth < 6.5:
        n = int(np.clip(round(area / 14.0), 3, 6))
        rects = _bsp(rng, (0.0, 0.0, width, depth), n)
        if rng.random() < 0.6:
            # An en-suite bathroom, toilet or closet cut from a room's end.
            i = int(rng.integers(len(rects)))
            x0, y0, x1, y1 = rects.pop(i)
            s = round(rng.uniform(1.5, 2.2), 2)
            if x1 - x0 >= y1 - y0 and x1 - x0 >= 4.6:
                rects += [(x0, y0, x1 - s, y1), (x1 - s, y0, x1, y1)]
            elif y1 - y0 >= 4.6:
                rects += [(x0, y0, x1, y1 - s), (x0, y1 - s, x1, y1)]
            else:
                rects.append((x0, y0, x1, y1))
        return width, depth, [(*r, None) for r in rects]
    c = round(rng.uniform(*recipe["corridor_width"]), 2)
    end = (
        round(rng.uniform(3.5, min(6.0, 0.4 * width)), 2)
        if width >= 10 and rng.random() < 0.6
        else 0.0
    )
    xe = width - end
    yc = round(float(np.clip(rng.uniform(0.4, 0.6) * depth - c / 2, 2.5, depth - c - 2.5)), 2)
    rects: list[tuple[float, float, float, float, str | None]] = [(0.0, yc, xe, yc + c, "h")]
    rooms = _split_strip(rng, 0.0, xe, 0.0, yc) + _split_strip(rng, 0.0, xe, yc + c, depth)
    if end > 0:
        if depth >= 7.0 and rng.random() < 0.6:
            ys = round(depth * rng.uniform(0.4, 0.6), 2)
            rooms += [(xe, 0.0, width, ys), (xe, ys, width, depth)]
        else:
            rooms.append((xe, 0.0, width, depth))
    return width, depth, rects + [(*r, None) for r in _split_large(rng, rooms)]


def _assign_kinds(
    rng: np.random.Generator,
    recipe: Recipe,
    rects: list[tuple[float, float, float, float, str | None]],
) -> list[str]:
    """Labels rooms: living room, kitchen, bedroom, bathroom first, then by size class."""
    areas = [(r[2] - r[0]) * (r[3] - r[1]) for r in rects]
    kinds: list[str | None] = [r[4] for r in rects]
    free = [i for i, k in enumerate(kinds) if k is None]

    def take(score: list[float]) -> int:
        best = min(free, key=lambda i: (score[i], i))
        free.remove(best)
        return best

    for kind, target in (("l", 1e9), ("k", 12.0), ("a", 5.0), ("b", 13.0)):
        if not free:
            break
        i = take([abs(areas[i] - target) for i in range(len(rects))])
        kinds[i] = kind
    classes = recipe["size_classes"]
    for i in free:
        for cls in ("small", "medium", "large"):
            if areas[i] <= classes[cls]["max_area"]:
                options = classes[cls]["kinds"]
                break
        names = sorted(options)
        weights = np.array([options[n] for n in names], dtype=float)
        kinds[i] = names[rng.choice(len(names), p=weights / weights.sum())]
    return [str(k) for k in kinds]


def _choose_doors(
    rng: np.random.Generator, recipe: Recipe, rooms: list[Room], height: float
) -> list[Door] | None:
    """Doors joining all rooms, or None when some room cannot be reached."""
    open_kinds, private = set(recipe["open_plan_kinds"]), set(recipe["private_kinds"])
    min_door = recipe["door_width"][0]
    walls = {}
    for i, r in enumerate(rooms):
        for j in range(i + 1, len(rooms)):
            w = _shared_wall(r, rooms[j])
            if w is not None and w[3] - w[2] >= min_door + 2 * _DOOR_MARGIN:
                walls[(i, j)] = w
    parent = list(range(len(rooms)))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    chosen: list[tuple[int, int]] = []
    # Every room on the hallway opens onto it.
    for i, j in sorted(walls):
        if "h" in (rooms[i].kind, rooms[j].kind):
            chosen.append((i, j))
            parent[root(i)] = root(j)
    # Then a spanning tree that prefers not to pass through bathrooms and closets.
    order = sorted(
        walls,
        key=lambda p: ((rooms[p[0]].kind in private) + (rooms[p[1]].kind in private), rng.random()),
    )
    for i, j in order:
        if root(i) != root(j):
            chosen.append((i, j))
            parent[root(i)] = root(j)
        elif (
            (i, j) not in chosen
            and rooms[i].kind in open_kinds
            and rooms[j].kind in open_kinds
            and rng.random() < 0.5
        ):
            chosen.append((i, j))
    if len({root(i) for i in range(len(rooms))}) > 1:
        return None
    doors = []
    for i, j in sorted(chosen):
        vertical, coord, lo, hi = walls[(i, j)]
        room_kinds = {rooms[i].kind, rooms[j].kind}
        span = hi - lo - 2 * _DOOR_MARGIN
        if room_kinds <= open_kinds:
            width = min(rng.uniform(*recipe["open_door_width"]), span)
        else:
            width = min(rng.uniform(*recipe["door_width"]), span)
        start = lo + _DOOR_MARGIN + rng.uniform(0.0, span - width)
        doors.append(Door(i, j, vertical, coord, round(start, 3), round(start + width, 3), height))
    return doors


def plan_house(rng: np.random.Generator, recipe: Recipe, area: float | None = None) -> FloorPlan:
    """Draws a floor plan from ``rng``.

    Args:
        rng: The house's generator (consumed deterministically).
        recipe: The procedural recipe.
        area: Target floor area in m²; drawn from the recipe's range when None.

    Returns:
        A plan whose rooms tile the footprint and whose doors connect every room.
    """
    for _ in range(50):
        target = area if area is not None else rng.uniform(*recipe["area_m2"])
        width, depth, rects = _footprint(rng, recipe, target)
        kinds = _assign_kinds(rng, recipe, rects)
        rooms = [Room(i, k, *r[:4]) for i, (r, k) in enumerate(zip(rects, kinds, strict=True))]
        height = round(rng.uniform(*recipe["wall_height"]), 2)
        doors = _choose_doors(rng, recipe, rooms, recipe["door_height"])
        if doors is not None:
            return FloorPlan(tuple(rooms), tuple(doors), width, depth, height)
    raise RuntimeError("could not draw a connected floor plan in 50 tries")  # pragma: no cover
