"""Procedural scenes: scan build time (first / cached), model step time, and render fps of the
home look against the plain look it replaced, with people, in one run.

"plain" is the look procedural houses had before materials and furniture meshes: the same
house's boxes, one flat colour per material (``boxes_to_parts``), written to a scan folder
beside the real one; "home" is the scan as built now. Both worlds hold the same people; each
frame poses them at its time, moves the camera (viewpoints of the house, looking at a person)
and renders RGB-D (+ the segmentation pass for "home+labels"). Methods run frame by frame in
turn so other load on the machine slows them alike; fps is 1 / median frame time.

Prints one JSON object. Run: ``python benchmarks/bench_scene.py [--seeds 0 1 2] [--frames 60]``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import tempfile
import time
from pathlib import Path

import mujoco
import numpy as np
from common import machine, median_seconds


def _plain_copy(scan, folder: Path) -> Path:
    """The scan folder with the flat box mesh of the plain look and no part labels."""
    from havln_mj.scene.mesh import boxes_to_parts, write_glb

    shutil.copytree(scan.folder, folder)
    (folder / "semantics.json").unlink()
    write_glb(boxes_to_parts(scan.boxes), folder / "mesh.glb")
    return folder


def _views(scan, crowd, n: int) -> list[tuple[np.ndarray, float, float, float]]:
    """(camera position, heading, elevation, time): viewpoints 1.5-5 m from a person, facing
    them."""
    from havln_mj.frames import heading_to

    graph, out, k = scan.graph, [], 0
    while len(out) < n:
        t = 0.25 * k
        states = crowd.states(t)
        person = states[k % len(states)].position + np.array([0.0, 0.0, 0.9])
        near = [
            v for v in graph.nodes if 1.5 < np.linalg.norm(graph.position(v)[:2] - person[:2]) < 5
        ]
        vp = near[k % len(near)] if near else graph.nodes[k % graph.num_nodes]
        p = graph.position(vp)
        el = math.atan2(person[2] - p[2], max(np.linalg.norm(person[:2] - p[:2]), 0.1))
        out.append((p, heading_to(p, person), el, t))
        k += 1
    return out


def _render_fps(scan_home, frames: int, sizes, people_style: str) -> dict:
    from havln_mj import groups
    from havln_mj.humans.mujoco_people import PeopleWriter
    from havln_mj.humans.population import populate
    from havln_mj.render.camera import Camera
    from havln_mj.render.labels import render_labels
    from havln_mj.robot.point_body import CAMERA, PointBody
    from havln_mj.scene.scan import read_scan_folder
    from havln_mj.sim.world import WorldOptions, build_world

    crowd = populate(scan_home, np.random.default_rng(0), count=4)
    tmp = Path(tempfile.mkdtemp(prefix="havln_plain_"))
    scans = {"plain": read_scan_folder(_plain_copy(scan_home, tmp / "plain")), "home": scan_home}
    views = _views(scan_home, crowd, frames)
    result = {"people": len(crowd), "people_style": people_style, "frames": frames}
    for width, height in sizes:
        worlds = {}
        for name, scan in scans.items():
            options = WorldOptions(people_style=people_style)
            model = build_world(scan, options, people=crowd.shapes).model
            data = mujoco.MjData(model)
            cam = Camera(model, CAMERA, width, height, geom_groups=groups.CAMERA_GROUPS)
            worlds[name] = (model, data, PeopleWriter(model, len(crowd)), cam)

        def frame(name: str, view, labels: bool = False, worlds=worlds) -> None:
            model, data, writer, cam = worlds[name]
            pos, heading, elevation, t = view
            writer.write(data, *crowd.pose(t))
            PointBody(pos, heading, elevation).write(model, data)
            cam.render(data)
            if labels:
                render_labels(model, data, cam)

        methods = {
            "plain": lambda v: frame("plain", v),
            "home": lambda v: frame("home", v),
            "home+labels": lambda v: frame("home", v, labels=True),
        }
        times: dict[str, list[float]] = {m: [] for m in methods}
        for view in views[:3]:
            for run in methods.values():
                run(view)  # warm up
        for view in views:
            for name, run in methods.items():
                t0 = time.perf_counter()
                run(view)
                times[name].append(time.perf_counter() - t0)
        fps = {m: round(1.0 / float(np.median(ts)), 1) for m, ts in times.items()}
        fps["home_over_plain"] = round(fps["home"] / fps["plain"], 2)
        result[f"rgbd_{width}x{height}"] = fps
        for *_, cam in worlds.values():
            cam.close()
    shutil.rmtree(tmp, ignore_errors=True)
    return result


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--people-style", default="pieces", help="pieces | skinned | capsules")
    args = ap.parse_args()
    os.environ["HAVLN_CACHE"] = tempfile.mkdtemp(prefix="havln_bench_")  # really cold
    os.environ.setdefault("MUJOCO_GL", "egl")

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
                "ngeom": world.model.ngeom,
                "mesh_faces": world.model.nmeshface,
                "textures": world.model.ntex,
                "scan_folder_mb": round(
                    sum(f.stat().st_size for f in scan.folder.iterdir()) / 1e6, 2
                ),
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
    render = _render_fps(scan, args.frames, ((640, 480), (128, 128)), args.people_style)
    print(
        json.dumps(
            {
                "machine": machine(),
                "scan_build": builds,
                "scan_build_first_s_max": max(b["first_s"] for b in builds),
                "scan_build_cached_s_max": max(b["cached_s"] for b in builds),
                "model_step_us": round(step_us, 2),
                "render_scene": scan.scene_id,
                "render": render,
                "render_note": "per frame: pose the people at t, move the camera (mj_kinematics), "
                "one RGB-D render (+ one segmentation pass for home+labels)",
            },
            indent=1,
        )
    )


if __name__ == "__main__":
    main()
