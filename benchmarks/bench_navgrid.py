"""Benchmark: per-floor occupancy grids (build time, size) and geodesic queries on them.

Usage: python benchmarks/bench_navgrid.py [--seeds 0 1 2 3 4] [--queries N] [--boxes N]

For each procedural house and for a synthetic world of many boxes (a third of them rotated,
plus a few convex mesh hulls), prints in one JSON object: the time to rasterise the grid,
its size, the first distance field (which also builds the free-cell graph), a further
distance field from another source, and the rate of ``distance(p, goal)`` queries against a
few goals whose fields stay cached.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
import tempfile
import time

import mujoco
import numpy as np
from common import machine, median_seconds
from scipy import ndimage


def synthetic_world(n_boxes: int, seed: int = 0, size: float = 30.0) -> mujoco.MjModel:
    """A size x size m floor with ``n_boxes`` random boxes and 20 random convex hulls."""
    from havln_mj import groups

    rng = np.random.default_rng(seed)
    spec = mujoco.MjSpec()
    box = mujoco.mjtGeom.mjGEOM_BOX
    col = groups.COLLISION
    spec.worldbody.add_geom(type=box, pos=(0, 0, -0.05), size=(size / 2, size / 2, 0.05), group=col)
    for k in range(n_boxes):
        half = rng.uniform(0.05, 0.4, 3)
        pos = (*rng.uniform(-size / 2, size / 2, 2), half[2] + rng.uniform(0.0, 1.0))
        yaw = rng.uniform(0, np.pi) if k % 3 == 0 else 0.0
        quat = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
        spec.worldbody.add_geom(type=box, pos=pos, size=half, quat=quat, group=col)
    for k in range(20):
        verts = rng.normal(size=(40, 3)) * 0.3
        spec.add_mesh(name=f"hull{k}", uservert=verts.astype(np.float32).ravel())
        spec.worldbody.add_geom(
            type=mujoco.mjtGeom.mjGEOM_MESH,
            meshname=f"hull{k}",
            pos=(*rng.uniform(-size / 2, size / 2, 2), 0.3),
            group=col,
        )
    return spec.compile()


def bench_grid(model: mujoco.MjModel, floor: float, queries: int, seed: int) -> dict:
    from havln_mj import groups
    from havln_mj.nav import GridSpec, NavGrid

    spec = GridSpec()
    build_s = median_seconds(lambda: NavGrid.from_model(model, floor, spec), 3)
    grid = NavGrid.from_model(model, floor, spec)
    rng = np.random.default_rng(seed)
    # Sources and query points in the largest 8-connected part of the free cells.
    labels, _ = ndimage.label(grid.free, structure=np.ones((3, 3)))
    largest = np.argmax(np.bincount(labels.ravel())[1:]) + 1
    part = np.argwhere(labels == largest)
    t = time.perf_counter()
    field0 = grid.distances_from(grid.to_world(part[len(part) // 2]))
    first_field_s = time.perf_counter() - t
    reach = np.argwhere(np.isfinite(field0))
    pts = grid.to_world(reach[rng.integers(0, len(reach), queries)])
    goals = grid.to_world(reach[rng.integers(0, len(reach), 4)])
    fresh = [NavGrid(grid.occupied, grid.origin, floor, spec) for _ in range(3)]
    for g in fresh:
        g.distances_from(goals[0])  # builds the graph
    field_s = statistics.median(
        median_seconds(lambda g=g, k=k: g.distances_from(goals[k]), 1)
        for g in fresh
        for k in (1, 2, 3)
    )
    for goal in goals:
        grid.distances_from(goal)  # warm the cache
    t = time.perf_counter()
    dist = [grid.distance(p, goals[k % 4]) for k, p in enumerate(pts)]
    query_s = time.perf_counter() - t
    straight = sum(grid.segment_is_free(p, goals[k % 4]) for k, p in enumerate(pts[:500]))
    t = time.perf_counter()
    cells = grid.to_cells(pts)
    lookup = grid.distances_from(goals[0])[cells[:, 0], cells[:, 1]]
    lookup_s = time.perf_counter() - t
    h, w = grid.shape
    return {
        "collision_geoms": int(np.count_nonzero(model.geom_group == groups.COLLISION)),
        "cells": [h, w],
        "free_fraction": round(float(grid.free.mean()), 4),
        "grid_build_ms": round(1000 * build_s, 2),
        "first_field_ms_incl_graph": round(1000 * first_field_s, 2),
        "field_ms": round(1000 * field_s, 2),
        "cached_queries_per_s": round(len(pts) / query_s),
        "field_lookup_points_per_s": round(len(pts) / lookup_s),
        "mean_query_distance_m": round(float(np.mean(dist)), 3),
        "unreachable_lookups": int(np.count_nonzero(np.isinf(lookup))),
        "straight_line_fraction": round(straight / min(500, len(pts)), 3),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--queries", type=int, default=2000, help="distance() calls per world")
    parser.add_argument("--boxes", type=int, default=3000, help="boxes of the synthetic world")
    args = parser.parse_args(argv)
    os.environ.setdefault("HAVLN_CACHE", tempfile.mkdtemp(prefix="havln_bench_"))

    from havln_mj.scene.scan import floor_heights, load_scan
    from havln_mj.sim.world import build_world

    result: dict = {"spec": {"resolution": 0.05, "robot_radius": 0.25, "z_band": [0.1, 0.6]}}
    houses = {}
    for seed in args.seeds:
        scan = load_scan(f"proc-{seed}")
        world = build_world(scan)
        houses[f"proc-{seed}"] = bench_grid(world.model, floor_heights(scan)[0], args.queries, seed)
    result["procedural"] = houses
    t = time.perf_counter()
    model = synthetic_world(args.boxes)
    compile_s = time.perf_counter() - t
    synth = bench_grid(model, 0.0, args.queries, 0)
    synth["model_compile_s"] = round(compile_s, 2)
    result[f"synthetic_{args.boxes}_boxes_30m"] = synth
    result["machine"] = machine()
    result["cpus"] = os.cpu_count()
    print(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
