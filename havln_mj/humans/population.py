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

User-supplied data (:class:`Sources`) changes how people look and move: with a HAPS folder,
HA3D placements play their own HAPS motion and standing activities in procedural houses play a
HAPS motion of their region; with an SMPL model file, people are skinned SMPL meshes of random
shape instead of the built-in bodies.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from havln_mj.errors import MalformedDataError, MissingDataError
from havln_mj.frames import heading_to
from havln_mj.humans.anny_data import load_anny_catalog
from havln_mj.humans.anny_mujoco import AnnyLook
from havln_mj.humans.anny_rig import fit
from havln_mj.humans.body import BodyShape, random_body
from havln_mj.humans.catalog import HA3D_REGIONS, Activity, Catalog, load_catalog, make_clip
from havln_mj.humans.clip import Clip
from havln_mj.humans.crowd import Crowd, Person
from havln_mj.humans.loaders import LoadedMotion, haps_dir_name
from havln_mj.humans.outfits import random_outfit
from havln_mj.humans.skeleton import MAX_HEIGHT, MIN_HEIGHT
from havln_mj.humans.skinned import Skin
from havln_mj.humans.smpl_model import SmplModel
from havln_mj.humans.together import conversation, handover, side_by_side
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.regions import Regions, SceneObject
from havln_mj.scene.scan import Scan

AREA_PER_PERSON = 67.0  # m² of floor per person (HA3D)
MIN_SEPARATION = 3.0  # metres between people (HA3D)
SEAT_REACH = 3.0  # metres: a seat this close to the viewpoint may be used
SEAT_DEPTH_IN = 0.25  # metres from a seat's front edge to where the pelvis sits
SEAT_CATEGORIES = ("sofa", "chair", "bed", "seating", "toilet")


@dataclass(frozen=True)
class Sources:
    """Motion and body data the user supplies.

    Attributes:
        haps: HAPS motions by prompt folder name (``loaders.load_haps_folder``), or None.
        smpl: An SMPL model to skin people with, or None.
        anny: Draw people as bodies of the shipped Anny catalog, dressed (else as capsule
            mannequins); an SMPL model takes precedence.
    """

    haps: dict[str, list[LoadedMotion]] | None = None
    smpl: SmplModel | None = None
    anny: bool = True

    def haps_for_region(self, code: str) -> list[LoadedMotion]:
        """The HAPS motions whose prompt's region is ``code``."""
        out = []
        for name, motions in (self.haps or {}).items():
            if _HAPS_REGION.get(_letters(name.split(":", 1)[0])) == code:
                out += motions
        return out

    def skin(self, rng: np.random.Generator) -> Skin | None:
        """A skin of random shape (betas ~ N(0, 1)), or None without a model."""
        return None if self.smpl is None else Skin(self.smpl, rng.normal(0.0, 1.0, 10))


def _letters(text: str) -> str:
    return "".join(c for c in text.lower() if c.isalpha())


# HAPS folder names replace ' ' and '/' by '_': match their regions on letters only.
_HAPS_REGION = {_letters(name): code for name, code in HA3D_REGIONS.items()}


def anny_shape(rng: np.random.Generator, base: BodyShape | None = None) -> BodyShape:
    """A random catalog body, fitted and dressed, as a shape (its height fits its clips).

    Args:
        rng: The source of the choice of body, outfit and fabric.
        base: Shape whose girth the capsule stand-in keeps (default: average).
    """
    catalog = load_anny_catalog()
    body = catalog.bodies[int(rng.integers(len(catalog)))]
    outfit = random_outfit(rng, body)
    rig = fit(body)
    look = AnnyLook(rig, outfit, int(rng.integers(2**31)))
    girth = base.girth if base is not None else 1.0
    return BodyShape(
        rig.clip_height, girth, outfit.skin, outfit.top, outfit.bottom_rgb, outfit.shoes, look
    )


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


def _walk_targets(graph: NavGraph, vp: str) -> list[str]:
    """Neighbours a person at ``vp`` can pace to: same floor, 1–6 m away."""
    pos, floor = graph.position(vp), graph.floor_z(vp)
    return [
        n
        for n in graph.neighbors(vp)
        if abs(graph.floor_z(n) - floor) < 0.3
        and 1.0 <= np.linalg.norm(graph.position(n)[:2] - pos[:2]) <= 6.0
    ]


class _Builder:
    """Makes people: a body (or skin), a clip for an activity, a start offset."""

    def __init__(self, rng: np.random.Generator, sources: Sources | None) -> None:
        self.rng = rng
        self.sources = sources or Sources()
        # Looks come from a child stream: choosing bodies and clothes leaves the placement
        # and motion draws of ``rng`` as they were.
        self.looks = rng.spawn(1)[0]

    def body(self) -> tuple[BodyShape, Skin | None]:
        shape = random_body(self.rng)
        if self.sources.anny and self.sources.smpl is None:
            return anny_shape(self.looks, shape), None
        skin = self.sources.skin(self.rng)
        if skin is not None:
            # Motions are made for the skin's own height, so its feet meet the floor.
            rest = skin.model.shaped(skin.betas)
            height = float(np.clip(np.ptp(rest[:, 1]), MIN_HEIGHT, MAX_HEIGHT))  # SMPL: y up
            shape = replace(shape, height=height)
        return shape, skin

    def person(
        self,
        body: tuple[BodyShape, Skin | None],
        clip: Clip,
        anchor: np.ndarray,
        heading: float,
        activity: Activity,
        viewpoint: str,
        text: str = "",
    ) -> Person:
        shape, skin = body
        offsets = getattr(clip, "offsets", None)  # loaded motions bring their own skeleton
        if skin is not None and offsets is not None:
            skin = None  # a loaded motion keeps its source's proportions: built-in body
        return Person(
            shape,
            clip,
            anchor,
            heading,
            activity.id,
            text or activity.text,
            activity.region,
            viewpoint,
            float(self.rng.uniform(0.0, max(clip.duration, 1e-9))),
            offsets,
            skin,
        )


