"""Procedural HA-R2R splits: paths, people shared with the simulator, files, determinism."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import havln_mj as MatterSim  # noqa: N812 - MatterSim code, only the import changed
from havln_mj.errors import InvalidArgumentError, UnknownSceneError
from havln_mj.scene.scan import load_scan
from havln_mj.tasks.annotate import crux_points, humans_on_path
from havln_mj.tasks.datasets import load_dataset
from havln_mj.tasks.instructions import tokenize
from havln_mj.tasks.procedural import (
    MAX_DISTANCE,
    MAX_VIEWPOINTS,
    MIN_DISTANCE,
    MIN_VIEWPOINTS,
    build_split,
    candidate_paths,
    read_vocab,
    scene_crowd,
    split_path_id_base,
)

SCENES = ["proc-0", "proc-1", "proc-2", "proc-4", "proc-6", "proc-8"]
SEED = 7


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    return build_split(SCENES, "val_seen", 30, SEED, tmp_path_factory.mktemp("split"))


def test_paths_are_r2r_like_shortest_paths(built):
    assert len(built.episodes) == 30 * len(SCENES)
    ids = [e.path_id for e in built.episodes]
    assert len(set(ids)) == len(ids) and min(ids) >= split_path_id_base("val_seen")
    for e in built.episodes:
        graph = load_scan(e.scan).graph
        assert MIN_VIEWPOINTS <= len(e.path) <= MAX_VIEWPOINTS
        assert MIN_DISTANCE <= e.distance <= MAX_DISTANCE
        assert math.isclose(graph.path_length(e.path), graph.distance(e.start, e.goal))
        assert math.isclose(e.distance, graph.distance(e.start, e.goal), abs_tol=0.01)
        assert 0.0 <= e.heading < 2 * math.pi
        assert e.crux_points == crux_points(e.path, graph)
    per_scene = {s: {e.path for e in built.episodes if e.scan == s} for s in SCENES}
    assert all(len(p) == 30 for p in per_scene.values())  # no path drawn twice


def test_people_and_descriptions_follow_ha3d(built):
    with_people = 0
    crowds = {s: scene_crowd(load_scan(s), SEED) for s in SCENES}
    for e in built.episodes:
        scan, crowd = load_scan(e.scan), crowds[e.scan]
        placements = {p.viewpoint: p for p in crowd.people}
        expected = humans_on_path(e.path, scan.graph, {v: "x" for v in placements})
        assert [(h.viewpoint, h.rel_pos) for h in e.humans] == [
            (h.viewpoint, h.rel_pos) for h in expected
        ]
        for h in e.humans:
            assert h.description.endswith(":" + placements[h.viewpoint].text)
        if e.humans:
            with_people += 1
            assert len(e.rel_pos_descriptions) == 3
            for text, about in zip(e.instructions, e.rel_pos_descriptions, strict=True):
                assert about and all(part in text for part in about.split(". "))
        else:
            assert e.rel_pos_descriptions is None
    assert with_people > len(built.episodes) // 4
    rels = {h.rel_pos for e in built.episodes for h in e.humans}
    assert {"Obstacle", "Around"} <= rels


def test_people_match_the_simulator(built):
    sim = MatterSim.Simulator(humans=True)
    sim.setRenderingEnabled(False)
    sim.setSeed(SEED)
    sim.initialize()
    for scene in SCENES[:3]:
        scan = load_scan(scene)
        crowd = scene_crowd(scan, SEED)
        start = next(e for e in built.episodes if e.scan == scene).start
        sim.newEpisode([scene], [start], [0.0], [0.0])
        got = sim.getHumanState()[0]
        want = crowd.states(0.0)
        assert [p.activity for p in got] == [p.activity for p in want]
        np.testing.assert_allclose([p.position for p in got], [p.position for p in want])
        # Every person the dataset names stands where one of the simulator's people stands.
        vps = {p.viewpoint for p in crowd.people}
        named = {h.viewpoint for e in built.episodes if e.scan == scene for h in e.humans}
        assert named and named <= vps
        for person, state in zip(crowd.people, got, strict=True):
            anchor = scan.graph.position(person.viewpoint)[:2]
            # Standing people are on their viewpoint; sitters and pacers move off a little.
            assert np.linalg.norm(state.position[:2] - anchor) < 6.5
    sim.close()


def test_instruction_lengths_and_vocabulary(built):
    words = np.array(built.word_counts())
    assert len(words) == 3 * len(built.episodes)
    assert 50 <= words.mean() <= 72, words.mean()
    assert words.min() >= 25
    for e in built.episodes:
        assert len(e.instructions) == 3 and len(set(e.instructions)) == 3
    vocab = read_vocab(built.vocab)
    counts: dict[str, int] = {}
    for e in built.episodes:
        for t in e.instructions:
            for tok in tokenize(t):
                counts[tok] = counts.get(tok, 0) + 1
    assert vocab == counts
    order = list(vocab.items())
    assert order == sorted(order, key=lambda kv: (-kv[1], kv[0]))


def test_files_round_trip(built):
    data = load_dataset(built.dataset)
    assert data.episodes == built.episodes
    raw = json.loads(built.dataset.read_text())
    assert set(raw[0]) >= {"distance", "scan", "path_id", "path", "heading", "instructions"}
    assert all("human" in r and "crux_points" in r for r in raw)
    assert built.dataset.name == "HA_val_seen.json" and built.vocab.name == "vocab_val_seen.txt"


def test_deterministic_and_order_free(built, tmp_path):
    again = build_split(SCENES[:2], "val_seen", 30, SEED, tmp_path / "a", progress=False)
    assert again.episodes == built.episodes[:60]
    swapped = build_split(SCENES[1::-1], "val_seen", 30, SEED, tmp_path / "b", progress=False)
    key = [(e.path, e.instructions, e.humans) for e in swapped.episodes]
    assert key[:30] == [(e.path, e.instructions, e.humans) for e in built.episodes[30:60]]
    other = build_split(SCENES[:1], "val_seen", 30, SEED + 1, tmp_path / "c", progress=False)
    assert [e.path for e in other.episodes] != [e.path for e in built.episodes[:30]]


def test_small_scenes_and_bad_input(tmp_path):
    small = build_split(["proc-9"], "train", 10_000, 0, tmp_path, progress=False)
    assert len(small.episodes) == len(candidate_paths(load_scan("proc-9").graph))
    with pytest.raises(UnknownSceneError, match="proc-x"):
        build_split(["proc-0", "proc-x"], "train", 2, 0, tmp_path / "bad")
    assert not (tmp_path / "bad").exists()
    with pytest.raises(InvalidArgumentError, match="more than once"):
        build_split(["proc-0", "proc-0"], "train", 2, 0, tmp_path)
    with pytest.raises(InvalidArgumentError, match="split name"):
        build_split(["proc-0"], "a/b", 2, 0, tmp_path)
    with pytest.raises(InvalidArgumentError, match="episodes per scene"):
        build_split(["proc-0"], "train", 0, 0, tmp_path)
    with pytest.raises(InvalidArgumentError, match="no scenes"):
        build_split([], "train", 2, 0, tmp_path)
