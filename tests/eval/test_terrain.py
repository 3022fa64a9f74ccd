"""Honest accounting by terrain: flat and stair episodes apart, falls always counted."""

from __future__ import annotations

import pytest

from havln_mj.eval.run import terrain_report
from havln_mj.scene.navgraph import STAIR_CLIMB, stair_edges
from havln_mj.scene.scan import load_scan


def _record(terrain, stopped, distance, fell, seconds=10.0):
    return {
        "terrain": terrain,
        "stopped": stopped,
        "true_distance": distance,
        "fell": fell,
        "sim_seconds": seconds,
    }


def test_falls_and_stalls_on_stairs_count_against_the_stairs():
    records = [
        _record("flat", True, 0.4, False),
        _record("flat", True, 3.5, False),  # stopped too far: not a success
        _record("stairs", False, 4.0, True, 6.0),  # fell on the stair: counted, never skipped
        _record("stairs", True, 1.0, False, 30.0),
        _record("stairs", True, 2.9, False, 20.0),
    ]
    report = terrain_report(records, 3.0)
    assert report["flat"] == {
        "instructions": 2,
        "success_rate": 0.5,
        "falls": 0,
        "mean_distance_m": pytest.approx(1.95),
        "mean_sim_seconds": 10.0,
    }
    stairs = report["stairs"]
    assert stairs["instructions"] == 3 and stairs["falls"] == 1
    assert stairs["success_rate"] == pytest.approx(2 / 3)
    assert stairs["mean_sim_seconds"] == pytest.approx(56 / 3)


def test_stair_edges_climb_more_than_the_threshold(shared_data):
    # A real graph with storeys: its edges between floors are stair edges, the others not.
    scan = load_scan("17DRP5sb8fy", connectivity_dir=shared_data / "mp3d_connectivity")
    g = scan.graph
    for a, b, _ in g.edges():
        climbs = abs(g.floor_z(a) - g.floor_z(b)) > STAIR_CLIMB
        assert (stair_edges(g, [a, b]) == [(a, b)]) == climbs


def test_eval_records_say_the_terrain_the_fall_and_the_true_distance(tmp_path):
    from havln_mj.commands.evaluate import main

    out = tmp_path / "ev"
    assert main(["--scenes", "proc-0", "--per-scene", "1", "--out", str(out)]) == 0
    import json

    lines = (out / "instructions.jsonl").read_text().splitlines()
    record = json.loads(lines[0])
    assert record["terrain"] in ("flat", "stairs") and record["fell"] is False
    assert record["true_distance"] < 3.0 and record["sim_seconds"] > 0
    summary = json.loads((out / "summary.json").read_text())[0]
    assert summary["by_terrain"]["flat"]["instructions"] == len(lines)