def populate(
    scan: Scan,
    rng: np.random.Generator,
    catalog: Catalog | None = None,
    count: int | None = None,
    sources: Sources | None = None,
    together: float = 0.0,
) -> Crowd:
    """People placed in ``scan`` by HA3D's rule.

    Args:
        scan: The building (its graph, regions and seats are used).
        rng: The only source of randomness.
        catalog: Activities by region (default: the built-in catalog).
        count: Head count (default: ``people_count``).
        sources: User-supplied motions and SMPL model.
        together: Chance that a placed person is joined by others (a conversation of two or
            three, someone handing them something, a companion walking beside them; see
            :mod:`havln_mj.humans.together`). 0 keeps HA3D's one person per spot.
    """
    catalog = catalog or load_catalog()
    build = _Builder(rng, sources)
    graph, regions = scan.graph, scan.regions
    known = set(catalog.regions())
    candidates = [
        vp
        for vp in graph.nodes
        if (region := regions.region_of(vp)) is not None and region.label in known
    ]
    chosen = _spread(graph, candidates, count or people_count(regions), rng)
    used_seats: set[int] = set()
    people = []
    for vp in chosen:
        region = regions.region_of(vp)
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
        walk_to = _walk_targets(graph, vp)
        body = build.body()
        options = catalog.activities(region.label)
        for k in rng.permutation(len(options)):
            activity = options[int(k)]
            if not ((activity.needs_seat and not seats) or (activity.needs_path and not walk_to)):
                break
        else:
            continue  # nothing this region offers fits here
        anchor, text, path = np.array([pos[0], pos[1], floor]), "", None
        if activity.needs_seat:
            seat = min(seats, key=lambda o: np.linalg.norm(o.bbox[:2] - pos[:2]))
            used_seats.add(seat.index)
            anchor, heading = _seat_pose(seat)
            clip = make_clip(activity, body[0].height, rng, seat_height=seat.seat_height)
        elif activity.needs_path:
            target = walk_to[int(rng.integers(len(walk_to)))]
            heading = 0.0
            path = np.array([[0.0, 0.0], graph.position(target)[:2] - pos[:2]])
            clip = make_clip(activity, body[0].height, rng, path=path)
        else:
            centre = region.polygon.mean(axis=0)
            far = np.linalg.norm(centre - pos[:2]) > 0.3
            heading = heading_to(pos, centre) if far else float(rng.uniform(0, 2 * math.pi))
            haps = build.sources.haps_for_region(region.label)
            if haps:  # the user's HAPS motion of this region replaces ours
                clip = haps[int(rng.integers(len(haps)))]
                text = clip.name.split(":", 1)[-1]
            else:
                clip = make_clip(activity, body[0].height, rng)
        person = build.person(body, clip, anchor, heading, activity, vp, text)
        if together > 0 and not activity.needs_seat and rng.random() < together:
            people += _group(person, activity, path, build)
        else:
            people.append(person)
    return Crowd(people)


def _group(person: Person, activity: Activity, path: np.ndarray | None, build: _Builder):
    """``person`` joined by others: walking beside them, or talking or handing something."""
    rng = build.rng

    def body() -> BodyShape:
        return build.body()[0]

    if path is not None:
        d = path[-1] - path[0]
        side = np.array([d[1], -d[0]]) / max(float(np.linalg.norm(d)), 1e-9)

        def beside(height: float, offset: float):
            return make_clip(activity, height, rng, path=path + offset * side)

        return side_by_side(person, rng, body, beside)
    if rng.random() < 0.3:
        return handover(person, rng, body)
    return conversation(person, rng, body, int(rng.integers(2, 4)))


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
    sources: Sources | None = None,
) -> Crowd:
    """People at HA3D's placements for one scan.

    With a HAPS folder each plays its own HAPS motion (prompt and model id). Otherwise it
    does our nearest activity of its region: sitting is swapped for a standing activity (the
    placement gives no seat), and walking paces toward a neighbouring viewpoint on the same
    floor when there is one.
    """
    catalog = catalog or load_catalog()
    build = _Builder(rng, sources)
    people = []
    for vp, (text, model_id, degrees) in sorted(entries.items()):
        graph.index(vp)  # raises for a viewpoint the scan does not have
        activity = catalog.map_ha3d(text, rng)
        pos, floor = graph.position(vp), graph.floor_z(vp)
        anchor, heading = np.array([pos[0], pos[1], floor]), ha3d_heading(degrees)
        body = build.body()
        haps = (build.sources.haps or {}).get(haps_dir_name(text))
        # HA3D also stands people on excluded viewpoints; those have no edges to pace along.
        walk_to = _walk_targets(graph, vp) if vp in graph else []
        if haps:
            clip = haps[model_id % len(haps)]
        else:
            if activity.needs_seat or (activity.needs_path and not walk_to):
                standing = [
                    a for a in catalog.activities(activity.region) if not a.needs_seat
                    and not a.needs_path
                ]  # fmt: skip
                activity = standing[int(rng.integers(len(standing)))]
            if activity.needs_path:
                target = walk_to[int(rng.integers(len(walk_to)))]
                path = np.array([[0.0, 0.0], graph.position(target)[:2] - pos[:2]])
                clip = make_clip(activity, body[0].height, rng, path=path)
                heading = 0.0
            else:
                clip = make_clip(activity, body[0].height, rng)
        people.append(
            build.person(body, clip, anchor, heading, activity, vp, text.split(":", 1)[-1])
        )
    return Crowd(people)
