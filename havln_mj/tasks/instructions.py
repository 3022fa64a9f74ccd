"""Navigation instructions composed from a route and the people on it (our own wording).

:func:`describe_route` turns a path on a scan into facts: per edge the turn (heading change
between consecutive edges, the first against the start heading), the rooms left and entered
(region names), stairs (floor height changes), a landmark (the nearest furniture of the room
reached); the goal room and landmark; and the people HA3D's rule links to the path
(:func:`havln_mj.tasks.annotate.humans_on_path`) with their activity and relative position.
:func:`generate_instructions` writes instructions from those facts: several templates per
element, random connectives, orderings and optional details, with each instruction's length
drawn around HA-R2R's mean (about 60 words). The sentences about people are also returned
per instruction, as HA-R2R's ``Relative Position Description``.

:func:`tokenize` splits text into the tokens the split's vocabulary file counts.
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
from havln_mj.tasks.datasets import HumanOnPath

TURNS = ("straight", "slight left", "slight right", "left", "right", "around")
# Turn bins in degrees of |heading change|: below the first is straight, and so on.
STRAIGHT_MAX, SLIGHT_MAX, TURN_MAX = 25.0, 65.0, 145.0
STAIR_STEP = 0.3  # metres of floor height change along one edge that count as stairs
LANDMARK_RADIUS = 3.0  # metres from a viewpoint to a furniture footprint's centre
TARGET_WORDS, TARGET_SPREAD = 52.0, 9.0  # extras stop here; people push the mean to ~60
MIN_TARGET, MAX_TARGET = 38, 90

# Room names as instructions say them; None: a region without a usable name.
_ROOM_WORDS = {
    "t": "washroom",
    "v": "TV room",
    "s": "stairway",
    "x": "garden",
    "r": "games room",
    "Z": None,
    "-": None,
}
_OUTSIDE = frozenset("pxy")  # porch, outdoors, balcony: "step out onto"
# Furniture categories as instructions say them (others: underscores become spaces).
_OBJECT_WORDS = {
    "tv_stand": "TV stand",
    "dining_set": "dining table",
    "plant": "potted plant",
    "bar_counter": "bar counter",
    "shelving": "shelves",
}
_HA3D_NAME = {code: name for name, code in HA3D_REGIONS.items()}
_TOKEN = re.compile(r"[a-z]+(?:'[a-z]+)?|\d+(?:\.\d+)?|[^\w\s]")


def room_name(label: str | None) -> str | None:
    """The word an instruction uses for a region label code (None: no usable name)."""
    if label is None:
        return None
    if label in _ROOM_WORDS:
        return _ROOM_WORDS[label]
    return REGION_LABELS.get(label)


def object_name(category: str) -> str:
    """The words an instruction uses for a furniture category (``"coffee_table"`` → ...)."""
    return _OBJECT_WORDS.get(category, category.replace("_", " "))


def tokenize(text: str) -> list[str]:
    """Lower-case word, number and punctuation tokens of ``text`` (the vocabulary's units)."""
    return _TOKEN.findall(text.lower())


def word_count(text: str) -> int:
    """Words as R2R statistics count them (whitespace-separated)."""
    return len(text.split())


# ---------------------------------------------------------------------- route facts


@dataclass(frozen=True)
class RouteStep:
    """One edge of a path, from ``path[index]`` to ``path[index + 1]``.

    Attributes:
        index: The edge's index.
        turn: One of :data:`TURNS`, the heading change onto this edge (the first edge's
            against the start heading).
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


# ---------------------------------------------------------------------- wording

_TURN_WORDS = {
    "slight left": ("bear left", "veer slightly left", "go slightly left", "angle a bit left"),
    "slight right": ("bear right", "veer slightly right", "go slightly right", "angle a bit right"),
    "left": ("turn left", "take a left", "make a left turn", "turn to your left"),
    "right": ("turn right", "take a right", "make a right turn", "turn to your right"),
    "around": ("turn around", "turn all the way around", "face the opposite way"),
}
_STRAIGHT_FIRST = ("walk straight ahead and", "head forward and", "go straight and", "")
_STRAIGHT_LATER = ("keep going straight and", "continue straight and", "carry on and", "", "")
_UP = ("go up the stairs", "climb the stairs", "take the stairs up", "walk up the steps")
_DOWN = ("go down the stairs", "take the stairs down", "walk down the steps", "head downstairs")
_ENTER = (
    "go through the doorway into the {room}",
    "walk into the {room}",
    "enter the {room}",
    "step through the door into the {room}",
    "head into the {room}",
    "pass through the doorway to the {room}",
)
_ENTER_OUT = ("step outside onto the {room}", "go out to the {room}", "head out into the {room}")
_ENTER_STAIRS = ("walk over to the stairs", "head to the staircase", "go to the foot of the stairs")
_ACROSS = (
    "walk across the {room}",
    "continue through the {room}",
    "walk along the {room}",
    "keep moving through the {room}",
    "cross the {room}",
)
_ON = ("", "", " and walk on", " and keep going")
_AHEAD = ("walk ahead", "keep walking", "continue forward", "move ahead")
_TOWARD = (
    " toward the {lm}",
    " until you reach the {lm}",
    " up to the {lm}",
    ", heading for the {lm}",
)
_BESIDE = (", keeping the {lm} on your {side}", " with the {lm} on your {side}")
_DISTANCE = (" for about {m} metres", " for roughly {m} metres", " for around {m} metres")
_SHORT = (" for a few steps", " a short way")
_JOIN = (", then ", ". Then ", ". Next, ", ". After that, ", ". From there, ", "; then ")
_LEAD = ("", "", "", "Now ", "Next, ", "Then ")

_GOAL_BOTH = (
    "Stop next to the {lm} in the {room}.",
    "Wait by the {lm} in the {room}.",
    "Your goal is beside the {lm} in the {room}, so stop there.",
    "Stop once you are in the {room} beside the {lm}.",
    "Come to a halt near the {lm} of the {room}.",
    "Finish in the {room}, right by the {lm}.",
)
_GOAL_ROOM = (  # the last step enters the goal room
    "Stop in the {room}.",
    "Stop as soon as you are inside the {room}.",
    "Wait there in the {room}.",
    "Your goal is the {room}; stop just inside it.",
    "Finish your walk in the {room}.",
)
_GOAL_WITHIN = (  # the walk was already in the goal room
    "Stop there in the {room}.",
    "Stop a little further on in the {room}.",
    "Wait at that point in the {room}.",
    "Finish your walk in the {room}.",
)
_GOAL_NONE = ("Stop there.", "Wait at that spot.", "That is your goal, so stop.")

_WHO = ("someone", "a person", "one person")
_PEOPLE = {
    "Beginning": (
        "At the start, {who} is {verb} beside you{where}.",
        "{Who} {verb} is right by your starting spot{where}.",
        "You begin next to {who} {verb}{where}; move off carefully.",
        "Right where you start, {who} is {verb}{where}.",
    ),
    "Obstacle": (
        "{Who} {verb} is in your way{where}; go around them.",
        "Watch out for {who} {verb} on your path{where}.",
        "{Where_lead}{who} is {verb} right on your route, so step around them.",
        "Pass {who} {verb}{where} with care.",
    ),
    "Around": (
        "{Who} is {verb} nearby{where}.",
        "You may notice {who} {verb}{where}.",
        "Off to the side{where}, {who} is {verb}.",
        "{Who} {verb} is close by{where}, not in your way.",
    ),
    "End": (
        "Near the end, {who} is {verb}{where}.",
        "{Who} {verb} is close to your goal{where}; do not bump into them.",
        "By the final spot{where}, {who} is {verb}.",
        "As you arrive you will see {who} {verb}{where}.",
    ),
}
_OPENERS_START = (
    "You begin in the {room}.",
    "You are starting in the {room}.",
    "Your walk starts in the {room}.",
)
_OPENERS_START_LM = (
    "You begin in the {room}, close to the {lm}.",
    "You are standing in the {room} near the {lm}.",
    "You start by the {lm} in the {room}.",
)
_GOAL_PREVIEW = (
    "Your destination is the {room}.",
    "You are heading for the {room}.",
    "The aim is to get to the {room}.",
)
_ROOMS_PASSED = (
    "On the way you pass through the {rooms}.",
    "You will walk through the {rooms} on the way.",
    "The route takes you through the {rooms}.",
)
_SIDE_NOTE = (
    "The {lm} will be on your {side}.",
    "You should see the {lm} on your {side}.",
    "Look for the {lm} to your {side}.",
)
_LENGTH_NOTE = (
    "The whole walk is roughly {m} metres.",
    "It is a short walk of about {m} metres.",
    "In total you cover around {m} metres.",
)
_CAUTION = (
    "Keep an eye on the people around you.",
    "Move slowly, since people are about.",
    "Take care, as the house is busy.",
    "Be mindful of anyone moving nearby.",
)
_CALM = (
    "Take your time.",
    "Walk at a steady pace.",
    "There is no need to hurry.",
)
_CONFIRM = (
    "That is where the walk ends.",
    "Once you are there, you have arrived.",
    "You are done when you get there.",
)


def _pick(rng: np.random.Generator, options: Sequence[str]) -> str:
    return options[int(rng.integers(len(options)))]


def _cap(text: str) -> str:
    return text[:1].upper() + text[1:] if text else text


@dataclass
class _Leg:
    """Consecutive steps the instructions describe as one movement."""

    steps: list[RouteStep]

    @property
    def first(self) -> RouteStep:
        return self.steps[0]

    @property
    def last(self) -> RouteStep:
        return self.steps[-1]

    @property
    def end_node(self) -> int:
        return self.last.index + 1

    @property
    def climb(self) -> int:
        return next((s.climb for s in self.steps if s.climb), 0)

    @property
    def length(self) -> float:
        return sum(s.length for s in self.steps)


def _legs(steps: Sequence[RouteStep]) -> list[_Leg]:
    """Steps merged while the walk goes on (straight or bending) within one room and level."""
    legs: list[_Leg] = []
    for s in steps:
        # Slight bends inside a room are part of walking through it, not a new movement.
        bend = s.turn in ("straight", "slight left", "slight right")
        if legs and bend and not s.climb and s.room_to == legs[-1].last.room_to:
            legs[-1].steps.append(s)
        else:
            legs.append(_Leg([s]))
    return legs


def _leg_clause(leg: _Leg, first: bool, detail: float, rng: np.random.Generator) -> str:
    """One movement, e.g. ``"turn left and go through the doorway into the kitchen"``."""
    s = leg.first
    entering = leg.last.room_to is not None and leg.last.room_to != s.room_from
    if leg.climb > 0:
        move = _pick(rng, _UP)
    elif leg.climb < 0:
        move = _pick(rng, _DOWN)
    elif entering and leg.last.label_to == "s":
        move = _pick(rng, _ENTER_STAIRS)
    elif entering:
        out = leg.last.label_to in _OUTSIDE
        move = _pick(rng, _ENTER_OUT if out else _ENTER).format(room=leg.last.room_to)
    elif s.turn != "straight" and rng.random() >= detail:
        # A turn inside the room: the turn itself says enough.
        return _pick(rng, _TURN_WORDS[s.turn]) + _pick(rng, _ON)
    elif leg.last.room_to is not None:
        move = _pick(rng, _ACROSS).format(room=leg.last.room_to)
    else:
        move = _pick(rng, _AHEAD)
    if not entering and not leg.climb and rng.random() < 0.6 * detail:
        m = round(leg.length)
        move += _pick(rng, _SHORT) if m < 3 else _pick(rng, _DISTANCE).format(m=m)
    lm = leg.last.landmark
    if lm is not None and rng.random() < 0.4 + 0.6 * detail:
        if leg.last.landmark_side is not None and rng.random() < 0.4:
            move += _pick(rng, _BESIDE).format(lm=lm, side=leg.last.landmark_side)
        else:
            move += _pick(rng, _TOWARD).format(lm=lm)
    if s.turn == "straight":
        lead = _pick(rng, _STRAIGHT_FIRST if first else _STRAIGHT_LATER)
        return f"{lead} {move}" if lead else move
    turn = _pick(rng, _TURN_WORDS[s.turn])
    return f"{turn}{_pick(rng, (' and ', ', then ', ' and '))}{move}"


def _person_sentence(p: PersonOnRoute, rng: np.random.Generator) -> str:
    who = _pick(rng, _WHO)
    # "vacuuming the hallway in the hallway" says the room twice.
    where = f" in the {p.room}" if p.room and p.room not in p.verb else ""
    text = _pick(rng, _PEOPLE[p.human.rel_pos])
    return _cap(
        text.format(
            who=who,
            Who=_cap(who),
            verb=p.verb,
            where=where,
            Where_lead=f"In the {p.room}, " if where else "",
        )
    )


def _goal_sentence(route: Route, rng: np.random.Generator) -> str:
    room, lm = route.goal_room, route.goal_landmark
    if room and lm:
        return _pick(rng, _GOAL_BOTH).format(room=room, lm=lm)
    if room:
        within = route.steps[-1].room_from == room
        return _pick(rng, _GOAL_WITHIN if within else _GOAL_ROOM).format(room=room)
    if lm:
        return f"Stop next to the {lm}."
    return _pick(rng, _GOAL_NONE)


def _join(rooms: Sequence[str]) -> str:
    return rooms[0] if len(rooms) == 1 else ", the ".join(rooms[:-1]) + " and the " + rooms[-1]


def _optional(route: Route, legs: Sequence[_Leg], rng: np.random.Generator) -> list[tuple]:
    """Extra sentences: ``(position, text)`` with position -1 first, len(legs) last."""
    out: list[tuple[int, str]] = []
    if route.start_room:
        if route.start_landmark:
            text = _pick(rng, _OPENERS_START_LM).format(
                room=route.start_room, lm=route.start_landmark
            )
        else:
            text = _pick(rng, _OPENERS_START).format(room=route.start_room)
        out.append((-1, text))
    if route.goal_room and route.goal_room != route.start_room:
        out.append((-1, _pick(rng, _GOAL_PREVIEW).format(room=route.goal_room)))
    passed = []
    for s in route.steps[:-1]:
        if s.room_to and s.room_to not in passed and s.room_to not in (route.start_room,):
            passed.append(s.room_to)
    passed = [r for r in passed if r != route.goal_room]
    if passed:
        out.append((-1, _pick(rng, _ROOMS_PASSED).format(rooms=_join(passed))))
    for k, leg in enumerate(legs[:-1]):
        if leg.last.landmark and leg.last.landmark_side:
            text = _pick(rng, _SIDE_NOTE).format(lm=leg.last.landmark, side=leg.last.landmark_side)
            out.append((k, text))
    out.append((len(legs), _pick(rng, _LENGTH_NOTE).format(m=max(1, round(route.distance)))))
    out.append((-1 if rng.random() < 0.5 else len(legs), _pick(rng, _CALM)))
    out.append((len(legs) + 1, _pick(rng, _CONFIRM)))
    if route.people:
        out.append((-1 if rng.random() < 0.5 else len(legs), _pick(rng, _CAUTION)))
    return out


def _compose(route: Route, rng: np.random.Generator) -> tuple[str, str]:
    """One instruction and its sentences about people."""
    legs = _legs(route.steps)
    target = int(np.clip(rng.normal(TARGET_WORDS, TARGET_SPREAD), MIN_TARGET, MAX_TARGET))
    detail = float(rng.uniform(0.2, 1.0))
    while True:
        # Slots: 0 opens, 1..len(legs) follow movement sentences, then the goal, then a last one.
        n_slots = len(legs) + 3
        goal_slot = n_slots - 2
        slots: list[list[str]] = [[] for _ in range(n_slots)]
        leg_slot = [0] * len(legs)  # the slot of the sentence that describes each leg
        k = 0
        while k < len(legs):
            two = k + 1 < len(legs) and rng.random() < 0.45
            clause = _leg_clause(legs[k], k == 0, detail, rng)
            if two:
                clause += _pick(rng, _JOIN) + _leg_clause(legs[k + 1], False, detail, rng)
            lead = "" if k == 0 else _pick(rng, _LEAD)
            slot = k + (2 if two else 1)
            slots[slot].append(_cap(lead + clause) + ".")
            leg_slot[k:slot] = [slot] * (slot - k)
            k = slot
        # Each person follows the movement that brings them into view; Beginning ones open.
        about_people = []
        for p in route.people:
            leg = next((i for i, g in enumerate(legs) if g.end_node >= p.node), len(legs) - 1)
            sentence = _person_sentence(p, rng)
            about_people.append(sentence)
            slots[0 if p.human.rel_pos == "Beginning" else leg_slot[leg]].append(sentence)
        goal = _goal_sentence(route, rng)
        slots[goal_slot].append(goal)
        words = sum(word_count(s) for slot in slots for s in slot)
        if words <= target + 5 or detail == 0.0:
            break
        detail = 0.0  # too long already: say it again without optional details
    extras = _optional(route, legs, rng)
    for i in rng.permutation(len(extras)):
        if words >= target:
            break
        pos, text = extras[int(i)]
        words += word_count(text)
        if pos < 0:
            slots[0].insert(0, text)
        elif pos < len(legs):
            slots[leg_slot[pos]].append(text)
        elif pos == len(legs):
            slots[goal_slot].insert(0, text)
        else:
            slots[-1].append(text)
    return " ".join(s for slot in slots for s in slot), " ".join(about_people)


def generate_instructions(
    route: Route, rng: np.random.Generator, n: int = 3
) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """``n`` different instructions for a route, and their sentences about people.

    Args:
        route: From :func:`describe_route`.
        rng: The only source of randomness.
        n: Number of instructions (HA-R2R has 3 per path).

    Returns:
        The instructions, and per instruction its sentences about the people (HA-R2R's
        ``Relative Position Description``; empty strings when no one is on the path).

    Raises:
        InvalidArgumentError: ``n`` is below 1.
    """
    if n < 1:
        raise InvalidArgumentError(f"n must be at least 1 instruction, got {n}")
    texts: list[str] = []
    people: list[str] = []
    for _ in range(n):
        for _attempt in range(20):  # wording is varied enough that repeats are rare
            text, about = _compose(route, rng)
            if text not in texts:
                break
        texts.append(text)
        people.append(about)
    return tuple(texts), tuple(people)
