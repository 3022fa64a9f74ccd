"""Ray evaluation equals the single-process one; scenes build as Ray tasks."""

from __future__ import annotations

import pytest

ray = pytest.importorskip("ray")

from havln_mj.distributed import build_scenes_ray, evaluate_split_ray  # noqa: E402
from havln_mj.distributed.sharded import _pieces, _shards  # noqa: E402
from havln_mj.eval.cli import parse_args  # noqa: E402
from havln_mj.eval.run import evaluate_split  # noqa: E402
from havln_mj.tasks.procedural import procedural_episodes  # noqa: E402

TIMING = ("seconds", "instructions_per_s")
ARGV = ["--scenes", "proc-0", "proc-1", "--per-scene", "2"]


@pytest.fixture(scope="module")
def ray_local():
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield ray
    ray.shutdown()


@pytest.fixture(scope="module")
def episodes():
    return procedural_episodes(["proc-0", "proc-1"], 2, 0)


def _untimed(report: dict) -> dict:
    summary = {k: v for k, v in report["summary"].items() if k not in TIMING}
    records = [
        {k: v for k, v in r.items() if k not in ("seconds", "split")} for r in report["records"]
    ]
    return {**report, "summary": summary, "records": records}


@pytest.mark.parametrize("agent", ["shortest", "oracle"])
def test_ray_matches_single_process(ray_local, episodes, agent, tmp_path):
    args = parse_args([*ARGV, "--agent", agent, "--workers", "2", "--out", str(tmp_path)])
    assert args.workers == 2 and args.address is None
    single = evaluate_split(args, episodes, "procedural")
    distributed = evaluate_split_ray(args, episodes, "procedural", workers=args.workers)
    assert single["summary"]["instructions"] == 12
    assert _untimed(distributed) == _untimed(single)


def test_random_agent_deterministic_across_workers(ray_local, episodes, tmp_path):
    args = parse_args([*ARGV, "--agent", "random", "--out", str(tmp_path)])
    one = evaluate_split_ray(args, episodes, "p", workers=1)
    two = evaluate_split_ray(args, episodes, "p", workers=2)
    assert _untimed(one) == _untimed(two)


def test_shards_cover_in_order():
    assert [list(r) for r in _shards(5, 2)] == [[0, 1], [2, 3, 4]]
    assert [list(r) for r in _shards(1, 4)] == [[0]]
    assert _shards(0, 2) == []
    # Each shard goes to its actor in pieces, in order, for the progress bar.
    assert [list(r) for r in _pieces(range(3, 10), 3)] == [[3, 4, 5], [6, 7, 8], [9]]


def test_build_scenes_ray(ray_local):
    rows = build_scenes_ray(["proc-0", "proc-1"])
    assert [r["scene"] for r in rows] == ["proc-0", "proc-1"]
    for row in rows:
        assert "error" not in row
        assert row["viewpoints"] > 0


def test_cli(ray_local, tmp_path, capsys):
    from havln_mj.cli import main
    from havln_mj.distributed.evaluate import main as alias

    argv = [*ARGV, "--agent", "shortest", "--out", str(tmp_path / "a")]
    assert main(["eval", *argv, "--workers", "2"]) == 0
    assert (tmp_path / "a" / "summary.json").exists()
    assert "| shortest (strict) |" in capsys.readouterr().out
    # python -m havln_mj.distributed.evaluate: the same command, two workers by default.
    assert alias([*ARGV, "--agent", "shortest", "--out", str(tmp_path / "b")]) == 0
    assert (tmp_path / "b" / "episodes.json").exists()
