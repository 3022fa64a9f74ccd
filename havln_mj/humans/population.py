"""Who is where, doing what: placing people in a scan the way HA3D does.

HA3D's rule: a building gets ``ceil(floor area / 67 m²)`` people, each on a viewpoint of a
region whose kind has activities, at least 3 m from one another. Each person faces into
their room (toward the region's centre). Sitting activities need a seat in the region
(furniture with a seat height; the person sits on it, facing away from its back); walking
activities pace along a graph edge to a neighbouring viewpoint on the same floor. An
activity whose needs are not met is swapped for another of the region.

For the real Matterport scans HA3D's own placement file (scan → viewpoint → ["region:
activity", model id, heading°]) can be used instead; its activities are mapped onto our
catalog by region.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from havln_mj.errors import MalformedDataError, MissingDataError
from havln_mj.frames import heading_to
from havln_mj.humans.body import random_body
from havln_mj.humans.catalog import Catalog, load_catalog, make_clip
from havln_mj.humans.crowd import Crowd, Person
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.regions import Regions, SceneObject
from havln_mj.scene.scan import Scan

AREA_PER_PERSON = 67.0  # m² of floor per person (HA3D)
MIN_SEPARATION = 3.0  # metres between people (HA3D)
SEAT_REACH = 3.0  # metres: a seat this close to the viewpoint may be used
SEAT_DEPTH_IN = 0.25  # metres from a seat's front edge to where the pelvis sits
SEAT_CATEGORIES = ("sofa", "chair", "bed", "seating", "toilet")


def people_count(regions: Regions) -> int:
    """HA3D's head count: one person per 67 m² of region floor (at least one)."""
    area = sum(_polygon_area(r.polygon) for r in regions.regions if r.label not in ("-", "Z"))
    return max(1, math.ceil(area / AREA_PER_PERSON))


def _polygon_area(poly: np.ndarray) -> float:
    x, y = np.asarray(poly, float).T
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def _seat_pose(obj: SceneObject) -> tuple[np.ndarray, float]:
    """Where a seated person's feet-centre goes on the floor, and which way they face.

    Seats have their back toward local +y (rotated by ``yaw``), so the sitter faces local −y.
    """
    lo, hi = obj.bbox[:3], obj.bbox[3:]
    centre = (lo + hi) / 2
    face = np.array([math.sin(obj.yaw), -math.cos(obj.yaw)])  # local −y turned by yaw
    depth = abs(face[0]) * (hi[0] - lo[0]) + abs(face[1]) * (hi[1] - lo[1])
    spot = centre[:2] + face * (depth / 2 - SEAT_DEPTH_IN)
    return np.array([spot[0], spot[1], lo[2]]), math.atan2(face[0], face[1]) % (2 * math.pi)


def _spread(graph: NavGraph, candidates: list[str], n: int, rng: np.random.Generator) -> list[str]:
    """Up to ``n`` of ``candidates`` in random order, each ≥ MIN_SEPARATION from the others."""
    chosen: list[str] = []
    for k in rng.permutation(len(candidates)):
        vp = candidates[int(k)]
        p = graph.position(vp)
        if all(np.linalg.norm(graph.position(c) - p) >= MIN_SEPARATION for c in chosen):
            chosen.append(vp)
            if len(chosen) == n:
                break
    return chosen


def populate(
    scan: Scan, rng: np.random.Generator, catalog: Catalog | None = None, count: int | None = None
) -> Crowd:
    """People placed in ``scan`` by HA3D's rule.

    Args:
        scan: The building (its graph, regions and seats are used).
        rng: The only source of randomness.
        catalog: Activities by region (default: the built-in catalog).
        count: Head count (default: ``people_count``).
    """
    catalog = catalog or load_catalog()
    graph, regions = scan.graph, scan.regions
    known = set(catalog.regions())
    candidates = []
    for vp in graph.nodes:
        region = regions.region_of(vp)
        if region is not None and region.label in known:
            candidates.append(vp)
    chosen = _spread(graph, candidates, count or people_count(regions), rng)
    used_seats: set[int] = set()
    people = []
    for vp in chosen:
        region = regions.region_of(vp)
        assert region is not None
        pos, floor = graph.position(vp), graph.floor_z(vp)
        seats = [
            o
            for o in regions.objects
            if o.seat_height is not None
            and o.region == region.index
            and o.mpcat40 in SEAT_CATEGORIES
            and o.index not in used_seats
            and np.linalg.norm((o.bbox[:2] + o.bbox[3:5]) / 2 - pos[:2]) <= SEAT_REACH
        ]
        walk_to = [
            n
            for n in graph.neighbors(vp)
            if abs(graph.floor_z(n) - floor) < 0.3
            and 1.0 <= np.linalg.norm(graph.position(n)[:2] - pos[:2]) <= 6.0
        ]
        shape = random_body(rng)
        for activity in (
            catalog.activities(region.label)[int(k)]
            for k in rng.permutation(len(catalog.activities(region.label)))
        ):
            if activity.needs_seat and not seats:
                continue
            if activity.needs_path and not walk_to:
                continue
            break
        else:
            continue  # nothing this region offers fits here
        if activity.needs_seat:
            seat = min(seats, key=lambda o: np.linalg.norm(o.bbox[:2] - pos[:2]))
            used_seats.add(seat.index)
            anchor, heading = _seat_pose(seat)
            clip = make_clip(activity, shape.height, rng, seat_height=seat.seat_height)
        elif activity.needs_path:
            target = walk_to[int(rng.integers(len(walk_to)))]
            anchor, heading = np.array([pos[0], pos[1], floor]), 0.0
            path = np.array([[0.0, 0.0], graph.position(target)[:2] - pos[:2]])
            clip = make_clip(activity, shape.height, rng, path=path)
        else:
            anchor = np.array([pos[0], pos[1], floor])
            centre = region.polygon.mean(axis=0)
            heading = (
                heading_to(pos, centre)
                if np.linalg.norm(centre - pos[:2]) > 0.3
                else float(rng.uniform(0, 2 * math.pi))
            )
            clip = make_clip(activity, shape.height, rng)
        people.append(
            Person(
                shape,
                clip,
                anchor,
                heading,
                activity.id,
                activity.text,
                region.label,
                vp,
                float(rng.uniform(0.0, max(clip.duration, 1e-9))),
            )
        )
    return Crowd(people)


