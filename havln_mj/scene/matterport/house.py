"""Parse a Matterport3D ``.house`` file (house_segmentations) into regions.

The result is a :class:`~havln_mj.scene.regions.Regions`. The file is ASCII: a first line
``ASCII 1.1``, then one record per line, fields separated by runs of spaces, the record type first
(see ``matterport_data_organization.md``)::

    H name label #images #panoramas #vertices #surfaces #segments #objects #categories
      #regions #portals #levels 0 0 0 0 0 xlo ylo zlo xhi yhi zhi 0 0 0 0 0
    L level_index #regions label px py pz xlo ylo zlo xhi yhi zhi 0 0 0 0 0
    R region_index level_index 0 0 label px py pz xlo ylo zlo xhi yhi zhi height 0 0 0 0
    P portal_index region0_index region1_index label xlo ylo zlo xhi yhi zhi 0 0 0 0
    S surface_index region_index 0 label px py pz nx ny nz xlo ylo zlo xhi yhi zhi 0 0 0 0 0
    V vertex_index surface_index label px py pz nx ny nz 0 0 0
    P name panorama_index region_index 0 px py pz 0 0 0 0 0
    I image_index panorama_index name camera_index yaw_index e00..e33 i00..i22 w h px py pz ...
    C category_index category_mapping_index category_mapping_name mpcat40_index mpcat40_name ...
    O object_index region_index category_index px py pz a0x a0y a0z a1x a1y a1z r0 r1 r2 ...
    E segment_index object_index id area px py pz xlo ylo zlo xhi yhi zhi 0 0 0 0 0

What is read:

- **Levels** (``L``): ``z_floor`` = bbox ``zlo``, ``z_ceiling`` = bbox ``zhi``.
- **Regions** (``R``): level, label code (codes outside
  :data:`~havln_mj.scene.regions.REGION_LABELS` become ``-``), bbox and height. The floor polygon is
  the vertex loop (``V``, in file order) of the region's floor surface (``S``): among its surfaces
  whose normal points up (``nz ≥ 0.5``, or all of them if none does), the one with the largest area.
  It is made counter-clockwise. A region without a usable surface (fewer than 3 vertices, zero area)
  gets its bbox rectangle. Regions are renumbered 0..N-1 in index order if the file skips indices.
- **Objects** (``O``): category from its ``C`` line (``category_mapping_name`` with ``#``
  read as a space; ``mpcat40_name``), or ``unknown``/``unlabeled`` for category -1. The
  oriented box (centre ``c``, unit axes ``a0``, ``a1``, ``a2 = a0 × a1``, radii ``r``) becomes
  the axis-aligned box ``c ± (|a0| r0 + |a1| r1 + |a2| r2)`` and ``yaw = atan2(a0y, a0x)``.
  Objects outside any region (region -1) are dropped: nothing can place them.
- **Panoramas** (``P``): viewpoint uuid -> region. Panoramas with region -1 are dropped.
- ``H``, ``I`` and ``E`` lines are checked for their type only.

**Portals and panoramas both use ``P``.** A ``P`` line is a *portal* when its second field
is an integer (portal index) and a *panorama* otherwise (its second field is the panorama's
name, a 32-hex uuid). A uuid made only of digits would read as a portal, so the header's
``#portals`` breaks that tie: once that many portals have been read, every further ``P``
line is a panorama. (The writer puts portals right after the regions and panoramas after the
vertices, so the header count alone also separates them; the field rule needs no ordering.)
Counts that disagree with the header are logged, not fatal: portals are not used.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Collection
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from havln_mj.errors import MalformedDataError, MissingDataError
from havln_mj.scene.regions import REGION_LABELS, Level, Region, Regions, SceneObject

log = logging.getLogger(__name__)

HEADER = "ASCII 1.1"
"""The first line of every supported ``.house`` file."""

# Fewest fields each record type must have (the fields read, plus the type letter).
_MIN_FIELDS = {"H": 13, "L": 13, "R": 16, "S": 11, "V": 7, "C": 6, "O": 16, "I": 1, "E": 1}
_MIN_PORTAL = 5
_MIN_PANORAMA = 4
_NO_CATEGORY = ("unknown", "unlabeled")


class _Line:
    """One record's fields with typed accessors whose errors name the file and line."""

    def __init__(self, path: Path, lineno: int, tokens: list[str]) -> None:
        self.path = path
        self.lineno = lineno
        self.tokens = tokens

    def error(self, message: str) -> MalformedDataError:
        return MalformedDataError(f"{self.path}:{self.lineno}: {self.tokens[0]} line: {message}")

    def integer(self, i: int, what: str) -> int:
        try:
            return int(self.tokens[i])
        except ValueError:
            raise self.error(
                f"{what} (field {i}) must be an integer, got {self.tokens[i]!r}"
            ) from None

    def number(self, i: int, what: str) -> float:
        try:
            value = float(self.tokens[i])
        except ValueError:
            raise self.error(
                f"{what} (field {i}) must be a number, got {self.tokens[i]!r}"
            ) from None
        if not math.isfinite(value):
            raise self.error(f"{what} (field {i}) must be finite, got {self.tokens[i]!r}")
        return value

    def numbers(self, i: int, n: int, what: str) -> np.ndarray:
        return np.array([self.number(i + k, f"{what}[{k}]") for k in range(n)])


