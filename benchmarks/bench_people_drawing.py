"""Drawing people: RGB-D frame rate with 4 people in view, per drawing style, in one run.

Builds ``proc-0``'s world with :func:`havln_mj.sim.world.build_world`'s spec plus four
people standing and talking 2–4 m in front of the agent camera, and renders RGB-D through
:class:`havln_mj.render.camera.Camera` while time runs, for each style of
:class:`havln_mj.humans.drawing.PeopleDrawing`: ``capsules`` (the mannequins: the baseline),
``pieces`` (Anny bodies as rigid textured pieces: the default) and ``skinned`` (Anny bodies
skinned and re-uploaded every frame). Also times the pose step alone (crowd pose + writing
the model, without rendering), the world build, and the catalog's size on disk.

Prints one JSON object. Run: ``python benchmarks/bench_people_drawing.py [--seconds S]
[--save DIR]`` (``--save`` writes one frame per style as PNG).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco
import numpy as np
from common import machine, median_seconds

from havln_mj.humans.catalog import load_catalog, make_clip
from havln_mj.humans.crowd import Crowd, Person
from havln_mj.humans.drawing import PeopleDrawing
from havln_mj.humans.population import anny_shape
from havln_mj.paths import asset_path
from havln_mj.render.camera import Camera
from havln_mj.robot.point_body import CAMERA, PointBody
from havln_mj.scene.scan import load_scan
from havln_mj.sim.world import WorldOptions, world_spec

STYLES = ("capsules", "pieces", "skinned")


def four_people(scan, rng: np.random.Generator) -> tuple[Crowd, np.ndarray]:
    """Four talking people 2–4 m ahead of the best-connected viewpoint, and that viewpoint."""
    graph = scan.graph
    vp = max(graph.nodes, key=lambda v: graph.degree(v))
    eye = graph.position(vp)
    talkers = [a for a in load_catalog().activities("l") if not (a.needs_seat or a.needs_path)]
    people = []
    for k in range(4):  # heading 0 faces +y; they face the camera
        shape = anny_shape(rng)
        clip = make_clip(talkers[k % len(talkers)], shape.height, rng)
        anchor = np.array([eye[0] - 0.9 + 0.6 * k, eye[1] + 2.0 + 0.6 * k, graph.floor_z(vp)])
        people.append(Person(shape, clip, anchor, math.pi, "bench"))
    return Crowd(people), eye


def _style(scan, crowd: Crowd, eye: np.ndarray, style: str, seconds: float, save: Path | None):
    t0 = time.perf_counter()
    spec, _, _ = world_spec(scan, WorldOptions(collision="none"))
    drawing = PeopleDrawing.from_crowd(crowd, style)
    drawing.add_to(spec)
    model = spec.compile()
    build_s = time.perf_counter() - t0
    data = mujoco.MjData(model)
    poser = drawing.poser(model)
    body = PointBody(eye, heading=0.0)
    row = {"style": style, "build_s": round(build_s, 2), "geoms": int(model.ngeom)}
    with Camera(model, CAMERA, 640, 480, 60.0) as cam:
        frames, start, t, uploads = 0, time.perf_counter(), 0.0, 0
        while time.perf_counter() - start < seconds:
            t += 1 / 30
            for mesh in poser.pose(data, t):
                cam.upload_mesh(mesh)
                uploads += 1
            body.write(model, data)
            frame = cam.render(data)
            frames += 1
        row["rgbd_fps_640x480"] = round(frames / (time.perf_counter() - start), 1)
        row["mesh_uploads_per_frame"] = uploads // max(frames, 1)
        ids = cam.render_geom_ids(data)
        human = np.isin(ids, np.flatnonzero(model.geom_group == 2))
        row["human_pixel_fraction"] = round(float(human.mean()), 3)
        row["depth_on_people_m"] = round(float(np.median(frame.depth[human])), 2)
    row["pose_ms"] = round(1e3 * median_seconds(lambda: poser.pose(data, 1.234), 50), 3)
    if save is not None:
        import cv2

        save.mkdir(parents=True, exist_ok=True)
        cv2.imwrite(str(save / f"people_{style}.png"), frame.rgb[..., ::-1])
    return row


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=5.0)
    ap.add_argument("--save", type=Path, default=None)
    args = ap.parse_args()
    scan = load_scan("proc-0")
    crowd, eye = four_people(scan, np.random.default_rng(3))
    rows = [_style(scan, crowd, eye, s, args.seconds, args.save) for s in STYLES]
    base = rows[0]["rgbd_fps_640x480"]
    for row in rows:
        row["fps_vs_capsules"] = round(row["rgbd_fps_640x480"] / base, 2)
    folder = asset_path("humans", "anny")
    catalog_mb = sum(f.stat().st_size for f in folder.iterdir()) / 1e6
    result = {
        "machine": machine(),
        "scene": "proc-0",
        "people_in_view": len(crowd),
        "styles": rows,
        "catalog_mb": round(catalog_mb, 2),
    }
    print(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
