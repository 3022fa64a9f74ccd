"""Pictures of people for the docs: five people up close, and crowds from the agent camera.

* ``people_five.png``: five catalog people (different bodies and outfits), full body and
  face, standing and talking, drawn in the default style (rigid pieces).
* ``people_crowd.png``: the agent camera's view (640×480, shown at half size) toward
  people placed by HA3D's rule in procedural houses, one frame per room.

Run: ``python benchmarks/people_gallery.py [--out docs] [--style pieces]``.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import cv2
import mujoco
import numpy as np

from havln_mj.frames import heading_to
from havln_mj.humans.anny_data import load_anny_catalog
from havln_mj.humans.anny_mujoco import AnnyLook
from havln_mj.humans.anny_rig import fit
from havln_mj.humans.body import BodyShape
from havln_mj.humans.catalog import load_catalog, make_clip
from havln_mj.humans.crowd import Crowd, Person
from havln_mj.humans.drawing import PeopleDrawing
from havln_mj.humans.outfits import random_outfit
from havln_mj.humans.population import populate
from havln_mj.render.camera import Camera
from havln_mj.robot.point_body import CAMERA, PointBody
from havln_mj.scene.scan import load_scan
from havln_mj.sim.world import WorldOptions, world_spec

FIVE = ("woman-average", "man-elder", "girl-11", "man-heavy", "woman-elder-slim")


def _five_crowd(style: str) -> Crowd:
    catalog = load_anny_catalog()
    talk = load_catalog().get("living-room/guest-chat")
    rng = np.random.default_rng(7)
    people = []
    for k, body_id in enumerate(FIVE):
        rig = fit(catalog.get(body_id))
        outfit = random_outfit(rng, rig.body)
        shape = BodyShape(rig.clip_height, 1.0, look=AnnyLook(rig, outfit, k))
        clip = make_clip(talk, shape.height, rng)
        people.append(Person(shape, clip, np.array([1.2 * k, 0.0, 0.0]), math.pi, talk.id))
    return Crowd(people)


def five_people(style: str) -> np.ndarray:
    """Five people, each shown full length and by the face, side by side."""
    crowd = _five_crowd(style)
    spec = mujoco.MjSpec()
    spec.visual.headlight.ambient = (0.45, 0.45, 0.45)
    spec.visual.headlight.diffuse = (0.35, 0.35, 0.35)
    spec.worldbody.add_light(dir=(0.3, 0.6, -1.0), diffuse=(0.5, 0.5, 0.5), castshadow=False)
    spec.worldbody.add_geom(
        type=mujoco.mjtGeom.mjGEOM_PLANE, size=(20, 20, 0.1), rgba=(0.75, 0.73, 0.70, 1)
    )
    for k in range(len(FIVE)):
        spec.worldbody.add_camera(
            name=f"full{k}", pos=(1.2 * k, -3.2, 1.0), xyaxes=(1, 0, 0, 0, 0, 1)
        )
        spec.worldbody.add_camera(
            name=f"face{k}", pos=(1.2 * k, -0.9, 1.5), xyaxes=(1, 0, 0, 0, 0, 1)
        )
    drawing = PeopleDrawing.from_crowd(crowd, style)
    drawing.add_to(spec)
    model = spec.compile()
    data = mujoco.MjData(model)
    drawing.poser(model).pose(data, 1.3)
    mujoco.mj_forward(model, data)
    columns = []
    for k in range(len(FIVE)):
        head_z = crowd.pose(1.3)[0][k, 15, 2]
        model.cam_pos[model.camera(f"face{k}").id] = (1.2 * k, -0.75, head_z + 0.02)
        model.cam_pos[model.camera(f"full{k}").id][2] = 0.5 * head_z + 0.1
        mujoco.mj_forward(model, data)
        with Camera(model, f"full{k}", 240, 420, 38.0) as cam:
            full = cam.render(data, depth=False).rgb
        with Camera(model, f"face{k}", 240, 240, 24.0) as cam:
            face = cam.render(data, depth=False).rgb
        columns.append(np.concatenate([full, face], axis=0))
    return np.concatenate(columns, axis=1)


def _facing_views(scan, crowd: Crowd, model, data, count: int) -> list[tuple[np.ndarray, float]]:
    """Viewpoints 2.5–6 m from a person with a clear line of sight to them, looking at them."""
    graph = scan.graph
    walls = np.zeros(6, np.uint8)
    walls[0] = 1  # the building's visual geometry only
    geom_id = np.zeros(1, np.int32)
    mujoco.mj_forward(model, data)
    out, seen = [], []
    for state in crowd.states(10.0):
        if any(np.linalg.norm(state.position[:2] - s) < 2.0 for s in seen):
            continue  # one picture per group
        for vp in sorted(graph.nodes):
            p = graph.position(vp)
            ray = state.position - p
            d = float(np.hypot(*ray[:2]))
            if not 2.5 <= d <= 6.0 or abs(graph.floor_z(vp) - (state.position[2] - 0.9)) > 0.6:
                continue
            hit = mujoco.mj_ray(model, data, p, ray, walls, 1, -1, geom_id)
            if hit < 0 or hit > 1.0:
                out.append((p, heading_to(p, state.position)))
                seen.append(state.position[:2])
                break
        if len(out) == count:
            break
    return out


def crowd_frames(scenes: list[str], style: str, per_scene: int) -> np.ndarray:
    """Agent-camera frames toward people in ``scenes``, tiled two per row at half size."""
    tiles = []
    for scene in scenes:
        scan = load_scan(scene)
        crowd = populate(scan, np.random.default_rng(0), together=0.5)
        spec, _, _ = world_spec(scan, WorldOptions(collision="none"))
        drawing = PeopleDrawing.from_crowd(crowd, style)
        drawing.add_to(spec)
        model = spec.compile()
        data = mujoco.MjData(model)
        poser = drawing.poser(model)
        views = _facing_views(scan, crowd, model, data, per_scene)
        with Camera(model, CAMERA, 640, 480, 60.0) as cam:
            for eye, heading in views:
                for mesh in poser.pose(data, 10.0):
                    cam.upload_mesh(mesh)
                PointBody(eye, heading=heading, elevation=-0.1).write(model, data)
                rgb = cam.render(data, depth=False).rgb
                tiles.append(cv2.resize(rgb, (320, 240), interpolation=cv2.INTER_AREA))
    while len(tiles) % 2:
        tiles.append(np.zeros_like(tiles[0]))
    rows = [np.concatenate(tiles[i : i + 2], axis=1) for i in range(0, len(tiles), 2)]
    return np.concatenate(rows, axis=0)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", type=Path, default=Path("docs"))
    ap.add_argument("--style", default="pieces")
    ap.add_argument("--scenes", default="proc-0,proc-1,proc-2")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    five = five_people(args.style)
    cv2.imwrite(str(args.out / f"people_five_{args.style}.png"), five[..., ::-1])
    frames = crowd_frames(args.scenes.split(","), args.style, 2)
    cv2.imwrite(str(args.out / f"people_crowd_{args.style}.png"), frames[..., ::-1])
    return 0


if __name__ == "__main__":
    sys.exit(main())
