"""The procedural-house recipe (``scenes/procedural.json``): sizes, room kinds, furniture."""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from havln_mj.errors import MalformedDataError
from havln_mj.paths import asset_path


@dataclass(frozen=True)
class Recipe:
    """Parsed recipe. ``raw`` keeps the file content; ``digest`` identifies it in cache keys."""

    raw: dict[str, Any]
    digest: str

    def __getitem__(self, key: str) -> Any:
        try:
            return self.raw[key]
        except KeyError:
            raise MalformedDataError(f"procedural recipe has no field {key!r}") from None

    def room(self, kind: str) -> dict[str, Any]:
        """The recipe of one room kind (floor/wall colours and furniture list)."""
        return self["rooms"][kind]

    def furniture(self, name: str) -> dict[str, Any]:
        """The recipe of one furniture item (shape, size, category, colour, placement)."""
        return self["furniture"][name]


def _load(path: Path) -> Recipe:
    data = path.read_bytes()
    try:
        raw = json.loads(data)
    except json.JSONDecodeError as exc:
        raise MalformedDataError(f"{path}: invalid JSON ({exc})") from exc
    recipe = Recipe(raw, hashlib.sha256(data).hexdigest()[:16])
    for kind, room in raw["rooms"].items():
        for item, _, _ in room["furniture"]:
            if item not in raw["furniture"]:
                raise MalformedDataError(f"{path}: room {kind!r} lists unknown furniture {item!r}")
    return recipe


def load_recipe(path: Path | None = None) -> Recipe:
    """Loads the built-in recipe (or ``path``)."""
    return _load((path or asset_path("scenes", "procedural.json")).resolve())
