"""Renders the pictures of the procedural houses' look in ``docs/``.

- ``home_contact_sheet.png``: 12 views, three rooms in each of four houses (the views with
  the most objects in sight);
- ``look_before_after.png``: the same views in the plain look the houses had before (flat
  colours, box furniture, no windows) and in the home look;
- ``segmentation_frame.png``: a view with people, its mpcat40 classes and its instances;
- ``panorama.png``: a 360° panorama at a viewpoint, colour over classes.

Run: ``python docs/home_frames.py [--out docs] [--seeds 0 1 2 3]``.
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import tempfile
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import cv2
import mujoco
import numpy as np

from havln_mj import groups
from havln_mj.frames import heading_to
from havln_mj.humans.mujoco_people import PeopleWriter
from havln_mj.humans.population import populate
from havln_mj.render.camera import Camera
from havln_mj.render.labels import colorize, render_labels
from havln_mj.render.panorama import render_panorama
from havln_mj.robot.point_body import CAMERA, PointBody
from havln_mj.scene.mesh import boxes_to_parts, write_glb
from havln_mj.scene.regions import REGION_LABELS
from havln_mj.scene.scan import load_scan, read_scan_folder
from havln_mj.sim.world import build_world

W, H = 320, 240
ELEVATION = -0.2


def _best_views(scan, model, data, count: int) -> list[tuple[str, float, str]]:
    """(viewpoint, heading, room name) of the views showing most objects, one per room kind."""
    graph, scored = scan.graph, []
    with Camera(model, CAMERA, 96, 72, geom_groups=groups.CAMERA_GROUPS) as cam:
        for vp in graph.nodes:
            for heading in np.arange(0.0, 2 * math.pi, math.pi / 4):
                PointBody(graph.position(vp), heading=heading, elevation=ELEVATION).write(
                    model, data
                )
                seg = render_labels(model, data, cam)
                depth = cam.render(data, rgb=False).depth
                score = len(np.unique(seg.instance)) + 2.0 * min(float(depth.mean()), 4.0)
                score -= 30.0 * float(np.mean(depth < 1.3))  # not a view into a fridge door
                scored.append((score, vp, float(heading), scan.regions.region_of(vp).label))
    chosen, kinds = [], set()
    for _, vp, heading, kind in sorted(scored, key=lambda s: -s[0]):
        if kind not in kinds:
            chosen.append((vp, heading, REGION_LABELS[kind]))
            kinds.add(kind)
        if len(chosen) == count:
            break
    return chosen


def _shoot(scan, model, data, views, caption: bool = True) -> list[np.ndarray]:
    out = []
    with Camera(model, CAMERA, W, H, geom_groups=groups.CAMERA_GROUPS) as cam:
        for vp, heading, name in views:
            PointBody(scan.graph.position(vp), heading=heading, elevation=ELEVATION).write(
                model, data
            )
            image = np.ascontiguousarray(cam.render(data).rgb[..., ::-1])
            if caption:
                text = f"{scan.scene_id}, {name}"
                for colour, weight in (((0, 0, 0), 3), ((255, 255, 255), 1)):  # outlined
                    font = cv2.FONT_HERSHEY_SIMPLEX
                    cv2.putText(image, text, (8, H - 10), font, 0.45, colour, weight, cv2.LINE_AA)
            out.append(image)
    return out


def _grid(images: list[np.ndarray], columns: int) -> np.ndarray:
    rows = [np.concatenate(images[i : i + columns], axis=1) for i in range(0, len(images), columns)]
    return np.concatenate(rows, axis=0)


def _plain(scan, folder: Path):
    """The same scan in the plain look: flat box colours, no part labels."""
    shutil.copytree(scan.folder, folder)
    (folder / "semantics.json").unlink()
    write_glb(boxes_to_parts(scan.boxes), folder / "mesh.glb")
    return read_scan_folder(folder)


def sheets(seeds: list[int], out: Path) -> None:
    """The contact sheet and the before/after pictures."""
    tiles, pairs = [], []
    tmp = Path(tempfile.mkdtemp(prefix="havln_docs_"))
    for seed in seeds:
        scan = load_scan(f"proc-{seed}")
        model = build_world(scan).model
        data = mujoco.MjData(model)
        views = _best_views(scan, model, data, 3)
        home = _shoot(scan, model, data, views)
        tiles += home
        if len(pairs) < 8:
            plain = _plain(scan, tmp / scan.scene_id)
            pmodel = build_world(plain).model
            before = _shoot(plain, pmodel, mujoco.MjData(pmodel), views)
            pairs += [
                np.concatenate([b, a], axis=1) for b, a in zip(before[:2], home[:2], strict=True)
            ]
    shutil.rmtree(tmp, ignore_errors=True)
    cv2.imwrite(str(out / "home_contact_sheet.png"), _grid(tiles, 3))
    cv2.imwrite(str(out / "look_before_after.png"), _grid(pairs[:6], 1))


def segmentation(out: Path, seed: int = 3) -> None:
    """A view with people: colour, mpcat40 classes, instances."""
    scan = load_scan(f"proc-{seed}")
    crowd = populate(scan, np.random.default_rng(1), count=4)
    model = build_world(scan, people=crowd.shapes).model
    data = mujoco.MjData(model)
    PeopleWriter(model, len(crowd)).write(data, *crowd.pose(2.0))
    graph, best = scan.graph, None
    with Camera(model, CAMERA, W, H, geom_groups=groups.CAMERA_GROUPS) as cam:
        for state in crowd.states(2.0):
            target = state.position + np.array([0.0, 0.0, 0.8])
            for vp in graph.nodes:
                p = graph.position(vp)
                if not 2.0 < np.linalg.norm(p[:2] - target[:2]) < 4.5:
                    continue
                PointBody(p, heading=heading_to(p, target), elevation=-0.15).write(model, data)
                seg = render_labels(model, data, cam)
                near = min(float((seg.semantic == 42).mean()), 0.06)  # in sight, not in the way
                score = near + 0.01 * len(np.unique(seg.instance))
                if best is None or score > best[0]:
                    best = (score, p, heading_to(p, target))
        PointBody(best[1], heading=best[2], elevation=-0.15).write(model, data)
        rgb = cam.render(data).rgb
        seg = render_labels(model, data, cam)
    palette = np.random.default_rng(0).integers(40, 255, (int(seg.instance.max()) + 1, 3))
    palette[0] = 0
    picture = np.concatenate(
        [rgb, colorize(seg.semantic), palette[seg.instance].astype(np.uint8)], 1
    )
    cv2.imwrite(str(out / "segmentation_frame.png"), picture[..., ::-1])


def panorama(out: Path, seed: int = 0) -> None:
    """A 360° panorama of a living room, colour above classes."""
    scan = load_scan(f"proc-{seed}")
    model = build_world(scan).model
    data = mujoco.MjData(model)
    graph = scan.graph
    vp = next(v for v in graph.nodes if scan.regions.region_of(v).label == "l")
    with Camera(model, CAMERA, 256, 256, geom_groups=groups.CAMERA_GROUPS) as cam:
        PointBody(graph.position(vp)).write(model, data)
        pano = render_panorama(model, data, cam, graph.position(vp), height=320)
    picture = np.concatenate([pano.rgb, colorize(pano.semantic)], axis=0)
    cv2.imwrite(str(out / "panorama.png"), picture[..., ::-1])


def main() -> None:
    """Writes the pictures."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3])
    args = ap.parse_args()
    sheets(args.seeds, args.out)
    segmentation(args.out)
    panorama(args.out)


if __name__ == "__main__":
    main()
