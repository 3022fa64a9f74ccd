"""Matterport's mpcat40 object categories, and the labels of a scan mesh's parts.

mpcat40 (``metadata/mpcat40.tsv`` of the Matterport3D release) numbers 42 categories
0..41: 0 ``void``, 1 ``wall``, 2 ``floor`` ... 40 ``misc``, 41 ``unlabeled``. People are
not one of them (Matterport3D scans hold none), so havln_mj adds :data:`PERSON` = 42.

A scan folder may hold ``semantics.json``: the object instances of the building (id >= 1,
category name, mpcat40 index, region, index in ``regions.json`` objects) and, for each
visual mesh part (by name), the instance it belongs to::

    {"instances": [{"id": 1, "category": "wall", "mpcat40": 1, "region": 0, "object": null}],
     "parts": {"1:wall/paint_0": 1}}
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from havln_mj.cache import atomic_write_json
from havln_mj.errors import MalformedDataError, MissingDataError

MPCAT40 = (
    "void", "wall", "floor", "chair", "door", "table", "picture", "cabinet", "cushion",
    "window", "sofa", "bed", "curtain", "chest_of_drawers", "plant", "sink", "stairs",
    "ceiling", "toilet", "stool", "towel", "mirror", "tv_monitor", "shower", "column",
    "bathtub", "counter", "fireplace", "lighting", "beam", "railing", "shelving", "blinds",
    "gym_equipment", "seating", "board_panel", "furniture", "appliances", "clothes",
    "objects", "misc", "unlabeled",
)  # fmt: skip
"""mpcat40 category names by index."""

PERSON = 42
"""The class of people (havln_mj's addition after mpcat40's 0..41)."""

CLASS_NAMES = (*MPCAT40, "person")
"""Names of every semantic class a havln_mj camera reports, by index."""

MPCAT40_COLOURS = (
    "ffffff", "aec7e8", "708090", "98df8a", "c5b0d5", "ff7f0e", "d62728", "1f77b4", "bcbd22",
    "ff9896", "2ca02c", "e377c2", "de9ed6", "9467bd", "8ca252", "843c39", "9edae5", "9c9ede",
    "e7969c", "637939", "8c564b", "dbdb8d", "d6616b", "cedb9c", "e7ba52", "393b79", "a55194",
    "ad494a", "b5cf6b", "5254a3", "bd9e39", "c49c94", "f7b6d2", "6b6ecf", "ffbb78", "c7c7c7",
    "8c6d31", "e7cb94", "ce6dbd", "17becf", "7f7f7f", "000000",
)  # fmt: skip
"""mpcat40's display colour of each category (hex RGB), from its table."""


_INDEX = {name: k for k, name in enumerate(MPCAT40)}


def mpcat40_index(name: str) -> int:
    """The mpcat40 index of a category name.

    Raises:
        MalformedDataError: ``name`` is not an mpcat40 category.
    """
    try:
        return _INDEX[name]
    except KeyError:
        raise MalformedDataError(
            f"{name!r} is not an mpcat40 category; valid: {', '.join(MPCAT40)}"
        ) from None


@dataclass(frozen=True)
class LabelMesh:
    """Triangles of one labelled object instance (vertices in the world frame)."""

    name: str
    vertices: np.ndarray  # (V, 3)
    faces: np.ndarray  # (F, 3)
    semantic: int
    instance: int


@dataclass(frozen=True)
class Instance:
    """One object instance of a building.

    Attributes:
        id: Instance id, >= 1 (0 means "no instance").
        category: Its own category name (e.g. ``"sofa cushion"``, ``"skirting"``).
        mpcat40: Its mpcat40 class index.
        region: Index of its region, or -1.
        object: Index of the ``regions.json`` object (a piece of furniture) it is or is part
            of (a sofa's cushion, a shelf's books), or None.
    """

    id: int
    category: str
    mpcat40: int
    region: int = -1
    object: int | None = None


@dataclass(frozen=True)
class SceneLabels:
    """The instances of a building and the instance of each visual mesh part."""

    instances: tuple[Instance, ...]
    parts: dict[str, int]

    def instance(self, part: str) -> Instance | None:
        """The instance of a mesh part by name, or None if the part is unlabelled."""
        iid = self.parts.get(part)
        return None if iid is None else self._by_id[iid]

    @cached_property
    def _by_id(self) -> dict[int, Instance]:
        return {inst.id: inst for inst in self.instances}

    def to_json(self) -> dict:
        """The ``semantics.json`` content."""
        return {
            "instances": [
                {
                    "id": i.id,
                    "category": i.category,
                    "mpcat40": i.mpcat40,
                    "region": i.region,
                    "object": i.object,
                }
                for i in self.instances
            ],
            "parts": dict(self.parts),
        }

    def write(self, path: Path) -> None:
        """Writes ``semantics.json`` atomically."""
        atomic_write_json(path, self.to_json(), separators=(",", ":"))

    @classmethod
    def read(cls, path: Path) -> SceneLabels:
        """Reads ``semantics.json``, raising MalformedDataError naming what is wrong."""
        if not path.is_file():
            raise MissingDataError(f"semantics file not found: {path}")
        try:
            raw = json.loads(path.read_text(encoding="utf-8"))
            instances = tuple(
                Instance(
                    int(i["id"]),
                    str(i["category"]),
                    int(i["mpcat40"]),
                    int(i.get("region", -1)),
                    None if i.get("object") is None else int(i["object"]),
                )
                for i in raw["instances"]
            )
            parts = {str(k): int(v) for k, v in raw["parts"].items()}
        except (json.JSONDecodeError, UnicodeDecodeError, KeyError, TypeError, ValueError) as exc:
            raise MalformedDataError(f"{path}: not a valid semantics file ({exc!r})") from exc
        ids = {i.id for i in instances}
        if len(ids) != len(instances) or min(ids, default=1) < 1:
            raise MalformedDataError(f"{path}: instance ids must be unique and >= 1")
        bad = [i for i in instances if not 0 <= i.mpcat40 < len(MPCAT40)]
        if bad:
            raise MalformedDataError(
                f"{path}: instance {bad[0].id} has mpcat40 {bad[0].mpcat40}, valid 0..41"
            )
        unknown = sorted(set(parts.values()) - ids)
        if unknown:
            raise MalformedDataError(f"{path}: parts refer to unknown instance {unknown[0]}")
        return cls(instances, parts)
