"""Region labels (Matterport3D codes) and the regions file of a scan folder.

The regions file (``regions.json``) holds the building's levels, its regions (label code,
extent, floor polygon), its furniture-like objects and the viewpoint -> region map::

    {"levels": [{"index": 0, "z_floor": 0.0, "z_ceiling": 2.7}],
     "regions": [{"index": 0, "level": 0, "label": "b", "polygon": [[x, y], ...],
                  "bbox": [xlo, ylo, zlo, xhi, yhi, zhi], "height": 2.7}],
     "objects": [{"index": 0, "region": 0, "category": "bed", "mpcat40": "bed",
                  "bbox": [xlo, ylo, zlo, xhi, yhi, zhi], "yaw": 0.0}],
     "viewpoints": {"<viewpoint id>": 0}}
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from havln_mj.cache import atomic_write_json
from havln_mj.errors import MalformedDataError, MissingDataError

REGION_LABELS: dict[str, str] = {
    "a": "bathroom",
    "b": "bedroom",
    "c": "closet",
    "d": "dining room",
    "e": "entryway",
    "f": "family room",
    "g": "garage",
    "h": "hallway",
    "i": "library",
    "j": "laundry room",
    "k": "kitchen",
    "l": "living room",
    "m": "meeting room",
    "n": "lounge",
    "o": "office",
    "p": "porch",
    "r": "rec room",
    "s": "stairs",
    "t": "toilet",
    "u": "utility room",
    "v": "tv room",
    "w": "gym",
    "x": "outdoor",
    "y": "balcony",
    "z": "other room",
    "B": "bar",
    "C": "classroom",
    "D": "dining booth",
    "S": "spa",
    "Z": "junk",
    "-": "no label",
}
"""Matterport3D region label codes (the ``R`` lines of a ``.house`` file) and their names."""


@dataclass(frozen=True)
class Level:
    """One floor of a building."""

    index: int
    z_floor: float
    z_ceiling: float


@dataclass(frozen=True)
class Region:
    """A room-like region: a floor polygon extruded by ``height`` from its level's floor."""

    index: int
    level: int
    label: str
    polygon: np.ndarray  # (K, 2) counter-clockwise
    bbox: np.ndarray  # (6,) xlo ylo zlo xhi yhi zhi
    height: float

    @property
    def name(self) -> str:
        """The label's English name, e.g. ``"bedroom"``."""
        return REGION_LABELS[self.label]

    def contains(self, xy: np.ndarray) -> bool:
        """True when the point ``xy`` lies inside the floor polygon (even-odd rule)."""
        x, y = float(xy[0]), float(xy[1])
        poly = self.polygon
        inside = False
        for (x0, y0), (x1, y1) in zip(poly, np.roll(poly, -1, axis=0), strict=True):
            if (y0 > y) != (y1 > y) and x < x0 + (y - y0) * (x1 - x0) / (y1 - y0):
                inside = not inside
        return inside


@dataclass(frozen=True)
class SceneObject:
    """A furniture-like object with an axis-aligned extent (landmarks, seats)."""

    index: int
    region: int
    category: str
    mpcat40: str
    bbox: np.ndarray  # (6,)
    yaw: float = 0.0
    seat_height: float | None = None  # for furniture people can sit on


@dataclass(frozen=True)
class Regions:
    """Levels, regions, objects and the viewpoint -> region map of a scan."""

    levels: tuple[Level, ...]
    regions: tuple[Region, ...]
    objects: tuple[SceneObject, ...] = ()
    viewpoint_region: dict[str, int] = field(default_factory=dict)

    def region_of(self, viewpoint: str) -> Region | None:
        """The region a viewpoint lies in, or None if it is not assigned."""
        index = self.viewpoint_region.get(viewpoint)
        return None if index is None else self.regions[index]

    def to_json(self) -> dict[str, Any]:
        """The regions file content (rounded to millimetres so output is stable)."""

        def r(a: np.ndarray) -> list[float]:
            return [round(float(v), 4) for v in np.asarray(a).ravel()]

        return {
            "levels": [
                {
                    "index": lv.index,
                    "z_floor": round(lv.z_floor, 4),
                    "z_ceiling": round(lv.z_ceiling, 4),
                }
                for lv in self.levels
            ],
            "regions": [
                {
                    "index": rg.index,
                    "level": rg.level,
                    "label": rg.label,
                    "polygon": [r(p) for p in rg.polygon],
                    "bbox": r(rg.bbox),
                    "height": round(rg.height, 4),
                }
                for rg in self.regions
            ],
            "objects": [
                {
                    "index": ob.index,
                    "region": ob.region,
                    "category": ob.category,
                    "mpcat40": ob.mpcat40,
                    "bbox": r(ob.bbox),
                    "yaw": round(ob.yaw, 4),
                    **({} if ob.seat_height is None else {"seat_height": ob.seat_height}),
                }
                for ob in self.objects
            ],
            "viewpoints": dict(self.viewpoint_region),
        }

    def write(self, path: Path) -> None:
        """Writes the regions file atomically."""
        atomic_write_json(path, self.to_json(), indent=1)

    @classmethod
    def from_json(cls, data: Any, source: str = "<regions>") -> Regions:
        """Parses a regions file's content, raising MalformedDataError naming the bad field."""
        try:
            levels = tuple(
                Level(int(lv["index"]), float(lv["z_floor"]), float(lv["z_ceiling"]))
                for lv in data["levels"]
            )
            regions = []
            for i, rg in enumerate(data["regions"]):
                label = rg["label"]
                if label not in REGION_LABELS:
                    raise MalformedDataError(
                        f"{source}: regions[{i}].label {label!r} is not a Matterport region code; "
                        f"valid: {' '.join(REGION_LABELS)}"
                    )
                polygon = np.asarray(rg["polygon"], dtype=float).reshape(-1, 2)
                regions.append(
                    Region(
                        index=int(rg["index"]),
                        level=int(rg["level"]),
                        label=label,
                        polygon=polygon,
                        bbox=np.asarray(rg["bbox"], dtype=float).reshape(6),
                        height=float(rg["height"]),
                    )
                )
            objects = tuple(
                SceneObject(
                    index=int(ob["index"]),
                    region=int(ob["region"]),
                    category=str(ob["category"]),
                    mpcat40=str(ob["mpcat40"]),
                    bbox=np.asarray(ob["bbox"], dtype=float).reshape(6),
                    yaw=float(ob.get("yaw", 0.0)),
                    seat_height=None if ob.get("seat_height") is None else float(ob["seat_height"]),
                )
                for ob in data.get("objects", [])
            )
            vp = {str(k): int(v) for k, v in data.get("viewpoints", {}).items()}
        except MalformedDataError:
            raise
        except (KeyError, TypeError, ValueError) as exc:
            raise MalformedDataError(f"{source}: not a valid regions file ({exc!r})") from exc
        for k, v in vp.items():
            if not 0 <= v < len(regions):
                raise MalformedDataError(
                    f"{source}: viewpoint {k!r} maps to region {v}, valid 0..{len(regions) - 1}"
                )
        return cls(levels, tuple(regions), objects, vp)

    @classmethod
    def read(cls, path: Path) -> Regions:
        """Reads a regions file."""
        if not path.is_file():
            raise MissingDataError(f"regions file not found: {path}")
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise MalformedDataError(f"{path}: invalid JSON ({exc})") from exc
        return cls.from_json(data, str(path))
