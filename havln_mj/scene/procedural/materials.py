"""Materials of one procedural house: the library (``assets/materials.json``) drawn per seed.

A :class:`Palette` picks each room's floor and walls from its room kind's options, and
furniture woods, fabrics and stones from the library's colour lists, all from the house's
look generator, so one seed always dresses its house the same way. Textures are generated
on first use (:mod:`havln_mj.scene.procedural.textures`) and shared by every material that
uses them; a material's colour tints its texture.
"""

from __future__ import annotations

import hashlib
import json
import zlib
from dataclasses import dataclass
from functools import cache, lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from havln_mj.errors import MalformedDataError
from havln_mj.paths import asset_path
from havln_mj.scene.procedural import textures as tx

FLOOR_TEXTURE = 512  # pixels per side of floor textures (wood grain needs the detail)
TEXTURE = 256  # pixels per side of the other surface textures


@dataclass(frozen=True)
class Material:
    """How a surface looks.

    Attributes:
        key: Unique name in the house (also the mesh material's name).
        rgba: Colour; it multiplies the texture. Alpha below 1 makes the surface blend.
        texture: Key of the texture image in the palette, or None for a plain colour.
        tile_m: Metres covered by one texture repeat; 0 when the surface's texture
            coordinates already span the image once (pictures, rugs, decals).
        shine: Gloss in [0, 1].
        emission: Self-lit share in [0, 1] (windows, lamp shades).
    """

    key: str
    rgba: tuple[float, float, float, float]
    texture: str | None = None
    tile_m: float = 0.0
    shine: float = 0.0
    emission: float = 0.0


@cache
def _library(path: Path) -> dict[str, Any]:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise MalformedDataError(f"{path}: invalid JSON ({exc})") from exc


def load_library(path: Path | None = None) -> dict[str, Any]:
    """The material library (``assets/materials.json`` unless ``path`` is given)."""
    return _library((path or asset_path("assets", "materials.json")).resolve())


def library_digest() -> str:
    """A digest of the built-in material library, recorded in a built scan's ``scan.json``."""
    return hashlib.sha256(asset_path("assets", "materials.json").read_bytes()).hexdigest()[:16]


def _rgba(colour: Any, alpha: float = 1.0) -> tuple[float, float, float, float]:
    c = [float(v) for v in colour][:3]
    return (c[0], c[1], c[2], float(alpha))


