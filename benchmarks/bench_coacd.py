"""CoACD building decomposition: cold time, cached reload time, hull count, and fit.

Usage::

    python benchmarks/bench_coacd.py                      # synthetic 4-room house, both settings
    python benchmarks/bench_coacd.py --config fast        # only the fast setting
    python benchmarks/bench_coacd.py --mesh house.obj     # a mesh file instead of the synthetic one

Prints one JSON object. Every run uses a fresh temporary HAVLN_CACHE, so "cold_s" is a real
CoACD run and "cached_s" the reload of the entry it wrote. Fit is measured on random points in
the mesh's bounding box: "solid_covered" is the fraction of points inside the input that some
hull covers, "free_covered" the fraction of free-space points that hulls wrongly fill (remesh
inflation, filled door gaps); both need a solid-membership test (known boxes for the synthetic
house, ``contains`` for a watertight file, else null). "inflation_m" is how far the hulls'
bounding box sticks out of the input's.
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
    # CoACD's published defaults (threshold 0.05, remesh 50, MCTS 100 x depth 3 x 20 nodes).
    "default": CoacdParams(),
    # Coarser remesh and a shorter search: about 2.5x faster, ~4 cm more wall inflation.
    "fast": CoacdParams(threshold=0.1, preprocess_resolution=30, mcts_iterations=60),
}

Box = tuple[np.ndarray, np.ndarray]


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
    mesh: trimesh.Trimesh, hulls: list[Hull], solid: Callable[[np.ndarray], np.ndarray] | None
) -> dict:
    lo, hi = mesh.bounds
    hv = np.concatenate([h.vertices for h in hulls])
    out = {
        "inflation_m": round(float(max((lo - hv.min(0)).max(), (hv.max(0) - hi).max())), 4),
        "solid_covered": None,
        "free_covered": None,
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
        **fit(mesh, hulls, solid),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mesh", type=Path, help="decompose this mesh file instead")
    parser.add_argument(
        "--config", choices=[*CONFIGS, "all"], default="all", help="parameter set (default: all)"
    )
    args = parser.parse_args(argv)

    if args.mesh is not None:
        mesh = trimesh.load(args.mesh, force="mesh")
        source = str(args.mesh)
        solid = mesh.contains if mesh.is_watertight else None
    else:
        mesh, boxes = synthetic_house()
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
        "runs": [bench(mesh, n, CONFIGS[n], solid) for n in names],
    }
    json.dump(report, sys.stdout, indent=2)
    print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
