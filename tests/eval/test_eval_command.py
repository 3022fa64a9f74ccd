"""``python -m havln_mj.eval`` end to end: splits, protocols, people, resuming, bad input."""

from __future__ import annotations

import itertools
import json

import pytest

from havln_mj.commands.evaluate import main
from havln_mj.errors import InvalidArgumentError
from havln_mj.eval import run as eval_run
from havln_mj.eval.cli import parse_args
from havln_mj.eval.outputs import PROGRESS, RUN
from havln_mj.eval.setup import make_agent, metric_config
from havln_mj.scene.scan import scans_dir
from havln_mj.sim.rules import HumanClock
from havln_mj.tasks.metrics import MetricConfig


def _summary(out):
    (summary,) = json.loads((out / "summary.json").read_text())
    return summary


def test_procedural_split_tables_and_submission(tmp_path):
    out = tmp_path / "eval"
    args = "--scenes proc-0 proc-1 --per-scene 3 --agent shortest --seed 2"
    assert main([*args.split(), "--out", str(out)]) == 0
    summary = _summary(out)
    assert summary["instructions"] == 18 and summary["split"] == "procedural"  # 3 per path
    assert summary["sr"] == 1.0 and summary["ne"] == 0.0 and summary["spl"] == pytest.approx(1.0)
    assert summary["protocol"] == "strict" and summary["collision_rule"]["check"] == "action"
    people = summary["people"]
    assert people["count"] > 0 and "HA3D's rule" in next(iter(people["sources"]))
    submission = json.loads((out / "submission.json").read_text())
    assert len(submission) == 18 and all(s["trajectory"][0][0] for s in submission)
    episodes = json.loads((out / "episodes.json").read_text())
    assert {e["instr_id"] for e in episodes} == {s["instr_id"] for s in submission}
    assert len((out / PROGRESS).read_text().splitlines()) == 18
    table = (out / "summary.md").read_text()
    assert "| shortest (strict) |" in table and "NE | TCR | CR | SR" in table


def test_critical_ha3d_reaches_the_whole_ha3d_metric_rule(tmp_path):
    base = ["--scenes", "proc-0", "--out", str(tmp_path)]
    assert metric_config(parse_args([*base, "--critical", "ha3d"])) == MetricConfig.ha3d()
    assert metric_config(parse_args([*base, "--protocol", "ha3d"])) == MetricConfig.ha3d()
    assert metric_config(parse_args(base)) == MetricConfig()
    assert metric_config(parse_args([*base, "--critical", "none"])).critical == "none"
    counted = metric_config(parse_args([*base, "--protocol", "ha3d", "--count", "viewpoint"]))
    assert counted.count == "viewpoint" and not counted.clip
    # End to end, the summary says which rules scored it.
    out = tmp_path / "crit"
    argv = ["--scenes", "proc-0", "--per-scene", "2", "--critical", "ha3d", "--out", str(out)]
    assert main(argv) == 0
    metrics = _summary(out)["metrics"]
    assert metrics["critical"] == "ha3d" and not metrics["clip"] and not metrics["cr_adjusted"]


def test_ha3d_protocol_on_the_expert(tmp_path):
    out = tmp_path / "ha3d"
    argv = "--scenes proc-0 --per-scene 4 --agent oracle --protocol ha3d --seed 1"
    assert main([*argv.split(), "--out", str(out)]) == 0
    summary = _summary(out)
    assert summary["protocol"] == "ha3d" and summary["expert_max_steps"] == 20
    assert summary["collision_rule"] == {"check": "state", "distance": "camera_3d", "threshold": 1}
    assert summary["human_clock"]["kind"] == "ha3d" and summary["steps"] <= 20
    records = [json.loads(x) for x in (out / PROGRESS).read_text().splitlines()]
    # One shared clock: each instruction starts where the last one left the counter, which
    # its start moved on 16 frames and each action (STOP is none) 32.
    clock = HumanClock.ha3d()
    assert all(a["frames"][1] == b["frames"][0] for a, b in itertools.pairwise(records))
    for r in records:
        frame = clock.after_start(r["frames"][0])
        for _ in range(len(r["r2r"]) - 1):
            frame = clock.after_action(frame)
        assert r["frames"][1] == frame


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
    summary = _summary(out)
    assert summary["instructions"] == 1021
    assert summary["sr"] == 1.0 and summary["ndtw"] == pytest.approx(1.0)
    assert 0.0 < summary["cr"] < 1.0  # people stand on some shortest paths
    assert summary["people"]["count"] == 259 and summary["people"]["scans"] == 56


def test_real_scans_without_placements_fail_fast_naming_the_flag(
    tmp_path, shared_data, capsys, monkeypatch
):
    monkeypatch.delenv("HAVLN_HA3D_PLACEMENTS", raising=False)
    built = set(scans_dir().glob("*")) if scans_dir().is_dir() else set()
    conn = ["--connectivity-dir", str(shared_data / "mp3d_connectivity")]
    for data in (
        shared_data / "ha_r2r" / "HA_val_seen.json",
        shared_data / "r2r" / "R2R_val_seen.json",
    ):
        argv = ["--dataset", str(data), *conn, "--out", str(tmp_path / "x")]
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "--human-placements" in err and "nobody to place" in err
    # Nothing was built to find that out (a graph proxy takes minutes).
    assert (set(scans_dir().glob("*")) if scans_dir().is_dir() else set()) == built
    # An empty building on purpose.
    argv = ["--dataset", str(data), *conn, "--no-people", "--out", str(tmp_path / "y")]
    assert main(argv) == 0
    assert _summary(tmp_path / "y")["people"]["count"] == 0


