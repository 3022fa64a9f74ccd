"""Graph proxies of all real navigation graphs: build time, geometry, walkability, physics.

Prints one JSON object: a row per scan (build time, floor/stair/wall box counts, layers,
unwalkable edges) and the physics step rate of a GO1-sized free body (0.65 × 0.28 × 0.3 m,
12 kg, 2 ms steps) standing in the proxy with the most boxes.

Run: ``python benchmarks/bench_proxies.py [--data ../shared/data] [--scans ID ...]``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import mujoco
import numpy as np
from common import machine


def main() -> int:
    default = Path(
        os.environ.get("HAVLN_SHARED_DATA", Path(__file__).resolve().parents[2] / "shared" / "data")
    )
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", type=Path, default=default)
    ap.add_argument("--scans", nargs="*", default=None)
    ap.add_argument("--steps", type=int, default=5000)
    args = ap.parse_args()
    conn = args.data / "mp3d_connectivity"
    if not conn.is_dir():
        print(
            f"connectivity graphs not found at {conn} (set HAVLN_SHARED_DATA or --data)",
            file=sys.stderr,
        )
        return 1

    from havln_mj.scene.navgraph import NavGraph
    from havln_mj.scene.proxy.build import build_proxy

    scans = args.scans or (conn / "scans.txt").read_text().split()
    rows, largest = [], None
    for scan in scans:
        graph = NavGraph.from_file(conn / f"{scan}_connectivity.json")
        t = time.perf_counter()
        proxy = build_proxy(graph)
        seconds = time.perf_counter() - t
        mats = proxy.boxes.material
        rows.append(
            {
                "scan": scan,
                "viewpoints": graph.num_nodes,
                "edges": graph.num_edges,
                "build_s": round(seconds, 3),
                "boxes": len(proxy.boxes),
                "floor_boxes": mats.count("floor"),
                "stair_boxes": mats.count("stairs"),
                "wall_boxes": mats.count("wall"),
                "layers": len(proxy.free),
                "unwalkable_edges": len(proxy.unwalkable),
            }
        )
        if largest is None or len(proxy.boxes) > largest[2]:
            largest = (scan, graph, len(proxy.boxes))
    step_rate = _physics(conn, largest[0], args.steps)
    total_edges = sum(r["edges"] for r in rows)
    bad = sum(r["unwalkable_edges"] for r in rows)
    print(
        json.dumps(
            {
                "machine": machine(),
                "scans": len(rows),
                "edges": total_edges,
                "unwalkable_edges": bad,
                "unwalkable_fraction": round(bad / total_edges, 4),
                "scans_with_unwalkable": sum(r["unwalkable_edges"] > 0 for r in rows),
                "build_s": {
                    "mean": round(float(np.mean([r["build_s"] for r in rows])), 3),
                    "max": max(r["build_s"] for r in rows),
                    "total": round(sum(r["build_s"] for r in rows), 1),
                },
                "boxes": {
                    "mean": round(float(np.mean([r["boxes"] for r in rows]))),
                    "max": max(r["boxes"] for r in rows),
                },
                "physics": step_rate,
                "rows": rows,
            },
            indent=1,
        )
    )
    return 0


def _physics(conn: Path, scan_id: str, steps: int) -> dict:
    """Steps/s of a GO1-sized free box dropped onto the proxy floor at a viewpoint."""
    import tempfile

    os.environ.setdefault("HAVLN_CACHE", tempfile.mkdtemp(prefix="havln_bench_"))
    from havln_mj.scene.scan import load_scan
    from havln_mj.sim.world import world_spec

    scan = load_scan(scan_id, connectivity_dir=conn)
    spec, _, n_collision = world_spec(scan)
    vp = scan.graph.nodes[len(scan.graph.nodes) // 2]
    x, y, _ = scan.graph.position(vp)
    body = spec.worldbody.add_body(name="go1_proxy", pos=(x, y, scan.graph.floor_z(vp) + 0.2))
    body.add_freejoint()
    body.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX, size=(0.325, 0.14, 0.15), mass=12.0, name="go1_trunk"
    )
    spec.option.timestep = 0.002
    model = spec.compile()
    data = mujoco.MjData(model)
    for _ in range(500):  # settle on the floor
        mujoco.mj_step(model, data)
    t = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(model, data)
    seconds = time.perf_counter() - t
    return {
        "scan": scan_id,
        "collision_geoms": n_collision,
        "steps_per_s": round(steps / seconds),
        "x_real_time": round(steps * model.opt.timestep / seconds, 1),
        "body_height_above_floor_m": round(float(data.qpos[2] - scan.graph.floor_z(vp)), 3),
        "contacts": int(data.ncon),
    }


if __name__ == "__main__":
    sys.exit(main())
