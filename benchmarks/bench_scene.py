"""Procedural scenes: scan build time (first / cached), model step time, render fps.

Prints one JSON object. Run: ``python benchmarks/bench_scene.py [--seeds 0 1 2]``.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time

import mujoco
import numpy as np
from common import machine, median_seconds


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    ap.add_argument("--frames", type=int, default=60)
    args = ap.parse_args()
    os.environ["HAVLN_CACHE"] = tempfile.mkdtemp(prefix="havln_bench_")  # really cold

    from havln_mj import groups
    from havln_mj.render.camera import Camera
    from havln_mj.robot.point_body import CAMERA, PointBody
    from havln_mj.scene.scan import load_scan
    from havln_mj.sim.world import build_world

    builds = []
    for seed in args.seeds:
        scene = f"proc-{seed}"
        t = time.perf_counter()
        scan = load_scan(scene)
        world = build_world(scan)
        first = time.perf_counter() - t
        cached = median_seconds(lambda s=scene: build_world(load_scan(s)), 5)
        builds.append(
            {
                "scene": scene,
                "area_m2": scan.meta["area_m2"],
                "viewpoints": scan.graph.num_nodes,
                "edges": scan.graph.num_edges,
                "ngeom": world.model.ngeom,
                "first_s": round(first, 3),
                "cached_s": round(cached, 4),
            }
        )

    scan = load_scan(f"proc-{args.seeds[0]}")
    model = build_world(scan).model
    data = mujoco.MjData(model)
    n_steps = 20000
    t = time.perf_counter()
    for _ in range(n_steps):
        mujoco.mj_step(model, data)
    step_us = (time.perf_counter() - t) / n_steps * 1e6

    graph = scan.graph
    poses = [(graph.position(v), h) for v in graph.nodes for h in (0.0, 1.6, 3.1, 4.7)]
    render = {}
    for w, h in ((640, 480), (128, 128)):
        with Camera(model, CAMERA, w, h, geom_groups=groups.CAMERA_GROUPS) as cam:
            res = {}
            for mode, kw in (("rgb", {"depth": False}), ("depth", {"rgb": False}), ("rgbd", {})):
                for k in range(5):  # warm up
                    PointBody(*poses[k % len(poses)]).write(model, data)
                    cam.render(data, **kw)
                t = time.perf_counter()
                for k in range(args.frames):
                    PointBody(*poses[k % len(poses)]).write(model, data)
                    cam.render(data, **kw)
                res[mode] = round(args.frames / (time.perf_counter() - t), 1)
            render[f"{w}x{h}"] = res
    print(
        json.dumps(
            {
                "machine": machine(),
                "scan_build": builds,
                "scan_build_first_s_max": max(b["first_s"] for b in builds),
                "scan_build_cached_s_max": max(b["cached_s"] for b in builds),
                "model_step_us": round(step_us, 2),
                "model_ngeom": model.ngeom,
                "render_fps": render,
                "render_scene": scan.scene_id,
                "render_note": "per frame: pose update (mj_kinematics) + one render",
            },
            indent=1,
        )
    )


if __name__ == "__main__":
    np.set_printoptions(precision=3)
    main()
