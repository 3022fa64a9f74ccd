"""The facts a path's instructions are made from: turns, rooms, stairs, landmarks and people.

:func:`describe_route` turns a path on a scan into a :class:`Route`: per edge the turn (heading
change between consecutive edges, the first against the start heading), the rooms left and
entered (region names), stairs (floor height changes), a landmark (the nearest furniture of
the room reached); the goal room and landmark; and the people HA3D's rule links to the path
(:func:`havln_mj.tasks.annotate.humans_on_path`) with their activity and relative position.
Rooms and furniture are named with the words of :mod:`havln_mj.tasks.phrases`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.frames import heading_to, wrap_angle
from havln_mj.humans.catalog import HA3D_REGIONS, Catalog, load_catalog
from havln_mj.humans.crowd import Crowd
from havln_mj.scene.regions import REGION_LABELS, Region
from havln_mj.scene.scan import Scan
from havln_mj.tasks.annotate import humans_on_path
from havln_mj.tasks.episodes import HumanOnPath
from havln_mj.tasks.phrases import default_phrases

# Turn bins in degrees of |heading change|: below the first is straight, and so on.
STRAIGHT_MAX, SLIGHT_MAX, TURN_MAX = 25.0, 65.0, 145.0
STAIR_STEP = 0.3  # metres of floor height change along one edge that count as stairs
LANDMARK_RADIUS = 3.0  # metres from a viewpoint to a furniture footprint's centre
_HA3D_NAME = {code: name for name, code in HA3D_REGIONS.items()}


def room_name(label: str | None) -> str | None:
    """The word an instruction uses for a region label code (None: no usable name)."""
    if label is None:
        return None
    words = default_phrases().room_words
    if label in words:
        return words[label]
    return REGION_LABELS.get(label)


def object_name(category: str) -> str:
    """The words an instruction uses for a furniture category (``"coffee_table"`` → ...)."""
    return default_phrases().object_words.get(category, category.replace("_", " "))


@dataclass(frozen=True)
class RouteStep:
    """One edge of a path, from ``path[index]`` to ``path[index + 1]``.

    Attributes:
        index: The edge's index.
        turn: One of :data:`~havln_mj.tasks.phrases.TURNS`, the heading change onto this
            edge (the first edge's against the start heading).
        room_from: Room name at the edge's start (None: unnamed).
        room_to: Room name at its end.
        label_to: Region label code at its end (None: no region).
        climb: +1 up stairs, -1 down, 0 level.
        landmark: Furniture near the edge's end in the room reached, or None.
        landmark_side: ``"left"`` or ``"right"`` of the direction of travel (None without one).
        length: Edge length in metres.
    """

    index: int
    turn: str
    room_from: str | None
    room_to: str | None
    label_to: str | None
    climb: int
    landmark: str | None
    landmark_side: str | None
    length: float


@dataclass(frozen=True)
class PersonOnRoute:
    """A person linked to the path, as the instructions describe them.

    Attributes:
        human: The HA-R2R ``human`` entry.
        verb: Their activity as a verb phrase (``"loading the dishwasher"``).
        room: The room they are in (None: unnamed).
        node: Index of the path viewpoint nearest them.
    """

    human: HumanOnPath
    verb: str
    room: str | None
    node: int


@dataclass(frozen=True)
class Route:
    """What the instructions of one path are made from.

    Attributes:
        path: The viewpoints, start first.
        steps: One step per edge.
        start_room: Room of the start (None: unnamed).
        start_landmark: Furniture near the start, or None.
        goal_room: Room of the goal (None: unnamed).
        goal_label: Region label code of the goal (None: no region).
        goal_landmark: Furniture near the goal, or None.
        people: The people HA3D's rule links to the path, in order of first sight.
        distance: Path length in metres.
    """

    path: tuple[str, ...]
    steps: tuple[RouteStep, ...]
    start_room: str | None
    start_landmark: str | None
    goal_room: str | None
    goal_label: str | None
    goal_landmark: str | None
    people: tuple[PersonOnRoute, ...]
    distance: float

    @property
    def humans(self) -> tuple[HumanOnPath, ...]:
        """The HA-R2R ``human`` entries."""
        return tuple(p.human for p in self.people)


def _turn(delta: float) -> str:
    deg = math.degrees(abs(delta))
    side = "right" if delta > 0 else "left"  # headings grow turning right
    if deg < STRAIGHT_MAX:
        return "straight"
    if deg < SLIGHT_MAX:
        return f"slight {side}"
    return side if deg < TURN_MAX else "around"


def _region(scan: Scan, vp: str) -> Region | None:
    return None if scan.regions is None else scan.regions.region_of(vp)


def _landmark(scan: Scan, vp: str, radius: float = LANDMARK_RADIUS):
    """The furniture of ``vp``'s room whose footprint centre is nearest ``vp`` (or None)."""
    region = _region(scan, vp)
    if region is None or scan.regions is None:
        return None
    here = scan.graph.position(vp)[:2]
    best, best_d = None, radius
    for obj in scan.regions.objects:
        if obj.region != region.index:
            continue
        d = float(np.linalg.norm((obj.bbox[:2] + obj.bbox[3:5]) / 2 - here))
        if d < best_d:
            best, best_d = obj, d
    return best


def person_description(label: str, text: str) -> str:
    """HA-R2R's ``human_description``: ``"<HA3D region name>:<sentence>"``."""
    region = _HA3D_NAME.get(label) or REGION_LABELS.get(label, "other room")
    return f"{region}:{text}"


def _verb(catalog: Catalog, activity: str, text: str) -> str:
    try:
        return catalog.get(activity).verb
    except (InvalidArgumentError, KeyError):
        # A user's motion (HAPS prompt): its own sentence, minus the subject.
        words = re.sub(
            r"^(a person|someone|a man|a woman|the person)\s+", "", text.strip(), flags=re.I
        )
        return words.rstrip(".").strip() or "standing there"


def describe_route(
    scan: Scan,
    path: Sequence[str],
    heading: float,
    crowd: Crowd,
    catalog: Catalog | None = None,
) -> Route:
    """The facts instructions for ``path`` are made from.

    Args:
        scan: The building.
        path: Viewpoints, start first (at least two).
        heading: Start heading in radians.
        crowd: The scan's people (``populate``'s, or an empty crowd).
        catalog: The activity catalog their verbs come from (default: the built-in one).

    Raises:
        InvalidArgumentError: The path has fewer than two viewpoints or a step is no edge.
        UnknownViewpointError: A viewpoint is not in the scan.
    """
    graph = scan.graph
    path = tuple(path)
    if len(path) < 2:
        raise InvalidArgumentError(f"a path needs at least 2 viewpoints, got {list(path)!r}")
    distance = graph.path_length(path)  # also checks every step is an edge
    steps = []
    facing = heading
    for i in range(len(path) - 1):
        a, b = path[i], path[i + 1]
        pa, pb = graph.position(a), graph.position(b)
        h = heading_to(pa, pb)
        ra, rb = _region(scan, a), _region(scan, b)
        dz = graph.floor_z(b) - graph.floor_z(a)
        obj = _landmark(scan, b)
        side = None
        if obj is not None:
            d, v = pb[:2] - pa[:2], (obj.bbox[:2] + obj.bbox[3:5]) / 2 - pa[:2]
            side = "left" if d[0] * v[1] - d[1] * v[0] > 0 else "right"
        steps.append(
            RouteStep(
                index=i,
                turn=_turn(wrap_angle(h - facing)),
                room_from=room_name(ra.label) if ra else None,
                room_to=room_name(rb.label) if rb else None,
                label_to=rb.label if rb else None,
                climb=0 if abs(dz) < STAIR_STEP else int(math.copysign(1, dz)),
                landmark=object_name(obj.category) if obj is not None else None,
                landmark_side=side,
                length=float(np.linalg.norm(pb - pa)),
            )
        )
        facing = h
    catalog = catalog or load_catalog()
    people = []
    by_vp = {p.viewpoint: p for p in crowd.people if p.viewpoint}
    placements = {vp: person_description(p.region, p.text) for vp, p in by_vp.items()}
    for human in humans_on_path(path, graph, placements):
        person = by_vp[human.viewpoint]
        here = graph.position(human.viewpoint)
        node = min(range(len(path)), key=lambda k: math.dist(here, graph.position(path[k])))
        region = _region(scan, human.viewpoint)
        label = region.label if region is not None else person.region
        people.append(
            PersonOnRoute(
                human, _verb(catalog, person.activity, person.text), room_name(label), node
            )
        )
    start, goal = _region(scan, path[0]), _region(scan, path[-1])
    start_obj, goal_obj = _landmark(scan, path[0]), _landmark(scan, path[-1])
    return Route(
        path=path,
        steps=tuple(steps),
        start_room=room_name(start.label) if start else None,
        start_landmark=object_name(start_obj.category) if start_obj else None,
        goal_room=room_name(goal.label) if goal else None,
        goal_label=goal.label if goal else None,
        goal_landmark=object_name(goal_obj.category) if goal_obj else None,
        people=tuple(people),
        distance=float(distance),
    )
