"""The wording tables of generated instructions: read from data once and checked entry by entry.

The built-in tables are ``eval/instruction_phrases.json`` (found through
:func:`havln_mj.paths.asset_path`). Each table is a list of interchangeable phrasings; a name in
braces (``"enter the {room}"``) is filled in by :mod:`havln_mj.tasks.instructions`, and each
table allows only the names the generator fills in there. ``turns`` and ``people`` hold one
list per turn kind and per HA-R2R relative position; ``room_words`` and ``object_words`` map
region label codes and furniture categories to the words instructions use.
"""

from __future__ import annotations

import functools
import json
import string
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from types import MappingProxyType
from typing import Any

from havln_mj.errors import MalformedDataError, MissingDataError, did_you_mean
from havln_mj.paths import asset_path
from havln_mj.scene.regions import REGION_LABELS
from havln_mj.tasks.episodes import REL_POSITIONS

TURNS = ("straight", "slight left", "slight right", "left", "right", "around")
_PERSON = ("who", "Who", "verb", "where", "Where_lead")


def _table(*names: str) -> Any:
    return field(metadata={"kind": "table", "names": names})


def _text(*names: str) -> Any:
    return field(metadata={"kind": "text", "names": names})


def _by(keys: tuple[str, ...], *names: str) -> Any:
    return field(metadata={"kind": "by", "keys": keys, "names": names})


def _words(keys: tuple[str, ...] | None, nullable: bool) -> Any:
    return field(metadata={"kind": "words", "keys": keys, "nullable": nullable})


@dataclass(frozen=True)
class Phrases:
    """Every wording table; see the module docstring and the built-in file for their use."""

    room_words: Mapping[str, str | None] = _words(tuple(REGION_LABELS), nullable=True)
    object_words: Mapping[str, str] = _words(None, nullable=False)
    turns: Mapping[str, tuple[str, ...]] = _by(TURNS[1:])
    turn_joins: tuple[str, ...] = _table()
    straight_first: tuple[str, ...] = _table()
    straight_later: tuple[str, ...] = _table()
    up: tuple[str, ...] = _table()
    down: tuple[str, ...] = _table()
    enter: tuple[str, ...] = _table("room")
    enter_outside: tuple[str, ...] = _table("room")
    enter_stairs: tuple[str, ...] = _table()
    across: tuple[str, ...] = _table("room")
    on: tuple[str, ...] = _table()
    ahead: tuple[str, ...] = _table()
    toward: tuple[str, ...] = _table("lm")
    beside: tuple[str, ...] = _table("lm", "side")
    distance: tuple[str, ...] = _table("m")
    short: tuple[str, ...] = _table()
    join: tuple[str, ...] = _table()
    lead: tuple[str, ...] = _table()
    goal_both: tuple[str, ...] = _table("room", "lm")
    goal_room: tuple[str, ...] = _table("room")
    goal_within: tuple[str, ...] = _table("room")
    goal_landmark: str = _text("lm")
    goal_none: tuple[str, ...] = _table()
    who: tuple[str, ...] = _table()
    people: Mapping[str, tuple[str, ...]] = _by(REL_POSITIONS, *_PERSON)
    opener: tuple[str, ...] = _table("room")
    opener_landmark: tuple[str, ...] = _table("room", "lm")
    goal_preview: tuple[str, ...] = _table("room")
    rooms_passed: tuple[str, ...] = _table("rooms")
    side_note: tuple[str, ...] = _table("lm", "side")
    length_note: tuple[str, ...] = _table("m")
    caution: tuple[str, ...] = _table()
    calm: tuple[str, ...] = _table()
    confirm: tuple[str, ...] = _table()


def load_phrases(path: Path | str | None = None) -> Phrases:
    """Reads and checks wording tables (default: the built-in ``eval/instruction_phrases.json``).

    Raises:
        MissingDataError: The file does not exist.
        MalformedDataError: It is not JSON, a table is missing or unknown, or an entry is not
            text or uses a name in braces its table does not fill in (the entry is named).
    """
    path = Path(path) if path is not None else asset_path("eval", "instruction_phrases.json")
    if not path.is_file():
        raise MissingDataError(f"phrase tables not found: {path}")
    try:
        raw = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise MalformedDataError(f"{path}: not a readable JSON file ({exc})") from None
    if not isinstance(raw, dict):
        raise MalformedDataError(f"{path}: expected an object of tables, got {type(raw).__name__}")
    specs = {f.name: f.metadata for f in fields(Phrases)}
    for name in sorted(raw.keys() - specs.keys() - {"about"}):
        raise MalformedDataError(f"{path}: unknown table {name!r}.{did_you_mean(name, specs)}")
    values = {}
    for name, spec in specs.items():
        if name not in raw:
            raise MalformedDataError(f"{path}: table {name!r} is missing")
        values[name] = _checked(raw[name], spec, f"{path}: {name}")
    return Phrases(**values)


@functools.cache
def default_phrases() -> Phrases:
    """The built-in tables, read once."""
    return load_phrases()


def _checked(value: object, spec: Mapping[str, Any], where: str) -> object:
    kind = spec["kind"]
    if kind == "text":
        return _phrase(value, spec["names"], where)
    if kind == "table":
        return _phrase_list(value, spec["names"], where)
    keyed = _keyed(value, spec["keys"], where)
    if kind == "by":
        missing = [k for k in spec["keys"] if k not in keyed]
        if missing:
            raise MalformedDataError(f"{where}: no phrases for {', '.join(map(repr, missing))}")
        return MappingProxyType(
            {k: _phrase_list(v, spec["names"], f"{where}[{k!r}]") for k, v in keyed.items()}
        )
    for k, v in keyed.items():
        if not ((isinstance(v, str) and v) or (v is None and spec["nullable"])):
            valid = "a non-empty string or null" if spec["nullable"] else "a non-empty string"
            raise MalformedDataError(f"{where}[{k!r}] must be {valid}, got {v!r}")
    return MappingProxyType(dict(keyed))


def _keyed(value: object, keys: tuple[str, ...] | None, where: str) -> dict:
    """An object; with ``keys``, each of its keys one of them."""
    if not isinstance(value, dict):
        raise MalformedDataError(f"{where} must be an object, got {type(value).__name__}")
    if keys is not None:
        for k in value:
            if k not in keys:
                raise MalformedDataError(
                    f"{where}: unknown key {k!r}; valid: {', '.join(keys)}.{did_you_mean(k, keys)}"
                )
    return value


def _phrase_list(value: object, names: tuple[str, ...], where: str) -> tuple[str, ...]:
    if not isinstance(value, list) or not value:
        raise MalformedDataError(f"{where} must be a non-empty list of phrases, got {value!r}")
    return tuple(_phrase(v, names, f"{where}[{i}]") for i, v in enumerate(value))


def _phrase(value: object, names: tuple[str, ...], where: str) -> str:
    if not isinstance(value, str):
        raise MalformedDataError(f"{where} must be a string, got {value!r}")
    try:
        used = [name for _, name, _, _ in string.Formatter().parse(value) if name is not None]
    except ValueError as exc:
        raise MalformedDataError(f"{where} = {value!r}: bad braces ({exc})") from None
    for name in used:
        if name not in names:
            valid = ", ".join(f"{{{n}}}" for n in names) or "none"
            raise MalformedDataError(
                f"{where} = {value!r} uses {{{name}}}; names this table fills in: {valid}"
            )
    return value