def _is_int(text: str) -> bool:
    return text.lstrip("+-").isdigit()


def _lines(path: Path) -> list[_Line]:
    """The file's records (after the header), blank lines skipped."""
    if not path.is_file():
        raise MissingDataError(f"house file not found: {path}")
    try:
        text = path.read_bytes().decode("ascii")
    except UnicodeDecodeError as exc:
        raise MalformedDataError(
            f"{path}: not an ASCII .house file (non-ASCII byte at offset {exc.start})"
        ) from exc
    rows = text.splitlines()
    first = rows[0].strip() if rows else ""
    if first != HEADER:
        raise MalformedDataError(
            f"{path}: first line must be {HEADER!r} (a Matterport3D .house file), "
            f"found {first[:40]!r}"
        )
    out = []
    for lineno, row in enumerate(rows[1:], start=2):
        tokens = row.split()
        if tokens:
            out.append(_Line(path, lineno, tokens))
    return out


def _ccw(polygon: np.ndarray) -> tuple[np.ndarray, float]:
    """The polygon counter-clockwise, and its (unsigned) area."""
    x, y = polygon[:, 0], polygon[:, 1]
    signed = 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))
    return (polygon if signed >= 0 else polygon[::-1].copy()), abs(signed)


def _bbox_rectangle(bbox: np.ndarray) -> np.ndarray:
    xlo, ylo, _, xhi, yhi, _ = bbox
    return np.array([[xlo, ylo], [xhi, ylo], [xhi, yhi], [xlo, yhi]], dtype=float)


def _floor_polygon(surfaces: list[tuple[float, list[np.ndarray]]], bbox: np.ndarray) -> np.ndarray:
    """The floor polygon from a region's surfaces ``(normal z, vertex xy list)``."""
    upward = [s for s in surfaces if s[0] >= 0.5] or surfaces
    best, best_area = None, 0.0
    for _, verts in upward:
        if len(verts) < 3:
            continue
        polygon, area = _ccw(np.array(verts, dtype=float))
        if area > best_area:
            best, best_area = polygon, area
    return best if best is not None else _bbox_rectangle(bbox)


def _axis_aligned(line: _Line) -> tuple[np.ndarray, float]:
    """An ``O`` line's oriented box as an axis-aligned bbox and a yaw."""
    center = line.numbers(4, 3, "center")
    axes = [line.numbers(7, 3, "axis0"), line.numbers(10, 3, "axis1")]
    radii = np.abs(line.numbers(13, 3, "radius"))
    for k, axis in enumerate(axes):
        norm = float(np.linalg.norm(axis))
        if norm == 0.0:
            raise line.error(f"axis{k} is the zero vector")
        axes[k] = axis / norm
    axes.append(np.cross(axes[0], axes[1]))
    half = sum(np.abs(a) * r for a, r in zip(axes, radii, strict=True))
    bbox = np.concatenate([center - half, center + half])
    return bbox, math.atan2(axes[0][1], axes[0][0])