class Palette:
    """The materials and texture images of one house, made on demand.

    Args:
        rng: The house's look generator (its only source of randomness).
        library: The material library; the built-in one by default.
    """

    def __init__(self, rng: np.random.Generator, library: dict[str, Any] | None = None) -> None:
        self.rng = rng
        self.lib = library or load_library()
        self.textures: dict[str, np.ndarray] = {}  # key -> uint8 H×W×3 or ×4
        self.materials: dict[str, Material] = {}
        self._main_floor = self.pick(self.lib["rooms"]["l"]["floor"])

    # ------------------------------------------------------------------ helpers

    def pick(self, options: list) -> Any:
        """One of ``options``, uniformly."""
        return options[int(self.rng.integers(len(options)))]

    def _jitter(self, colour: Any, amount: float = 0.06) -> tuple[float, float, float]:
        c = np.clip(np.asarray(colour[:3], float) * self.rng.uniform(1 - amount, 1 + amount), 0, 1)
        return (float(c[0]), float(c[1]), float(c[2]))

    def texture(self, key: str, kind: str, size: int, *args: Any, variants: int = 3) -> str:
        """Registers texture ``key``: one of ``variants`` images of ``kind`` with ``args``.

        The house picks the variant; images are drawn once per process (see :func:`image`).
        """
        if key not in self.textures:
            variant = int(self.rng.integers(variants))
            self.textures[key] = image(kind, size, _frozen(args), variant)
        return key

    def add(self, material: Material) -> Material:
        """Registers ``material`` (the first one registered under a key wins)."""
        return self.materials.setdefault(material.key, material)

    def plain(self, key: str, colour: Any, shine: float = 0.0, emission: float = 0.0) -> Material:
        """An untextured material."""
        return self.add(Material(key, _rgba(colour), shine=shine, emission=emission))

    # ------------------------------------------------------------------ surfaces

    def _surface(self, name: str, spec: dict[str, Any], colour: Any, size: int) -> Material:
        """A tiled surface material from a library entry (floors and walls)."""
        kind = spec["texture"]
        if kind == "paint":  # matt paint: a plain colour (texturing it costs frame rate)
            return self.plain(name, colour, float(spec.get("shine", 0.0)))
        if kind in ("planks", "parquet"):
            key = self.texture(f"{kind}/{name}", kind, size)
        elif kind == "tiles":
            own = "colour" in spec  # floor tiles have their colours, wall tiles take the paint
            args = [spec.get(k) for k in ("count", "layout", "alternate", "grout")]
            key = self.texture(f"tiles/{name}", kind, size, spec.get("colour", (1, 1, 1)), *args)
            colour = (1.0, 1.0, 1.0) if own else colour
        elif kind == "wallpaper":
            key = self.texture(f"wallpaper/{spec['pattern']}", kind, size, spec["pattern"])
        else:  # greyscale textures tinted by the colour
            key = self.texture(kind, kind, size)
        return self.add(
            Material(
                name,
                _rgba(colour),
                key,
                float(spec["tile_m"]),
                float(spec.get("shine", 0.0)),
            )
        )

    def floor(self, kind: str) -> Material:
        """The floor of a room of region code ``kind`` (living areas share one main floor)."""
        options = self.lib["rooms"][kind]["floor"]
        name = self._main_floor if self._main_floor in options and self.rng.random() < 0.6 else None
        name = name or self.pick(options)
        spec = self.lib["floors"][name]
        return self._surface(f"floor/{name}", spec, spec["colour"], FLOOR_TEXTURE)

    def wall(self, kind: str, room: int) -> Material:
        """The walls of room ``room`` (region code ``kind``): paint, wallpaper or tiles."""
        room_lib = self.lib["rooms"][kind]
        name = self.pick(room_lib["wall"])
        colour = self._jitter(self.pick(self.lib["paints"][self.pick(room_lib["paints"])]), 0.03)
        spec = dict(self.lib["walls"][name])
        if spec["texture"] == "tiles":
            spec.setdefault("colour", colour)
        return self._surface(f"wall/{name}_{room}", spec, colour, TEXTURE)

    def ceiling(self) -> Material:
        """The ceiling paint."""
        spec = {"texture": "paint", "tile_m": 2.5}
        return self._surface("ceiling", spec, self.lib["ceiling"][0], TEXTURE)

    def rug_odds(self, kind: str) -> float:
        """How likely a room of this kind is to have a rug."""
        return float(self.lib["rooms"][kind].get("rug", 0.0))

    # ------------------------------------------------------------------ furnishings

    def wood(self, key: str = "wood") -> Material:
        """A wood finish (per key: one per piece of furniture or per house element)."""
        colour = self._jitter(self.pick(self.lib["woods"]))
        grain = self.texture("wood", "wood", TEXTURE)
        return self.add(Material(f"wood/{key}", _rgba(colour), grain, 0.8, 0.3))

    def painted(self, key: str) -> Material:
        """A painted or lacquered finish (cabinets, frames)."""
        colour = self._jitter(self.pick(self.lib["painted"]), 0.03)
        return self.plain(f"painted/{key}", colour, shine=0.25)

    def fabric(self, key: str, colours: str = "fabrics") -> Material:
        """Upholstery (``colours`` = ``"fabrics"``) or bed linen (``"bedding"``)."""
        colour = self._jitter(self.pick(self.lib[colours]))
        weave = self.texture("fabric", "fabric", TEXTURE)
        return self.add(Material(f"{colours}/{key}", _rgba(colour), weave, 0.35))

    def accent(self, key: str) -> Material:
        """A bright cushion or throw colour."""
        weave = self.texture("fabric", "fabric", TEXTURE)
        colour = self._jitter(self.pick(self.lib["accents"]))
        return self.add(Material(f"accent/{key}", _rgba(colour), weave, 0.35))

    def metal(self, name: str) -> Material:
        """Brushed ``steel``, ``black`` or ``brass`` metal."""
        streaks = self.texture("brushed", "brushed", TEXTURE)
        return self.add(
            Material(f"metal/{name}", _rgba(self.lib["metals"][name]), streaks, 0.5, 0.6)
        )

    def stone(self, key: str) -> Material:
        """A stone worktop."""
        ground, vein = self.pick(self.lib["stones"])
        stone = self.texture(f"stone/{key}", "marble", TEXTURE, ground, vein)
        return self.add(Material(f"stone/{key}", (1.0, 1.0, 1.0, 1.0), stone, 1.0, 0.5))

    def ceramic(self) -> Material:
        """Glazed white ceramic (toilets, basins, baths)."""
        return self.plain("ceramic", (0.95, 0.95, 0.96), shine=0.8)

    def image(
        self, key: str, kind: str, size: int, *args: Any, emission: float = 0.0, shine: float = 0.0
    ) -> Material:
        """A material showing one whole generated image (pictures, rugs, books, sky)."""
        self.texture(key, kind, size, *args, variants=4)
        return self.add(Material(key, (1.0, 1.0, 1.0, 1.0), key, 0.0, shine, emission))

    def decal(self, key: str, overlay: np.ndarray, emission: float = 0.0) -> Material:
        """A blended RGBA overlay (corner shading, contact shadows, patches of daylight)."""
        self.textures.setdefault(key, overlay)
        return self.add(Material(key, (1.0, 1.0, 1.0, 0.99), key, 0.0, emission=emission))


def _frozen(args: Any) -> Any:
    """Lists as tuples, recursively, so texture arguments can key a cache."""
    if isinstance(args, list | tuple):
        return tuple(_frozen(a) for a in args)
    return args


@lru_cache(maxsize=48)
def image(kind: str, size: int, args: tuple, variant: int) -> np.ndarray:
    """Variant ``variant`` of a texture: the same pixels for the same arguments, every time.

    Its generator is seeded from the arguments, not from a house, so houses share images and
    a process draws each one once (about 20 MB are kept).
    """
    seed = zlib.crc32(repr((kind, size, args)).encode())
    rng = np.random.default_rng([seed, variant])
    out = tx.to_uint8(tx.GENERATORS[kind](rng, size, *args))
    out.flags.writeable = False
    return out
