"""Hand-placed people and HA3D's placement file."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from havln_mj.annotator.placements import (
    Placement,
    check_people,
    from_entries,
    ha3d_degrees,
    load_people,
    save_people,
    to_entry,
)
from havln_mj.errors import InvalidArgumentError, MalformedDataError, UnknownViewpointError
from havln_mj.humans.catalog import load_catalog
from havln_mj.humans.population import ha3d_heading, populate_ha3d, read_ha3d_placements
from havln_mj.scene.scan import load_scan


@pytest.fixture(scope="module")
def catalog():
    return load_catalog()


@pytest.fixture(scope="module")
def graph():
    return load_scan("proc-0").graph


def test_every_activity_and_heading_survives_the_file(catalog):
    for k, activity in enumerate(catalog):
        heading = (0.37 * k) % (2 * math.pi)
        person = Placement(f"vp{k}", activity.id, k % 3, heading)
        sentence, model, degrees = to_entry(person, catalog)
        assert sentence.endswith(activity.text) and ":" in sentence
        (back,) = from_entries({person.viewpoint: (sentence, model, degrees)}, catalog)
        assert back.activity == activity.id and back.model == k % 3
        assert math.isclose(back.heading, heading, abs_tol=1e-4)
    for degrees in (0.0, 91.0, 184.0, 359.5):
        assert ha3d_degrees(ha3d_heading(degrees)) == pytest.approx(degrees)


def test_save_keeps_other_scans_and_load_reads_them_back(tmp_path, catalog):
    path = tmp_path / "placements.json"
    path.write_text(json.dumps({"other": {"v": ["kitchen:Someone cooking.", 2, 10]}}))
    people = [
        Placement("a", "kitchen/dishwasher", 1, 0.5),
        Placement("b", "hallway/walk-hall", 0, 0.0),
    ]
    save_people(path, "proc-0", people, catalog)
    raw = read_ha3d_placements(path)
    assert raw["other"] == {"v": ("kitchen:Someone cooking.", 2, 10.0)}
    assert raw["proc-0"]["a"] == ("kitchen:A person loading the dishwasher.", 1, ha3d_degrees(0.5))
    assert [(p.viewpoint, p.activity, p.model) for p in load_people(path, "proc-0", catalog)] == [
        (p.viewpoint, p.activity, p.model) for p in people
    ]
    save_people(path, "proc-0", [], catalog)  # nobody left: the scan leaves the file
    assert set(read_ha3d_placements(path)) == {"other"}
    assert [p.name for p in tmp_path.iterdir()] == ["placements.json"]  # no partial file
    assert load_people(tmp_path / "none.json", "proc-0", catalog) == []


def test_a_broken_file_is_never_overwritten(tmp_path, catalog):
    path = tmp_path / "broken.json"
    path.write_text("{not json")
    with pytest.raises(MalformedDataError, match="not overwriting"):
        save_people(path, "proc-0", [Placement("a", "kitchen/dishwasher")], catalog)
    assert path.read_text() == "{not json"


def test_ha3d_sentences_are_kept_as_read(shared_data, tmp_path, catalog):
    """HA3D's own file: loading a scan's people and saving them rewrites the same entries."""
    source = shared_data / "ha3d" / "human_placements.json"
    original = read_ha3d_placements(source)
    path = tmp_path / "copy.json"
    for scan in list(original)[:10]:
        save_people(path, scan, load_people(source, scan, catalog), catalog)
    copied = read_ha3d_placements(path)
    for scan in copied:
        for vp, (sentence, model, degrees) in original[scan].items():
            got = copied[scan][vp]
            assert got[:2] == (sentence, model) and got[2] == pytest.approx(degrees)


def test_check_people_names_what_is_wrong(graph, catalog):
    vp, other = graph.nodes[0], graph.nodes[1]
    check_people([Placement(vp, "kitchen/dishwasher"), Placement(other, "hallway/walk-hall")],
                 graph, catalog)  # fmt: skip
    cases = [
        ([Placement("nowhere", "kitchen/dishwasher")], UnknownViewpointError, "nowhere"),
        ([Placement(vp, "kitchen/dishwash")], InvalidArgumentError, "did you mean"),
        ([Placement(vp, "kitchen/dishwasher", 3)], InvalidArgumentError, r"one of \(0, 1, 2\)"),
        ([Placement(vp, "kitchen/dishwasher", 0, math.nan)], InvalidArgumentError, "finite"),
        (
            [Placement(vp, "kitchen/dishwasher"), Placement(vp, "hallway/walk-hall")],
            InvalidArgumentError,
            "already has a person",
        ),
    ]
    sitting = next(a for a in catalog if a.needs_seat)
    cases.append(([Placement(vp, sitting.id)], InvalidArgumentError, "carry no seat|sits"))
    for people, error, message in cases:
        with pytest.raises(error, match=f"(?i){message}"):
            check_people(people, graph, catalog)


def test_the_simulator_plays_what_was_saved(tmp_path, graph, catalog):
    """Entries as written give the simulator's crowd those activities on those viewpoints."""
    vps = list(graph.nodes[:3])
    acts = [
        next(a.id for a in catalog.activities(code) if not (a.needs_seat or a.needs_path))
        for code in ("k", "o", "v")
    ]
    people = [Placement(v, a, 1, 1.0) for v, a in zip(vps, acts, strict=True)]
    path = tmp_path / "p.json"
    save_people(path, "proc-0", people, catalog)
    crowd = populate_ha3d(graph, read_ha3d_placements(path)["proc-0"], np.random.default_rng(0))
    got = {p.viewpoint: (p.activity, round(p.heading, 3)) for p in crowd.people}
    assert got == {v: (a, 1.0) for v, a in zip(vps, acts, strict=True)}