def read_house(path: Path, viewpoint_ids: Collection[str] | None = None) -> Regions:
    """Reads a Matterport3D ``.house`` file as levels, regions, objects and viewpoint regions.

    Args:
        path: The ``<scan>.house`` file.
        viewpoint_ids: When given, only these viewpoints are kept in the viewpoint -> region
            map (e.g. the connectivity file's ids).

    Returns:
        The regions (see the module docstring for what is read and how).

    Raises:
        MissingDataError: The file does not exist.
        MalformedDataError: The file is not ``ASCII 1.1`` or a line is malformed; the message
            names the file, the line number and the field.
    """
    path = Path(path)
    records = _Records()
    for line in _lines(path):
        records.add(line)
    renumber = {old: new for new, old in enumerate(sorted(records.regions))}
    regions = records.out_regions(path, renumber)
    objects = records.out_objects(renumber)
    viewpoint_region = records.viewpoint_regions(renumber, viewpoint_ids)
    records.check_counts(path)
    return Regions(
        levels=tuple(sorted(records.levels, key=lambda lv: lv.index)),
        regions=tuple(regions),
        objects=tuple(objects),
        viewpoint_region=viewpoint_region,
    )


@dataclass
class _Records:
    """A ``.house`` file's records as read, line by line, before they are joined up."""

    header_counts: dict[str, int] = field(default_factory=dict)
    levels: list[Level] = field(default_factory=list)
    regions: dict[int, tuple[_Line, int, str, np.ndarray, float]] = field(default_factory=dict)
    surfaces: dict[int, tuple[int, float]] = field(default_factory=dict)  # -> (region, nz)
    vertices: dict[int, list[np.ndarray]] = field(default_factory=dict)  # surface -> xy, in order
    categories: dict[int, tuple[str, str]] = field(default_factory=dict)
    objects: list[tuple[_Line, int, int, int]] = field(
        default_factory=list
    )  # line, index, region, category
    panoramas: dict[str, tuple[_Line, int]] = field(default_factory=dict)
    n_portals: int = 0

    def add(self, line: _Line) -> None:
        """Reads one record line (raises on a malformed one)."""
        kind = line.tokens[0]
        if kind == "P":
            self._add_p(line)
            return
        if kind not in _MIN_FIELDS:
            raise line.error(f"unknown record type {kind!r}; expected one of H L R P S V I C O E")
        if len(line.tokens) < _MIN_FIELDS[kind]:
            raise line.error(f"needs at least {_MIN_FIELDS[kind]} fields, got {len(line.tokens)}")
        if kind == "H":
            names = ("images", "panoramas", "vertices", "surfaces", "segments", "objects")
            names += ("categories", "regions", "portals", "levels")
            self.header_counts = {n: line.integer(3 + k, f"#{n}") for k, n in enumerate(names)}
        elif kind == "L":
            bbox = line.numbers(7, 6, "bbox")
            self.levels.append(
                Level(line.integer(1, "level_index"), float(bbox[2]), float(bbox[5]))
            )
        elif kind == "R":
            index = line.integer(1, "region_index")
            if index in self.regions:
                raise line.error(
                    f"region {index} already defined on line {self.regions[index][0].lineno}"
                )
            label = line.tokens[5] if line.tokens[5] in REGION_LABELS else "-"
            bbox = line.numbers(9, 6, "bbox")
            height = line.number(15, "height")
            self.regions[index] = (line, line.integer(2, "level_index"), label, bbox, height)
        elif kind == "S":
            index = line.integer(1, "surface_index")
            self.surfaces[index] = (line.integer(2, "region_index"), line.number(10, "nz"))
        elif kind == "V":
            surface = line.integer(2, "surface_index")
            self.vertices.setdefault(surface, []).append(line.numbers(4, 2, "position"))
        elif kind == "C":
            index = line.integer(1, "category_index")
            line.integer(2, "category_mapping_index")
            line.integer(4, "mpcat40_index")
            self.categories[index] = (line.tokens[3].replace("#", " "), line.tokens[5])
        elif kind == "O":
            self.objects.append(
                (
                    line,
                    line.integer(1, "object_index"),
                    line.integer(2, "region_index"),
                    line.integer(3, "category_index"),
                )
            )

    def _add_p(self, line: _Line) -> None:
        """A ``P`` line: a portal or a panorama (see the module docstring)."""
        portal = _is_int(line.tokens[1]) if len(line.tokens) > 1 else False
        if portal and self.n_portals >= self.header_counts.get("portals", math.inf):
            portal = False  # all portals read already: a uuid made of digits
        need = _MIN_PORTAL if portal else _MIN_PANORAMA
        if len(line.tokens) < need:
            what = "portal" if portal else "panorama"
            raise line.error(f"a {what} line needs at least {need} fields, got {len(line.tokens)}")
        if portal:
            for i, what in ((1, "portal_index"), (2, "region0_index"), (3, "region1_index")):
                line.integer(i, what)
            self.n_portals += 1
            return
        name = line.tokens[1]
        line.integer(2, "panorama_index")
        if name in self.panoramas:
            raise line.error(
                f"panorama {name!r} already defined on line {self.panoramas[name][0].lineno}"
            )
        self.panoramas[name] = (line, line.integer(3, "region_index"))

    def out_regions(self, path: Path, renumber: dict[int, int]) -> list[Region]:
        """The regions in index order, each with its floor polygon."""
        by_region: dict[int, list[tuple[float, list[np.ndarray]]]] = {}
        for surface, (region, nz) in self.surfaces.items():
            by_region.setdefault(region, []).append((nz, self.vertices.get(surface, [])))
        for surface in self.vertices:
            if surface not in self.surfaces:
                log.warning("%s: vertices reference surface %d, which has no S line", path, surface)
        out = []
        for old in renumber:
            _, level, label, bbox, height = self.regions[old]
            polygon = _floor_polygon(by_region.get(old, []), bbox)
            out.append(Region(renumber[old], level, label, polygon, bbox, height))
        return out

    def out_objects(self, renumber: dict[int, int]) -> list[SceneObject]:
        """The objects inside a region, with their categories' names."""
        out = []
        for line, index, region, category in self.objects:
            if region < 0:
                continue
            if region not in renumber:
                raise line.error(f"object {index} refers to region {region}, which has no R line")
            if category < 0:
                names = _NO_CATEGORY
            elif category in self.categories:
                names = self.categories[category]
            else:
                raise line.error(
                    f"object {index} refers to category {category}, which has no C line"
                )
            bbox, yaw = _axis_aligned(line)
            out.append(SceneObject(index, renumber[region], names[0], names[1], bbox, yaw))
        return out

    def viewpoint_regions(
        self, renumber: dict[int, int], viewpoint_ids: Collection[str] | None
    ) -> dict[str, int]:
        """Viewpoint -> region, for the panoramas in a region (and in ``viewpoint_ids``)."""
        keep = None if viewpoint_ids is None else set(viewpoint_ids)
        out = {}
        for name, (line, region) in self.panoramas.items():
            if region < 0 or (keep is not None and name not in keep):
                continue
            if region not in renumber:
                raise line.error(
                    f"panorama {name!r} refers to region {region}, which has no R line"
                )
            out[name] = renumber[region]
        return out

    def check_counts(self, path: Path) -> None:
        """Logs the counts that disagree with the header's."""
        found = {"panoramas": len(self.panoramas), "portals": self.n_portals}
        found |= {"regions": len(self.regions), "levels": len(self.levels)}
        found |= {"objects": len(self.objects), "categories": len(self.categories)}
        for what, n in found.items():
            if what in self.header_counts and self.header_counts[what] != n:
                log.warning(
                    "%s: header says %d %s, found %d", path, self.header_counts[what], what, n
                )