def read_ha3d_placements(path: Path | str) -> dict[str, dict[str, tuple[str, int, float]]]:
    """HA3D's ``human_motion_text.json``: scan → viewpoint → (region:activity, model, heading°).

    Raises:
        MissingDataError: The file does not exist.
        MalformedDataError: It does not follow that schema.
    """
    path = Path(path)
    if not path.is_file():
        raise MissingDataError(f"HA3D placement file not found: {path}")
    try:
        raw = json.loads(path.read_text())
        return {
            scan: {vp: (str(e[0]), int(e[1]), float(e[2])) for vp, e in entries.items()}
            for scan, entries in raw.items()
        }
    except (ValueError, TypeError, IndexError, AttributeError) as exc:
        raise MalformedDataError(
            f"{path}: expected {{scan: {{viewpoint: ['region:activity', model id, heading°]}}}} "
            f"({exc})"
        ) from None


def ha3d_heading(degrees: float) -> float:
    """Our heading for an HA3D placement angle.

    HA3D turns the SMPL body (facing +z, y up) by ``degrees`` about y, then maps
    ``(x, y, z) → (x, −z, y)``: the body faces ``(sin θ, −cos θ)``, which is heading π − θ.
    """
    return (math.pi - math.radians(degrees)) % (2 * math.pi)


def populate_ha3d(
    graph: NavGraph,
    entries: dict[str, tuple[str, int, float]],
    rng: np.random.Generator,
    catalog: Catalog | None = None,
) -> Crowd:
    """People at HA3D's placements for one scan, doing our nearest activity of their region.

    Sitting activities are swapped for standing ones (the placement gives no seat); walking
    ones pace toward a neighbouring viewpoint when there is one on the same floor.
    """
    catalog = catalog or load_catalog()
    people = []
    for vp, (text, _model, degrees) in sorted(entries.items()):
        if vp not in graph:
            raise MalformedDataError(
                f"HA3D placement viewpoint {vp!r} is not an included viewpoint of {graph.name}"
            )
        activity = catalog.map_ha3d(text, rng)
        pos, floor = graph.position(vp), graph.floor_z(vp)
        walk_to = [
            n
            for n in graph.neighbors(vp)
            if abs(graph.floor_z(n) - floor) < 0.3
            and 1.0 <= np.linalg.norm(graph.position(n)[:2] - pos[:2]) <= 6.0
        ]
        if activity.needs_seat or (activity.needs_path and not walk_to):
            standing = [
                a
                for a in catalog.activities(activity.region)
                if not a.needs_seat and not a.needs_path
            ]
            activity = standing[int(rng.integers(len(standing)))]
        shape = random_body(rng)
        anchor = np.array([pos[0], pos[1], floor])
        heading = ha3d_heading(degrees)
        if activity.needs_path:
            target = walk_to[int(rng.integers(len(walk_to)))]
            path = np.array([[0.0, 0.0], graph.position(target)[:2] - pos[:2]])
            clip = make_clip(activity, shape.height, rng, path=path)
            heading = 0.0
        else:
            clip = make_clip(activity, shape.height, rng)
        people.append(
            Person(
                shape,
                clip,
                anchor,
                heading,
                activity.id,
                activity.text,
                activity.region,
                vp,
                float(rng.uniform(0.0, max(clip.duration, 1e-9))),
            )
        )
    return Crowd(people)
