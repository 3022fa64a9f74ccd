"""``python -m havln_mj.eval`` end to end on a small procedural split and on HA-R2R val_seen."""

from __future__ import annotations

import json

import pytest

from havln_mj.errors import InvalidArgumentError
from havln_mj.eval.run import main, make_agent


def test_procedural_split_tables_and_submission(tmp_path):
    out = tmp_path / "eval"
    args = "--scenes proc-0 proc-1 --per-scene 3 --agent shortest --seed 2"
    assert main([*args.split(), "--out", str(out)]) == 0
    (summary,) = json.loads((out / "summary.json").read_text())
    assert summary["instructions"] == 18 and summary["split"] == "procedural"  # 3 per path
    assert summary["sr"] == 1.0 and summary["ne"] == 0.0 and summary["spl"] == pytest.approx(1.0)
    submission = json.loads((out / "submission.json").read_text())
    assert len(submission) == 18 and all(s["trajectory"][0][0] for s in submission)
    episodes = json.loads((out / "episodes.json").read_text())
    assert {e["instr_id"] for e in episodes} == {s["instr_id"] for s in submission}
    table = (out / "summary.md").read_text()
    assert "| shortest |" in table and "NE | TCR | CR | SR" in table


def test_ha_r2r_val_seen_with_the_optimal_expert(tmp_path, shared_data):
    out = tmp_path / "ha"
    args = [
        "--dataset", str(shared_data / "ha_r2r" / "HA_val_seen.json"),
        "--split", "val_seen", "--agent", "shortest",
        "--connectivity-dir", str(shared_data / "mp3d_connectivity"),
        "--human-placements", str(shared_data / "ha3d" / "human_placements.json"),
        "--out", str(out),
    ]  # fmt: skip
    assert main(args) == 0
    (summary,) = json.loads((out / "summary.json").read_text())
    assert summary["instructions"] == 1021
    assert summary["sr"] == 1.0 and summary["ndtw"] == pytest.approx(1.0)
    assert 0.0 < summary["cr"] < 1.0  # people stand on some shortest paths


def test_bad_agent_names_the_valid_ones(tmp_path):
    with pytest.raises(InvalidArgumentError, match="shortest"):
        make_agent("teleport")
    assert main(["--scenes", "proc-0", "--agent", "nope:thing", "--out", str(tmp_path)]) == 2


def test_the_go1_body_runs_the_same_split(tmp_path):
    out = tmp_path / "go1"
    args = "--scenes proc-0 --per-scene 1 --agent shortest --body go1 --no-people"
    assert main([*args.split(), "--out", str(out)]) == 0
    (summary,) = json.loads((out / "summary.json").read_text())
    assert summary["body"] == "go1" and summary["sr"] == 1.0 and summary["collisions"] == 0
    assert summary["instructions"] == 3
