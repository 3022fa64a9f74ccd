"""Benchmark: load the 90 MatterSim navigation graphs and query geodesics.

Usage: python benchmarks/bench_navgraph.py [--data DIR] [--queries N]

DIR is the shared data folder holding ``mp3d_connectivity/`` (default ``$HAVLN_SHARED_DATA``,
else ``../shared/data`` beside the repository). Prints one JSON object to stdout.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import random
import sys
import time
from pathlib import Path

from havln_mj.scene.navgraph import NavGraph

_DEFAULT_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--data",
        type=Path,
        default=Path(os.environ.get("HAVLN_SHARED_DATA", _DEFAULT_DATA)),
        help="shared data folder holding mp3d_connectivity/ (default: %(default)s)",
    )
    parser.add_argument("--queries", type=int, default=20_000, help="shortest_path queries")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    folder = args.data / "mp3d_connectivity"
    scans_file = folder / "scans.txt"
    if not scans_file.is_file():
        sys.exit(
            f"bench_navgraph: connectivity data not found: {scans_file}\n"
            "Pass --data DIR or set HAVLN_SHARED_DATA to the folder holding mp3d_connectivity/."
        )
    scans = scans_file.read_text().split()

    t0 = time.perf_counter()
    graphs = {s: NavGraph.from_file(folder / f"{s}_connectivity.json") for s in scans}
    load_s = time.perf_counter() - t0

    # All-pairs Dijkstra on the largest scan, from a freshly loaded graph (lazy, cached).
    largest = max(graphs, key=lambda s: graphs[s].num_nodes)
    fresh = NavGraph(graphs[largest].connectivity)
    t0 = time.perf_counter()
    fresh.distance_matrix()
    all_pairs_s = time.perf_counter() - t0

    # Random shortest_path queries over all scans, after warming each scan's cache.
    rng = random.Random(args.seed)
    names = list(graphs)
    for graph in graphs.values():
        graph.distance_matrix()
    queries = []
    while len(queries) < args.queries:
        graph = graphs[rng.choice(names)]
        a, b = rng.choice(graph.nodes), rng.choice(graph.nodes)
        if graph.distance(a, b) < float("inf"):
            queries.append((graph, a, b))
    t0 = time.perf_counter()
    hops = sum(len(graph.shortest_path(a, b)) for graph, a, b in queries)
    query_s = time.perf_counter() - t0

    result = {
        "scans": len(graphs),
        "viewpoints": sum(len(g.ids) for g in graphs.values()),
        "nodes": sum(g.num_nodes for g in graphs.values()),
        "edges": sum(g.num_edges for g in graphs.values()),
        "load_total_s": round(load_s, 4),
        "load_mean_per_graph_ms": round(1000 * load_s / len(graphs), 3),
        "largest_scan": largest,
        "largest_scan_nodes": fresh.num_nodes,
        "all_pairs_largest_ms": round(1000 * all_pairs_s, 3),
        "shortest_path_queries": len(queries),
        "shortest_path_queries_per_s": round(len(queries) / query_s),
        "shortest_path_mean_hops": round(hops / len(queries), 3),
        "python": platform.python_version(),
        "machine": platform.machine(),
    }
    print(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
