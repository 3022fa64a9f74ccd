"""The wording tables: shipped as data, read once, and every malformed entry named."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from havln_mj.errors import MalformedDataError, MissingDataError
from havln_mj.humans.crowd import Crowd
from havln_mj.paths import asset_path
from havln_mj.scene.scan import load_scan
from havln_mj.tasks.episodes import REL_POSITIONS
from havln_mj.tasks.instructions import generate_instructions
from havln_mj.tasks.phrases import TURNS, default_phrases, load_phrases
from havln_mj.tasks.procedural import sample_paths
from havln_mj.tasks.route_facts import describe_route, room_name

BUILT_IN = asset_path("eval", "instruction_phrases.json")


def _raw() -> dict:
    return json.loads(BUILT_IN.read_text())


def _write(tmp_path: Path, raw: dict) -> Path:
    path = tmp_path / "phrases.json"
    path.write_text(json.dumps(raw))
    return path


def test_built_in_tables_load_once():
    phrases = default_phrases()
    assert phrases is default_phrases()
    assert set(phrases.turns) == set(TURNS[1:]) and set(phrases.people) == set(REL_POSITIONS)
    assert "{room}" in phrases.enter[0] and phrases.goal_landmark == "Stop next to the {lm}."
    assert room_name("t") == "washroom" and room_name("Z") is None and room_name("k") == "kitchen"
    assert load_phrases(BUILT_IN) == phrases


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (lambda r: r["enter"].__setitem__(2, "walk into the {place}"), r"enter\[2\].*\{place\}"),
        (lambda r: r["people"]["End"].append("{who} is {doing}"), r"people\['End'\]\[4\].*doing"),
        (lambda r: r["toward"].__setitem__(0, "to the {lm"), r"toward\[0\].*bad braces"),
        (lambda r: r["calm"].__setitem__(1, 7), r"calm\[1\] must be a string"),
        (lambda r: r.__setitem__("confirm", []), r"confirm must be a non-empty list"),
        (lambda r: r.pop("caution"), r"table 'caution' is missing"),
        (lambda r: r.__setitem__("cautoin", ["x"]), r"unknown table 'cautoin'.*'caution'"),
        (lambda r: r["turns"].pop("around"), r"turns: no phrases for 'around'"),
        (lambda r: r["turns"].__setitem__("leftish", ["x"]), r"turns: unknown key 'leftish'"),
        (lambda r: r["room_words"].__setitem__("q9", "nook"), r"room_words: unknown key 'q9'"),
        (lambda r: r["object_words"].__setitem__("sofa", None), r"object_words\['sofa'\]"),
        (lambda r: r.__setitem__("goal_landmark", ["Stop."]), r"goal_landmark must be a string"),
    ],
)
def test_a_malformed_entry_is_named(tmp_path, edit, match):
    raw = _raw()
    edit(raw)
    with pytest.raises(MalformedDataError, match=match):
        load_phrases(_write(tmp_path, raw))


def test_unreadable_or_absent_files(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(MalformedDataError, match="not a readable JSON"):
        load_phrases(bad)
    with pytest.raises(MalformedDataError, match="expected an object"):
        load_phrases(_write(tmp_path, ["a list"]))
    with pytest.raises(MissingDataError):
        load_phrases(tmp_path / "missing.json")


def test_own_wording_is_used(tmp_path):
    raw = _raw()
    raw["enter"] = ["enter THE {room} NOW"]
    raw["confirm"] = ["ARRIVED."]
    own = load_phrases(_write(tmp_path, raw))
    scan = load_scan("proc-0")
    rng = np.random.default_rng(0)
    texts = []
    for path in sample_paths(scan.graph, 10, rng):
        route = describe_route(scan, path, 0.0, Crowd([]))
        texts += generate_instructions(route, rng, 3, phrases=own)[0]
    joined = " ".join(texts)
    assert "THE living room NOW" in joined or "THE kitchen NOW" in joined
    assert "ARRIVED." in joined
    assert not any(p.format(room="") in joined for p in default_phrases().enter)
