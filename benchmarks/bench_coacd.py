"""CoACD building decomposition: cold time, cached reload time, hull count, and fit.

Usage::

    python benchmarks/bench_coacd.py                      # synthetic 4-room house, all settings
    python benchmarks/bench_coacd.py --config fast        # only the fast setting
    python benchmarks/bench_coacd.py --mesh house.obj     # a mesh file instead of the synthetic one

Prints one JSON object. Every run uses a fresh temporary HAVLN_CACHE, so "cold_s" is a real
CoACD run and "cached_s" the reload of the entry it wrote. Fit is measured on random points in
the mesh's bounding box: "solid_covered" is the fraction of points inside the input that some
hull covers, "free_covered" the fraction of free-space points that hulls wrongly fill (remesh
inflation, space between furniture and walls); both need a solid-membership test (known boxes
for the synthetic house, ``contains`` for a watertight file, else null). "doors_blocked" counts
the synthetic house's 20 door-gap sample points (5 doors x 4 heights) inside some hull.
"inflation_m" is how far the hulls' bounding box sticks out of the input's.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import os
import platform
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import trimesh
from scipy.spatial import ConvexHull

from havln_mj.scene.collision import CoacdParams, Hull, decompose, hull_cache_path

CONFIGS = {
    # havln_mj's building defaults: threshold 0.1 m (real metric), CoACD's search defaults.
    "default": CoacdParams(),
    # A shorter MCTS search: about a third of the time, nearly the same fit.
    "fast": CoacdParams(mcts_iterations=40, mcts_max_depth=2, mcts_nodes=10),
    # CoACD's own defaults (normalised threshold 0.05), for reference.
    "coacd_defaults": CoacdParams(threshold=0.05, real_metric=False),
}

Box = tuple[np.ndarray, np.ndarray]

# Centres of the synthetic house's door gaps (x, y), sampled at 4 heights each.
DOORS = ((4.5, 0.05), (5.0, 2.0), (5.0, 6.0), (2.5, 4.0), (7.5, 4.0))
DOOR_POINTS = np.array([(x, y, z) for x, y in DOORS for z in (0.5, 1.0, 1.5, 2.0)])


def synthetic_house(seed: int = 0) -> tuple[trimesh.Trimesh, list[Box]]:
    """A 10 x 8 m, 4-room house: floor slab, 2.5 m walls 0.1 m thick with door gaps, furniture.

    Returns the triangle soup (boxes concatenated, not unioned) and the boxes themselves.
    """
    h, t = 2.5, 0.1
    boxes = [
        ((0, 0, -t), (10, 8, 0)),  # floor slab
        ((0, 0, 0), (4, t, h)),  # front wall, entrance gap 4..5
        ((5, 0, 0), (10, t, h)),
        ((0, 8 - t, 0), (10, 8, h)),  # back wall
        ((0, 0, 0), (t, 8, h)),  # side walls
        ((10 - t, 0, 0), (10, 8, h)),
        ((5 - t / 2, 0, 0), (5 + t / 2, 1.5, h)),  # wall x=5, doors at y 1.5..2.5, 5.5..6.5
        ((5 - t / 2, 2.5, 0), (5 + t / 2, 5.5, h)),
        ((5 - t / 2, 6.5, 0), (5 + t / 2, 8, h)),
        ((0, 4 - t / 2, 0), (2, 4 + t / 2, h)),  # wall y=4, doors at x 2..3, 7..8
        ((3, 4 - t / 2, 0), (7, 4 + t / 2, h)),
        ((8, 4 - t / 2, 0), (10, 4 + t / 2, h)),
    ]
    rng = np.random.default_rng(seed)
    for cx, cy in ((2.5, 2.0), (7.5, 2.0), (2.5, 6.0), (7.5, 6.0)):  # 3 furniture boxes per room
        for _ in range(3):
            sx, sy, sz = rng.uniform(0.4, 1.6), rng.uniform(0.4, 1.0), rng.uniform(0.4, 1.0)
            x, y = cx + rng.uniform(-1.5, 1.5 - sx), cy + rng.uniform(-1.5, 1.5 - sy)
            boxes.append(((x, y, 0), (x + sx, y + sy, sz)))
    boxes_np = [(np.array(lo, float), np.array(hi, float)) for lo, hi in boxes]
    parts = []
    for lo, hi in boxes_np:
        b = trimesh.creation.box(extents=hi - lo)
        b.apply_translation((lo + hi) / 2)
        parts.append(b)
    return trimesh.util.concatenate(parts), boxes_np


def inside_hulls(hulls: list[Hull], points: np.ndarray) -> np.ndarray:
    hit = np.zeros(len(points), dtype=bool)
    for h in hulls:
        eq = ConvexHull(h.vertices).equations
        hit |= (points @ eq[:, :3].T + eq[:, 3] <= 1e-9).all(axis=1)
    return hit


def fit(
    mesh: trimesh.Trimesh,
    hulls: list[Hull],
    solid: Callable[[np.ndarray], np.ndarray] | None,
    doors: np.ndarray | None,
) -> dict:
    lo, hi = mesh.bounds
    hv = np.concatenate([h.vertices for h in hulls])
    out = {
        "inflation_m": round(float(max((lo - hv.min(0)).max(), (hv.max(0) - hi).max())), 4),
        "solid_covered": None,
        "free_covered": None,
        "doors_blocked": None if doors is None else int(inside_hulls(hulls, doors).sum()),
    }
    if solid is not None:
        pts = np.random.default_rng(0).uniform(lo, hi, size=(50_000, 3))
        is_solid, covered = solid(pts), inside_hulls(hulls, pts)
        out["solid_covered"] = round(float(covered[is_solid].mean()), 4)
        out["free_covered"] = round(float(covered[~is_solid].mean()), 4)
    return out


def bench(
    mesh: trimesh.Trimesh,
    name: str,
    params: CoacdParams,
    solid: Callable[[np.ndarray], np.ndarray] | None,
    doors: np.ndarray | None,
) -> dict:
    old = os.environ.get("HAVLN_CACHE")
    with tempfile.TemporaryDirectory(prefix="bench_coacd_") as tmp:
        os.environ["HAVLN_CACHE"] = tmp  # fresh cache: the first call is really cold
        try:
            t0 = time.perf_counter()
            hulls = decompose(mesh, params)
            cold = time.perf_counter() - t0
            entry_bytes = hull_cache_path(mesh, params).stat().st_size
            t0 = time.perf_counter()
            cached = decompose(mesh, params)
            warm = time.perf_counter() - t0
        finally:
            if old is None:
                os.environ.pop("HAVLN_CACHE", None)
            else:
                os.environ["HAVLN_CACHE"] = old
    assert len(cached) == len(hulls)
    return {
        "config": name,
        "params": json.loads(params.to_json()),
        "cold_s": round(cold, 2),
        "cached_s": round(warm, 4),
        "hulls": len(hulls),
        "hull_vertices": int(sum(len(h.vertices) for h in hulls)),
        "cache_entry_bytes": entry_bytes,
        **fit(mesh, hulls, solid, doors),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mesh", type=Path, help="decompose this mesh file instead")
    parser.add_argument(
        "--scene",
        help="decompose a scene's exported mesh as the world builder does (e.g. proc-0): the "
        "collision band of each level; 'doors_blocked' then counts viewpoints (at 0.3/1.0 m) "
        "that hulls cover",
    )
    parser.add_argument(
        "--config", choices=[*CONFIGS, "all"], default="all", help="parameter set (default: all)"
    )
    args = parser.parse_args(argv)

    if args.scene is not None:
        from havln_mj.scene.scan import load_scan
        from havln_mj.sim.world import WorldOptions, collision_chunks

        scan = load_scan(args.scene)
        opts = WorldOptions()
        mesh = trimesh.util.concatenate(
            collision_chunks(scan, opts.collision_band, opts.collision_chunk)
        )
        source = f"{scan.description}: exported mesh, collision band"
        solid = None
        if scan.boxes is not None:
            walls = scan.boxes.of_kind("wall", "furniture", "floor")

            def solid(p: np.ndarray) -> np.ndarray:
                return ((p[:, None] > walls.lo[None]) & (p[:, None] < walls.hi[None])).all(2).any(1)

        g = scan.graph
        doors = np.array(
            [
                g.position(v) - [0, 0, g.connectivity.heights[g.index(v)] - z]
                for v in g.nodes
                for z in (0.3, 1.0)
            ]
        )
    elif args.mesh is not None:
        if not args.mesh.is_file():
            parser.error(f"--mesh {args.mesh}: no such file")
        mesh = trimesh.load(args.mesh, force="mesh")
        source = str(args.mesh)
        solid = mesh.contains if mesh.is_watertight else None
        doors = None
    else:
        mesh, boxes = synthetic_house()
        doors = DOOR_POINTS
        source = "synthetic 10x8 m 4-room house, 2.5 m walls 0.1 m thick, 12 furniture boxes"

        def solid(p: np.ndarray) -> np.ndarray:
            return np.any([((p > lo) & (p < hi)).all(axis=1) for lo, hi in boxes], axis=0)

    names = list(CONFIGS) if args.config == "all" else [args.config]
    report = {
        "mesh": {
            "source": source,
            "vertices": len(mesh.vertices),
            "faces": len(mesh.faces),
            "bounds": np.round(mesh.bounds, 3).tolist(),
        },
        "coacd_version": importlib.metadata.version("coacd"),
        "cpus": os.cpu_count(),
        "python": platform.python_version(),
        "runs": [bench(mesh, n, CONFIGS[n], solid, doors) for n in names],
    }
    json.dump(report, sys.stdout, indent=2)
    print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
