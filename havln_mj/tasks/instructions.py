"""Navigation instructions composed from a route's facts (our own wording).

:func:`generate_instructions` writes instructions from a :class:`~havln_mj.tasks.route_facts.Route`
(:func:`~havln_mj.tasks.route_facts.describe_route`): several phrasings per element (the tables
of :mod:`havln_mj.tasks.phrases`), random connectives, orderings and optional details, with
each instruction's length drawn around HA-R2R's mean (about 60 words). The sentences about
people are also returned per instruction, as HA-R2R's ``Relative Position Description``.

:func:`tokenize` splits text into the tokens the split's vocabulary file counts.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.tasks.phrases import Phrases, default_phrases
from havln_mj.tasks.route_facts import PersonOnRoute, Route, RouteStep

TARGET_WORDS, TARGET_SPREAD = 52.0, 9.0  # extras stop here; people push the mean to ~60
MIN_TARGET, MAX_TARGET = 38, 90
_OUTSIDE = frozenset("pxy")  # porch, outdoors, balcony: "step out onto"
_TOKEN = re.compile(r"[a-z]+(?:'[a-z]+)?|\d+(?:\.\d+)?|[^\w\s]")


def tokenize(text: str) -> list[str]:
    """Lower-case word, number and punctuation tokens of ``text`` (the vocabulary's units)."""
    return _TOKEN.findall(text.lower())


def word_count(text: str) -> int:
    """Words as R2R statistics count them (whitespace-separated)."""
    return len(text.split())


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


def _leg_clause(
    ph: Phrases, leg: _Leg, first: bool, detail: float, rng: np.random.Generator
) -> str:
    """One movement, e.g. ``"turn left and go through the doorway into the kitchen"``."""
    s = leg.first
    entering = leg.last.room_to is not None and leg.last.room_to != s.room_from
    if leg.climb > 0:
        move = _pick(rng, ph.up)
    elif leg.climb < 0:
        move = _pick(rng, ph.down)
    elif entering and leg.last.label_to == "s":
        move = _pick(rng, ph.enter_stairs)
    elif entering:
        out = leg.last.label_to in _OUTSIDE
        move = _pick(rng, ph.enter_outside if out else ph.enter).format(room=leg.last.room_to)
    elif s.turn != "straight" and rng.random() >= detail:
        # A turn inside the room: the turn itself says enough.
        return _pick(rng, ph.turns[s.turn]) + _pick(rng, ph.on)
    elif leg.last.room_to is not None:
        move = _pick(rng, ph.across).format(room=leg.last.room_to)
    else:
        move = _pick(rng, ph.ahead)
    if not entering and not leg.climb and rng.random() < 0.6 * detail:
        m = round(leg.length)
        move += _pick(rng, ph.short) if m < 3 else _pick(rng, ph.distance).format(m=m)
    lm = leg.last.landmark
    if lm is not None and rng.random() < 0.4 + 0.6 * detail:
        if leg.last.landmark_side is not None and rng.random() < 0.4:
            move += _pick(rng, ph.beside).format(lm=lm, side=leg.last.landmark_side)
        else:
            move += _pick(rng, ph.toward).format(lm=lm)
    if s.turn == "straight":
        lead = _pick(rng, ph.straight_first if first else ph.straight_later)
        return f"{lead} {move}" if lead else move
    turn = _pick(rng, ph.turns[s.turn])
    return f"{turn}{_pick(rng, ph.turn_joins)}{move}"


def _person_sentence(ph: Phrases, p: PersonOnRoute, rng: np.random.Generator) -> str:
    who = _pick(rng, ph.who)
    # "vacuuming the hallway in the hallway" says the room twice.
    where = f" in the {p.room}" if p.room and p.room not in p.verb else ""
    text = _pick(rng, ph.people[p.human.rel_pos])
    return _cap(
        text.format(
            who=who,
            Who=_cap(who),
            verb=p.verb,
            where=where,
            Where_lead=f"In the {p.room}, " if where else "",
        )
    )


def _goal_sentence(ph: Phrases, route: Route, rng: np.random.Generator) -> str:
    room, lm = route.goal_room, route.goal_landmark
    if room and lm:
        return _pick(rng, ph.goal_both).format(room=room, lm=lm)
    if room:
        within = route.steps[-1].room_from == room
        return _pick(rng, ph.goal_within if within else ph.goal_room).format(room=room)
    if lm:
        return ph.goal_landmark.format(lm=lm)
    return _pick(rng, ph.goal_none)


def _join(rooms: Sequence[str]) -> str:
    return rooms[0] if len(rooms) == 1 else ", the ".join(rooms[:-1]) + " and the " + rooms[-1]


def _optional(
    ph: Phrases, route: Route, legs: Sequence[_Leg], rng: np.random.Generator
) -> list[tuple]:
    """Extra sentences: ``(position, text)`` with position -1 first, len(legs) last."""
    out: list[tuple[int, str]] = []
    if route.start_room:
        if route.start_landmark:
            text = _pick(rng, ph.opener_landmark).format(
                room=route.start_room, lm=route.start_landmark
            )
        else:
            text = _pick(rng, ph.opener).format(room=route.start_room)
        out.append((-1, text))
    if route.goal_room and route.goal_room != route.start_room:
        out.append((-1, _pick(rng, ph.goal_preview).format(room=route.goal_room)))
    passed = []
    for s in route.steps[:-1]:
        if s.room_to and s.room_to not in passed and s.room_to not in (route.start_room,):
            passed.append(s.room_to)
    passed = [r for r in passed if r != route.goal_room]
    if passed:
        out.append((-1, _pick(rng, ph.rooms_passed).format(rooms=_join(passed))))
    for k, leg in enumerate(legs[:-1]):
        if leg.last.landmark and leg.last.landmark_side:
            side = leg.last.landmark_side
            out.append((k, _pick(rng, ph.side_note).format(lm=leg.last.landmark, side=side)))
    out.append((len(legs), _pick(rng, ph.length_note).format(m=max(1, round(route.distance)))))
    out.append((-1 if rng.random() < 0.5 else len(legs), _pick(rng, ph.calm)))
    out.append((len(legs) + 1, _pick(rng, ph.confirm)))
    if route.people:
        out.append((-1 if rng.random() < 0.5 else len(legs), _pick(rng, ph.caution)))
    return out


def _compose(ph: Phrases, route: Route, rng: np.random.Generator) -> tuple[str, str]:
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
            clause = _leg_clause(ph, legs[k], k == 0, detail, rng)
            if two:
                clause += _pick(rng, ph.join) + _leg_clause(ph, legs[k + 1], False, detail, rng)
            lead = "" if k == 0 else _pick(rng, ph.lead)
            slot = k + (2 if two else 1)
            slots[slot].append(_cap(lead + clause) + ".")
            leg_slot[k:slot] = [slot] * (slot - k)
            k = slot
        # Each person follows the movement that brings them into view; Beginning ones open.
        about_people = []
        for p in route.people:
            leg = next((i for i, g in enumerate(legs) if g.end_node >= p.node), len(legs) - 1)
            sentence = _person_sentence(ph, p, rng)
            about_people.append(sentence)
            slots[0 if p.human.rel_pos == "Beginning" else leg_slot[leg]].append(sentence)
        goal = _goal_sentence(ph, route, rng)
        slots[goal_slot].append(goal)
        words = sum(word_count(s) for slot in slots for s in slot)
        if words <= target + 5 or detail == 0.0:
            break
        detail = 0.0  # too long already: say it again without optional details
    extras = _optional(ph, route, legs, rng)
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
    route: Route, rng: np.random.Generator, n: int = 3, phrases: Phrases | None = None
) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """``n`` different instructions for a route, and their sentences about people.

    Args:
        route: From :func:`~havln_mj.tasks.route_facts.describe_route`.
        rng: The only source of randomness.
        n: Number of instructions (HA-R2R has 3 per path).
        phrases: The wording tables (default: the built-in ones).

    Returns:
        The instructions, and per instruction its sentences about the people (HA-R2R's
        ``Relative Position Description``; empty strings when no one is on the path).

    Raises:
        InvalidArgumentError: ``n`` is below 1.
    """
    if n < 1:
        raise InvalidArgumentError(f"n must be at least 1 instruction, got {n}")
    ph = phrases or default_phrases()
    texts: list[str] = []
    people: list[str] = []
    for _ in range(n):
        for _attempt in range(20):  # wording is varied enough that repeats are rare
            text, about = _compose(ph, route, rng)
            if text not in texts:
                break
        texts.append(text)
        people.append(about)
    return tuple(texts), tuple(people)