def test_placements_that_are_not_the_datasets_are_refused(tmp_path, shared_data, capsys):
    data = json.loads((shared_data / "ha3d" / "human_placements.json").read_text())
    data = {scan: dict(list(entries.items())[1:]) for scan, entries in data.items()}
    placements = tmp_path / "fewer.json"
    placements.write_text(json.dumps(data))
    argv = [
        "--dataset", str(shared_data / "ha_r2r" / "HA_val_seen.json"),
        "--connectivity-dir", str(shared_data / "mp3d_connectivity"),
        "--human-placements", str(placements), "--out", str(tmp_path / "x"),
    ]  # fmt: skip
    assert main(argv) == 2
    assert "not the ones the dataset was made with" in capsys.readouterr().err


def test_an_interrupted_evaluation_resumes_where_it_stopped(tmp_path, monkeypatch, capsys):
    args = "--scenes proc-0 --per-scene 3 --agent oracle --protocol ha3d --seed 3"
    argv = args.split()
    whole, cut = tmp_path / "whole", tmp_path / "cut"
    assert main([*argv, "--out", str(whole)]) == 0

    real, calls = eval_run.run_expert, []

    def interrupted(*a, **kw):
        calls.append(1)
        if len(calls) == 5:
            raise KeyboardInterrupt
        return real(*a, **kw)

    monkeypatch.setattr(eval_run, "run_expert", interrupted)
    assert main([*argv, "--out", str(cut)]) == 130
    assert "--resume" in capsys.readouterr().err
    assert len((cut / PROGRESS).read_text().splitlines()) == 4
    assert not (cut / "summary.json").exists()
    with open(cut / PROGRESS, "a") as f:
        f.write('{"split": "procedural", "instr_id": "torn')  # a line cut by the interrupt
    calls.clear()

    def counted(*a, **kw):
        calls.append(1)
        return real(*a, **kw)

    monkeypatch.setattr(eval_run, "run_expert", counted)
    assert main([*argv, "--out", str(cut), "--resume"]) == 0
    assert len(calls) == 9 - 4  # only what had not finished
    for name in ("episodes.json", "submission.json"):
        assert json.loads((cut / name).read_text()) == json.loads((whole / name).read_text())
    a, b = _summary(whole), _summary(cut)
    assert {k: v for k, v in a.items() if "seconds" not in k and "per_s" not in k} == {
        k: v for k, v in b.items() if "seconds" not in k and "per_s" not in k
    }
    # Resuming with other settings is refused; a fresh run clears the folder first.
    assert main([*argv[:-1], "4", "--out", str(cut), "--resume"]) == 2
    assert "other settings" in capsys.readouterr().err
    assert main(["--scenes", "proc-0", "--per-scene", "1", "--out", str(cut)]) == 0
    assert len((cut / PROGRESS).read_text().splitlines()) == 3


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        ("--seed -1", "--seed must be in [0, 2^32)"),
        ("--per-scene 0", "--per-scene must be at least 1"),
        ("--skip -2", "--skip must be ≥ 0"),
        ("--record -1", "--record must be ≥ 0"),
        ("--threads 0", "--threads must be at least 1"),
        ("--protocol lenient", "invalid choice: 'lenient'"),
        ("--count minute", "invalid choice: 'minute'"),
        ("--human-placements /no/such/file.json", "is not a file"),
        ("--connectivity-dir /no/such/folder", "is not a folder"),
        ("--seed x", "invalid int value"),
    ],
)
def test_bad_flags_are_refused_before_any_work(flags, message, tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["--scenes", "proc-0", *flags.split(), "--out", str(tmp_path / "o")])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_bad_outputs_and_resume_without_an_evaluation(tmp_path, capsys):
    afile = tmp_path / "file"
    afile.write_text("x")
    with pytest.raises(SystemExit):
        main(["--scenes", "proc-0", "--out", str(afile)])
    assert "is a file" in capsys.readouterr().err
    assert main(["--scenes", "proc-0", "--out", str(tmp_path / "new"), "--resume"]) == 2
    assert "holds no evaluation to resume" in capsys.readouterr().err
    assert not (tmp_path / "new" / RUN).exists()


def test_bad_agent_names_the_valid_ones(tmp_path):
    with pytest.raises(InvalidArgumentError, match="shortest"):
        make_agent("teleport")
    assert main(["--scenes", "proc-0", "--agent", "nope:thing", "--out", str(tmp_path)]) == 2


def test_the_go1_body_runs_the_same_split(tmp_path):
    out = tmp_path / "go1"
    args = "--scenes proc-0 --per-scene 1 --agent shortest --body go1 --no-people"
    assert main([*args.split(), "--out", str(out)]) == 0
    summary = _summary(out)
    assert summary["body"] == "go1" and summary["sr"] == 1.0 and summary["collisions"] == 0
    assert summary["instructions"] == 3


def test_paths_without_instructions_are_refused_blank_ones_reported(tmp_path, shared_data, capsys):
    data = json.loads((shared_data / "ha_r2r" / "HA_val_seen.json").read_text())[:3]
    conn = ["--connectivity-dir", str(shared_data / "mp3d_connectivity"), "--no-people"]
    path = tmp_path / "bad.json"
    data[1]["instructions"] = []
    path.write_text(json.dumps(data))
    assert main(["--dataset", str(path), *conn, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "no instructions" in err and str(data[1]["path_id"]) in err
    # HA-R2R val_seen itself holds 13 blank instructions: evaluated as HA3D did, and said so.
    data[1]["instructions"] = ["go", " "]
    path.write_text(json.dumps(data))
    assert main(["--dataset", str(path), *conn, "--out", str(tmp_path / "o")]) == 0
    blank = f"{data[1]['path_id']}_1"
    assert blank in capsys.readouterr().err
    assert _summary(tmp_path / "o")["blank_instructions"] == [blank]
