"""Benchmark: the human-aware expert's path planning on the 90 MatterSim navigation graphs.

Usage: python benchmarks/bench_planning.py [--data DIR] [--queries N] [--seed S]

Per graph, ``N`` seeded cases: a start and goal in one component and 1-4 people standing at
random viewpoints; the nodes within 1 m of them are blocked (``blocked_nodes``, start and
goal kept). Times ``blocked_nodes``, ``plan_path`` around the blocked nodes by length and by
hops, ``plan_path`` with nothing blocked, and a ``PathPlanner`` held across the cases (as the
experts hold one per scan: ``planner_*``). ``graph.distance`` (a look-up in the cached
all-pairs matrix) is timed in the same run as the anchor: the ``per_lookup`` ratios compare
runs on a noisy machine.
DIR is the shared data folder holding ``mp3d_connectivity/`` (default ``$HAVLN_SHARED_DATA``,
else ``../shared/data`` beside the repository). Prints one JSON object to stdout.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from common import machine

from havln_mj.scene.navgraph import NavGraph
from havln_mj.tasks.planning import PathPlanner, blocked_nodes, plan_path

_DEFAULT_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def _cases(graph: NavGraph, n: int, rng: np.random.Generator) -> list[tuple]:
    """(start, goal, people) with the goal reachable from the start."""
    nodes = graph.nodes
    dist = graph.distance_matrix()
    out = []
    while len(out) < n:
        i, j = rng.integers(0, len(nodes), 2)
        if i == j or not np.isfinite(dist[i, j]):
            continue
        at = rng.choice(len(nodes), size=int(rng.integers(1, 5)), replace=False)
        people = [graph.position(nodes[k]) - (0.0, 0.0, 0.6) for k in at]
        out.append((nodes[i], nodes[j], people))
    return out


def _time_graph(graph: NavGraph, cases: list[tuple]) -> tuple[dict[str, float], int]:
    """Seconds each job takes over ``cases``, and how many nodes the cases block."""
    planner = PathPlanner(graph)
    blocked = [blocked_nodes(graph, p, 1.0, (a, b)) for a, b, p in cases]
    jobs: dict[str, Callable] = {
        "lookup": lambda a, b, p, s: graph.distance(a, b),
        "blocked_nodes": lambda a, b, p, s: blocked_nodes(graph, p, 1.0, (a, b)),
        "weighted": lambda a, b, p, s: plan_path(graph, a, b, s),
        "hops": lambda a, b, p, s: plan_path(graph, a, b, s, weighted=False),
        "unblocked": lambda a, b, p, s: plan_path(graph, a, b),
        "planner_blocked": lambda a, b, p, s: planner.blocked(p, 1.0, (a, b)),
        "planner": lambda a, b, p, s: planner.plan(a, b, s),
        "planner_hops": lambda a, b, p, s: planner.plan(a, b, s, weighted=False),
    }
    seconds = {}
    for name, job in jobs.items():
        t = time.perf_counter()
        for (a, b, p), s in zip(cases, blocked, strict=True):
            job(a, b, p, s)
        seconds[name] = time.perf_counter() - t
    return seconds, sum(map(len, blocked))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--data",
        type=Path,
        default=Path(os.environ.get("HAVLN_SHARED_DATA", _DEFAULT_DATA)),
        help="shared data folder holding mp3d_connectivity/ (default: %(default)s)",
    )
    parser.add_argument("--queries", type=int, default=200, help="cases per graph")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    folder = args.data / "mp3d_connectivity"
    scans_file = folder / "scans.txt"
    if not scans_file.is_file():
        sys.exit(f"no {scans_file}: pass --data or set HAVLN_SHARED_DATA")
    scans = scans_file.read_text().split()
    rng = np.random.default_rng(args.seed)

    totals: dict[str, float] = {}
    calls = blocked_total = 0
    for scan in scans:
        graph = NavGraph.from_file(folder / f"{scan}_connectivity.json")
        cases = _cases(graph, args.queries, rng)
        seconds, blocked = _time_graph(graph, cases)
        for name, t in seconds.items():
            totals[name] = totals.get(name, 0.0) + t
        calls += len(cases)
        blocked_total += blocked

    us = {k: round(1e6 * v / calls, 2) for k, v in totals.items()}
    result = {
        "machine": machine(),
        "graphs": len(scans),
        "cases": calls,
        "mean_blocked_nodes": round(blocked_total / calls, 2),
        "us_per_call": us,
        "per_lookup": {k: round(v / totals["lookup"], 1) for k, v in totals.items()},
    }
    print(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
