"""People: pose updates per second, MjSpec build time, and render fps with people in view.

* **Pose updates/s** for 10 people of the built-in catalog (placed in ``proc-0`` by HA3D's
  rule, plus more people if the house has fewer): sampling every clip at time t, forward
  kinematics, writing the 240 mocap poses and ``mj_kinematics``. Median over repeats.
* **Build**: ``add_people`` for 10 bodies into a ``MjSpec`` plus ``compile``, in an empty
  world and in ``proc-0``'s world.
* **Render fps** at 640×480 (RGB-D, one pass) and 128×128 from a camera with 4 people in
  view, standing 2–4 m in front of it, people moving with time.

Prints one JSON object. Run: ``python benchmarks/bench_humans.py [--seconds S]``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco
import numpy as np
from common import machine, median_seconds

from havln_mj.humans.body import random_body
from havln_mj.humans.catalog import load_catalog, make_clip
from havln_mj.humans.crowd import Crowd, Person
from havln_mj.humans.mujoco_people import PeopleWriter, add_people
from havln_mj.humans.population import populate
from havln_mj.render.camera import Camera
from havln_mj.robot.point_body import CAMERA, PointBody
from havln_mj.scene.scan import load_scan
from havln_mj.sim.world import WorldOptions, build_world


def _crowd(scan, n: int, rng: np.random.Generator) -> Crowd:
    people = list(populate(scan, rng).people)
    catalog = load_catalog()
    standing = [
        a
        for code in catalog.regions()
        for a in catalog.activities(code)
        if not (a.needs_seat or a.needs_path)
    ]
    while len(people) < n:  # top up with standing people around the first viewpoint
        shape = random_body(rng)
        activity = standing[int(rng.integers(len(standing)))]
        clip = make_clip(activity, shape.height, rng)
        anchor = scan.graph.position(scan.graph.nodes[len(people)]) * [1, 1, 0]
        people.append(Person(shape, clip, anchor, 0.0, activity.id, activity.text))
    return Crowd(people[:n])


def _pose_rate(scan, repeat: int) -> dict:
    crowd = _crowd(scan, 10, np.random.default_rng(0))
    world = build_world(scan, WorldOptions(collision="none"), crowd.shapes)
    data = mujoco.MjData(world.model)
    writer = PeopleWriter(world.model, len(crowd))
    t = [0.0]

    def update() -> None:
        t[0] += 1 / 30
        writer.write(data, *crowd.pose(t[0]))
        mujoco.mj_kinematics(world.model, data)

    for _ in range(50):
        update()
    s = median_seconds(update, repeat)
    pose_only = median_seconds(lambda: crowd.pose(1.234), repeat)
    positions = median_seconds(lambda: crowd.positions(np.linspace(0, 2, 33)), repeat)
    return {
        "people": len(crowd),
        "updates_per_s": round(1 / s),
        "pose_only_per_s": round(1 / pose_only),
        "collision_query_33_samples_per_s": round(1 / positions),
    }


def _build_times(scan, repeat: int) -> dict:
    shapes = [random_body(np.random.default_rng(k)) for k in range(10)]

    def empty() -> None:
        spec = mujoco.MjSpec()
        add_people(spec, shapes)
        spec.compile()

    def in_house() -> None:
        build_world(scan, WorldOptions(collision="none"), shapes)

    bare = median_seconds(lambda: build_world(scan, WorldOptions(collision="none")), repeat)
    return {
        "people": 10,
        "empty_world_ms": round(1e3 * median_seconds(empty, repeat), 1),
        "proc0_world_ms": round(1e3 * median_seconds(in_house, repeat), 1),
        "proc0_world_without_people_ms": round(1e3 * bare, 1),
    }


def _render(scan, seconds: float) -> list[dict]:
    rng = np.random.default_rng(1)
    graph = scan.graph
    vp = max(graph.nodes, key=lambda v: graph.degree(v))
    eye = graph.position(vp)
    catalog = load_catalog()
    talkers = [a for a in catalog.activities("l") if not (a.needs_seat or a.needs_path)]
    people = []
    for k in range(4):  # a row of people 2–4 m ahead of the camera (heading 0 faces +y)
        shape = random_body(rng)
        clip = make_clip(talkers[k % len(talkers)], shape.height, rng)
        anchor = np.array([eye[0] - 0.9 + 0.6 * k, eye[1] + 2.0 + 0.6 * k, graph.floor_z(vp)])
        people.append(Person(shape, clip, anchor, math.pi, "bench"))
    crowd = Crowd(people)
    world = build_world(scan, WorldOptions(collision="none"), crowd.shapes)
    model, data = world.model, mujoco.MjData(world.model)
    writer = PeopleWriter(model, 4)
    body = PointBody(eye, heading=0.0)
    rows = []
    for width, height in ((640, 480), (128, 128)):
        with Camera(model, CAMERA, width, height, 60.0) as cam:
            frames, t0, t = 0, time.perf_counter(), 0.0
            while time.perf_counter() - t0 < seconds:
                t += 1 / 30
                writer.write(data, *crowd.pose(t))
                body.write(model, data)
                frame = cam.render(data)
                frames += 1
            fps = frames / (time.perf_counter() - t0)
            ids = cam.render_geom_ids(data)
            human_pixels = float(np.isin(ids, np.flatnonzero(model.geom_group == 2)).mean())
        rows.append(
            {
                "resolution": f"{width}x{height}",
                "people_in_view": 4,
                "rgbd_fps": round(fps, 1),
                "human_pixel_fraction": round(human_pixels, 3),
                "depth_valid": bool((frame.depth > 0).mean() > 0.9),
            }
        )
    return rows


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=5.0)
    ap.add_argument("--repeat", type=int, default=200)
    args = ap.parse_args()
    scan = load_scan("proc-0")
    result = {
        "machine": machine(),
        "pose_updates": _pose_rate(scan, args.repeat),
        "build": _build_times(scan, max(3, args.repeat // 40)),
        "render": _render(scan, args.seconds),
    }
    print(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
