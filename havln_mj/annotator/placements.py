"""People placed by hand, read from and written to HA3D's placement file.

HA3D's ``human_motion_text.json`` maps scan → viewpoint → ``["region:activity", model id,
heading°]``: one person per viewpoint, a sentence prefixed by HA3D's region name, which of the
activity's motions plays (0–2) and the HA3D rotation angle (see
:func:`havln_mj.humans.population.ha3d_heading`). The simulator reads such a file with
``Simulator(humans=True, human_placements=path)`` and maps each sentence onto the closest
activity of our catalog; every catalog activity written as ``"<region>:<its text>"`` maps back
onto itself. A person read from a file keeps its original sentence until its activity is
changed, so saving what was loaded rewrites it unchanged.
"""

from __future__ import annotations

import json
import math
import numbers
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from havln_mj.errors import InvalidArgumentError, MalformedDataError
from havln_mj.humans.catalog import HA3D_REGIONS, Catalog
from havln_mj.humans.population import ha3d_heading, read_ha3d_placements
from havln_mj.scene.navgraph import NavGraph

MODELS = (0, 1, 2)
"""HA3D's motion model ids: the three motions generated for each activity sentence."""

HA3D_NAME = {code: name for name, code in HA3D_REGIONS.items()}
"""HA3D's region name (the part of a sentence before ':') of each region label code."""


@dataclass(frozen=True)
class Placement:
    """One person placed on a viewpoint.

    Attributes:
        viewpoint: The viewpoint they stand on.
        activity: Catalog activity id, e.g. ``"kitchen/dishwasher"``.
        model: HA3D motion model id (0, 1 or 2).
        heading: Which way they face, radians (0 faces +y, growing toward +x).
        sentence: The ``"region:activity"`` text read from a placement file, kept while the
            activity is the one it maps to; empty for people placed here.
    """

    viewpoint: str
    activity: str
    model: int = 0
    heading: float = 0.0
    sentence: str = ""


def ha3d_degrees(heading: float) -> float:
    """HA3D's placement angle for our heading (the inverse of ``ha3d_heading``)."""
    return round((180.0 - math.degrees(heading)) % 360.0, 3)


def to_entry(person: Placement, catalog: Catalog) -> list:
    """The HA3D entry ``["region:activity", model, heading°]`` of one person."""
    activity = catalog.get(person.activity)
    sentence = person.sentence or f"{HA3D_NAME[activity.region]}:{activity.text}"
    return [sentence, int(person.model), ha3d_degrees(person.heading)]


def from_entries(
    entries: Mapping[str, tuple[str, int, float]], catalog: Catalog
) -> list[Placement]:
    """People from one scan's HA3D entries, each with the activity the simulator maps it to.

    A sentence whose words tie between activities is settled by a fixed seed, so reading a
    file always gives the same people.
    """
    people = []
    for vp, (sentence, model, degrees) in entries.items():
        activity = catalog.map_ha3d(sentence, np.random.default_rng(0))
        people.append(Placement(vp, activity.id, int(model), ha3d_heading(degrees), sentence))
    return people


def check_people(people: Iterable[Placement], graph: NavGraph, catalog: Catalog) -> None:
    """Checks a set of people can be written as HA3D placements.

    Raises:
        UnknownViewpointError: A viewpoint the scan does not have.
        InvalidArgumentError: An unknown activity, a sitting activity (HA3D placements stand
            people on viewpoints and carry no seat), a model id other than 0–2, a non-finite
            heading, or two people on one viewpoint.
    """
    seen: set[str] = set()
    for p in people:
        graph.index(p.viewpoint)
        activity = catalog.get(p.activity)
        if activity.needs_seat and not p.sentence:
            raise InvalidArgumentError(
                f"activity {p.activity!r} sits: HA3D placements stand people on viewpoints; "
                "choose a standing or walking activity"
            )
        if isinstance(p.model, bool) or p.model not in MODELS:
            raise InvalidArgumentError(f"model must be one of {MODELS}, got {p.model!r}")
        if not (isinstance(p.heading, numbers.Real) and math.isfinite(p.heading)):
            raise InvalidArgumentError(f"heading must be a finite number, got {p.heading!r}")
        if p.viewpoint in seen:
            raise InvalidArgumentError(
                f"viewpoint {p.viewpoint!r} already has a person (HA3D places one per viewpoint)"
            )
        seen.add(p.viewpoint)


def load_people(path: Path, scene_id: str, catalog: Catalog) -> list[Placement]:
    """The people a placement file gives ``scene_id`` (none when the file does not exist).

    Raises:
        MalformedDataError: The file does not follow HA3D's schema.
        InvalidArgumentError: A sentence whose region HA3D does not name.
    """
    if not path.exists():
        return []
    return from_entries(read_ha3d_placements(path).get(scene_id, {}), catalog)


def save_people(path: Path, scene_id: str, people: Iterable[Placement], catalog: Catalog) -> None:
    """Writes ``scene_id``'s people into a placement file, keeping the other scans' entries.

    The file is replaced atomically (written beside it, then renamed). A scan left without
    people is removed from the file.

    Raises:
        MalformedDataError: The existing file is not an HA3D placement file.
    """
    data: dict = {}
    if path.exists():
        try:
            data = json.loads(path.read_text())
        except ValueError as exc:
            raise MalformedDataError(f"{path}: not JSON ({exc}); not overwriting it") from None
        if not isinstance(data, dict):
            raise MalformedDataError(f"{path}: expected {{scan: {{viewpoint: entry}}}}")
    entries = {p.viewpoint: to_entry(p, catalog) for p in people}
    if entries:
        data[scene_id] = entries
    else:
        data.pop(scene_id, None)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.name}.partial")
    partial.write_text(json.dumps(data, indent=1) + "\n")
    os.replace(partial, path)