def read_object_classes(path: Path | str) -> dict[int, tuple[str, int]]:
    """Each object's category name and mpcat40 index, by ``O`` line object index.

    Objects with category -1 read ``("unknown", 41)`` (mpcat40's ``unlabeled``).

    Raises:
        MissingDataError: The file does not exist.
        MalformedDataError: The file is not ``ASCII 1.1``, or a ``C`` or ``O`` line is
            malformed or refers to a missing category.
    """
    path = Path(path)
    categories: dict[int, tuple[str, int]] = {}
    objects: list[tuple[_Line, int, int]] = []
    for line in _lines(path):
        kind = line.tokens[0]
        if kind not in ("C", "O"):
            continue
        if len(line.tokens) < _MIN_FIELDS[kind]:
            raise line.error(f"needs at least {_MIN_FIELDS[kind]} fields, got {len(line.tokens)}")
        if kind == "C":
            mpcat40 = line.integer(4, "mpcat40_index")
            categories[line.integer(1, "category_index")] = (
                line.tokens[3].replace("#", " "),
                mpcat40,
            )
        else:
            objects.append(
                (line, line.integer(1, "object_index"), line.integer(3, "category_index"))
            )
    out = {}
    for line, index, category in objects:
        if category < 0:
            out[index] = (_NO_CATEGORY[0], 41)
        elif category in categories:
            out[index] = categories[category]
        else:
            raise line.error(f"object {index} refers to category {category}, which has no C line")
    return out
