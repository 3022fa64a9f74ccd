"""The activity catalog: coverage, our own wording, clips for every activity, HA3D mapping."""

from __future__ import annotations

import difflib
import json
import os
from pathlib import Path

import numpy as np
import pytest

from havln_mj.errors import InvalidArgumentError, MalformedDataError
from havln_mj.humans.catalog import HA3D_REGIONS, load_catalog, make_clip
from havln_mj.humans.clip import Clip
from havln_mj.humans.motion import RECIPES
from havln_mj.scene.regions import REGION_LABELS

HAPS_CODES = [c for c in REGION_LABELS if c not in ("Z", "-")]  # the 29 kinds with activities
_SHARED = Path(
    os.environ.get("HAVLN_SHARED_DATA", Path(__file__).resolve().parents[3] / "shared" / "data")
)


@pytest.fixture(scope="module")
def catalog():
    return load_catalog()


def _haps_sentences() -> dict[str, list[str]]:
    path = _SHARED / "ha3d" / "region_activities.json"
    if not path.is_file():
        pytest.skip(f"HA3D region activities not found at {path}")
    return json.loads(path.read_text())


def test_every_region_kind_has_at_least_five_activities(catalog):
    assert len(HAPS_CODES) == 29
    assert sorted(catalog.regions()) == sorted(HAPS_CODES)
    for code in HAPS_CODES:
        acts = catalog.activities(code)
        assert len(acts) >= 5, code
        assert all(a.region == code for a in acts)
        # Every region offers something that needs neither a seat nor a path.
        assert any(not a.needs_seat and not a.needs_path for a in acts), code


def test_activities_are_well_formed_and_unique(catalog):
    acts = list(catalog)
    assert len({a.id for a in acts}) == len(acts)
    assert len({a.text.lower() for a in acts}) == len(acts)
    for a in acts:
        assert a.recipe in RECIPES
        assert a.text.endswith(".") and 10 < len(a.text) < 80
        assert a.verb[:1].islower() and not a.verb.endswith(".")
        assert a.needs_seat == bool(a.params.get("needs_seat"))
        assert catalog.get(a.id) is a
    recipes = {a.recipe for a in acts}
    assert recipes == set(RECIPES)  # every recipe is used somewhere


def test_texts_are_our_own_words():
    haps = [s.lower() for sents in _haps_sentences().values() for s in sents]
    for a in load_catalog():
        assert a.text.lower() not in haps
        closest = max(difflib.SequenceMatcher(None, a.text.lower(), s).ratio() for s in haps)
        assert closest < 0.8, a.text


def test_every_activity_builds_a_clip(catalog):
    rng = np.random.default_rng(0)
    path = np.array([[0.0, 0.0], [0.5, 3.0]])
    for a in catalog:
        clip = make_clip(
            a,
            1.68,
            rng,
            seat_height=0.45 if a.needs_seat else None,
            path=path if a.needs_path else None,
        )
        assert isinstance(clip, Clip) and clip.frames > 30 and np.isfinite(clip.local).all()
        if a.needs_path:  # the walker reaches both ends of the path
            d = np.linalg.norm(clip.root[:, None, :2] - path[None], axis=2).min(axis=0)
            assert (d < 0.1).all(), a.id


def test_missing_seat_or_path_is_a_clear_error(catalog):
    rng = np.random.default_rng(0)
    sitting = next(a for a in catalog if a.needs_seat)
    walking = next(a for a in catalog if a.recipe == "walk_path")
    pacing = next(a for a in catalog if a.recipe == "pace")
    with pytest.raises(InvalidArgumentError, match="seat_height"):
        make_clip(sitting, 1.7, rng)
    with pytest.raises(InvalidArgumentError, match="path"):
        make_clip(walking, 1.7, rng)
    with pytest.raises(InvalidArgumentError, match="two ground points"):
        make_clip(pacing, 1.7, rng, path=np.array([[0.0, 0.0]]))


def test_same_seed_same_clip(catalog):
    a = catalog.activities("k")[0]
    c1 = make_clip(a, 1.7, np.random.default_rng(3))
    c2 = make_clip(a, 1.7, np.random.default_rng(3))
    np.testing.assert_array_equal(c1.local, c2.local)


def test_lookup_by_code_name_or_ha3d_name(catalog):
    kitchen = catalog.activities("k")
    assert catalog.activities("kitchen") == kitchen
    assert catalog.activities("Kitchen") == kitchen
    assert catalog.activities("tv") == catalog.activities("v")
    for name, code in HA3D_REGIONS.items():
        assert catalog.region_code(name) == code


def test_unknown_region_names_valid_codes(catalog):
    with pytest.raises(InvalidArgumentError) as err:
        catalog.activities("kitchn")
    msg = str(err.value)
    assert "'kitchn'" in msg and "k (kitchen)" in msg and "S (spa)" in msg
    assert "Did you mean 'kitchen'" in msg
    with pytest.raises(InvalidArgumentError, match="valid region codes"):
        catalog.activities("Z")  # junk regions have no activities


def test_map_ha3d_picks_by_keywords_within_the_region(catalog):
    rng = np.random.default_rng(0)
    act = catalog.map_ha3d("hallway:Someone talking on the phone while pacing.", rng)
    assert act.region == "h" and act.recipe == "pace" and act.params.get("phone")
    act = catalog.map_ha3d("bathroom:A person brushing their teeth in front of the mirror.", rng)
    assert act.id == "bathroom/brush-teeth"
    act = catalog.map_ha3d("tv:An individual enjoying a sports game, cheering loudly.", rng)
    assert act.region == "v" and "cheer" in act.text
    # No shared words: a deterministic draw from the region.
    picks = [catalog.map_ha3d("spa/sauna:Zzz.", np.random.default_rng(5)).id for _ in range(3)]
    assert len(set(picks)) == 1 and picks[0].startswith("spa/")
    with pytest.raises(InvalidArgumentError, match="region:activity"):
        catalog.map_ha3d("no region here", rng)


def test_map_ha3d_covers_every_real_placement(catalog):
    path = _SHARED / "ha3d" / "human_placements.json"
    if not path.is_file():
        pytest.skip(f"HA3D placements not found at {path}")
    rng = np.random.default_rng(0)
    for entries in json.loads(path.read_text()).values():
        for text, *_ in entries.values():
            region = text.partition(":")[0]
            assert catalog.map_ha3d(text, rng).region == HA3D_REGIONS[region]


def test_malformed_catalogs_are_rejected(tmp_path):
    def write(activity: dict) -> Path:
        p = tmp_path / "cat.json"
        p.write_text(json.dumps({"regions": {"k": {"name": "kitchen", "activities": [activity]}}}))
        return p

    good = {"id": "k/x", "text": "Someone cooking.", "verb": "cooking", "recipe": "idle"}
    assert len(load_catalog(write(good))) == 1
    with pytest.raises(MalformedDataError, match="unknown recipe 'dance'"):
        load_catalog(write({**good, "recipe": "dance"}))
    with pytest.raises(MalformedDataError, match="takes no \\['speed'\\]"):
        load_catalog(write({**good, "params": {"speed": 1.0}}))
    with pytest.raises(MalformedDataError, match="expected"):
        load_catalog(write({"id": "k/x"}))
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"regions": {"kk": {"activities": []}}}))
    with pytest.raises(MalformedDataError, match="unknown region code 'kk'"):
        load_catalog(bad)
