"""Benchmark: the experts' evaluation of HA-R2R val_seen (1,021 instructions), both protocols.

Usage: python benchmarks/bench_eval_protocol.py [--data DIR]

For each protocol (``strict``, ``ha3d``) and expert (``shortest``, the optimal; ``oracle``, the
sub-optimal human-aware one), what ``python -m havln_mj.eval`` does, timed in parts:
``setup_s`` (simulator and the 56 scans' people), ``run_s`` (every instruction through the
simulator and the task step) and ``score_s`` (the metrics), with the results beside them.
The optimal expert in the same run is the anchor: ``oracle_over_shortest`` compares runs on
a noisy machine. DIR holds ``mp3d_connectivity/``, ``ha_r2r/`` and ``ha3d/`` (default
``$HAVLN_SHARED_DATA``, else ``../shared/data`` beside the repository). Prints one JSON object.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

from common import machine

from havln_mj.eval.cli import parse_args
from havln_mj.eval.run import run_instruction, score_split
from havln_mj.eval.setup import evaluation_simulator, make_agent, people_report, protocol_of
from havln_mj.tasks.datasets import load_dataset

_DEFAULT_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def _evaluate(data: Path, protocol: str, agent: str, episodes: list) -> dict:
    args = parse_args(
        [
            "--dataset", str(data / "ha_r2r" / "HA_val_seen.json"),
            "--connectivity-dir", str(data / "mp3d_connectivity"),
            "--human-placements", str(data / "ha3d" / "human_placements.json"),
            "--protocol", protocol, "--agent", agent,
        ]
    )  # fmt: skip
    t0 = time.perf_counter()
    sim = evaluation_simulator(args)
    people = people_report(sim, episodes)
    make, proto = make_agent(agent, args), protocol_of(args)
    t1 = time.perf_counter()
    records, index = [], 0
    for episode in episodes:
        for k in range(len(episode.instructions)):
            records.append(run_instruction(sim, episode, k, index, make, args, proto))
            index += 1
    t2 = time.perf_counter()
    summary = score_split(args, episodes, "val_seen", records, sim, people)["summary"]
    t3 = time.perf_counter()
    sim.close()
    return {
        "instructions": len(records),
        "setup_s": round(t1 - t0, 3),
        "run_s": round(t2 - t1, 3),
        "score_s": round(t3 - t2, 3),
        "total_s": round(t3 - t0, 3),
        **{k: round(summary[k], 4) for k in ("ne", "tcr", "cr", "sr", "steps")},
    }


def main() -> int:
    """Runs the benchmark and prints its JSON."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--data", type=Path, default=None)
    args = p.parse_args()
    data = args.data or Path(os.environ.get("HAVLN_SHARED_DATA", _DEFAULT_DATA))
    if not (data / "ha_r2r" / "HA_val_seen.json").is_file():
        print(f"no HA-R2R val_seen under {data} (give --data)", file=sys.stderr)
        return 2
    t0 = time.perf_counter()
    dataset = load_dataset(data / "ha_r2r" / "HA_val_seen.json")
    load_s = time.perf_counter() - t0
    results = {}
    for protocol in ("strict", "ha3d"):
        row = {
            a: _evaluate(data, protocol, a, list(dataset.episodes)) for a in ("shortest", "oracle")
        }
        row["oracle_over_shortest"] = round(row["oracle"]["run_s"] / row["shortest"]["run_s"], 2)
        results[protocol] = row
    print(
        json.dumps({"machine": machine(), "dataset_load_s": round(load_s, 3), **results}, indent=1)
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
