"""Skybox mode: views of a made-up skybox, their speed, and (given a MatterSim build) how far
they are from MatterSim's own images of the same files.

A synthetic scan is written to a temporary folder in MatterSim's layout (connectivity graph,
``<vp>_skybox_small.jpg`` of six smooth, distinct faces, three viewpoints whose poses face
different ways). ``skybox_view`` renders views at random headings and elevations; with
``--mattersim-build DIR`` (the folder holding ``MatterSim*.so``, see
``../shared/peers/mattersim/build.sh``) MatterSim renders the same views (OSMesa) and the JSON
gives the per-pixel differences and both frame rates. Also timed: a 360° panorama of
``proc-0`` and a composited skybox frame (people from MuJoCo).

Prints one JSON object. Run: ``python benchmarks/bench_skybox.py [--mattersim-build DIR]``.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import os
import tempfile
import time
from pathlib import Path

import numpy as np
from common import machine

os.environ.setdefault("MUJOCO_GL", "egl")

W, H, VFOV = 640, 480, 60.0
SCAN = "fakeScan001"


def _make_dataset(root: Path, size: int = 512) -> list[tuple[str, np.ndarray]]:
    """Writes the synthetic scan; returns (viewpoint, pose) pairs."""
    import cv2

    sky = root / "scans" / SCAN / "matterport_skybox_images"
    sky.mkdir(parents=True)
    graph = root / "connectivity"
    graph.mkdir()
    yy, xx = np.mgrid[0:size, 0:size] / size
    faces = []
    for k in range(6):
        face = np.stack([40 * k + 20 + 0 * xx, 30 + 190 * xx, 30 + 190 * yy], -1)
        face += 20 * np.sin(2 * np.pi * (xx * (k + 1) + yy * (6 - k)))[..., None]
        faces.append(np.clip(face, 0, 255).astype(np.uint8))
    strip = np.concatenate(faces, axis=1)[..., ::-1]
    out = []
    for k, yaw in enumerate((0.0, 0.9, 2.5)):
        vp = f"vp{k}"
        cv2.imwrite(str(sky / f"{vp}_skybox_small.jpg"), strip, [cv2.IMWRITE_JPEG_QUALITY, 100])
        pose = np.eye(4)
        look, right = [math.sin(yaw), math.cos(yaw), 0.0], [math.cos(yaw), -math.sin(yaw), 0.0]
        pose[:3, :3] = np.column_stack([right, [0.0, 0.0, -1.0], look])
        pose[:3, 3] = [2.0 * k, 0.0, 1.5]
        out.append((vp, pose))
    entries = [
        {
            "image_id": vp,
            "pose": pose.ravel().tolist(),
            "included": True,
            "visible": [True] * len(out),
            "unobstructed": [i != j for j in range(len(out))],
            "height": 1.5,
        }
        for i, (vp, pose) in enumerate(out)
    ]
    (graph / f"{SCAN}_connectivity.json").write_text(json.dumps(entries))
    (graph / "scans.txt").write_text(SCAN + "\n")
    return out


def _import_mattersim(build: Path):
    """MatterSim's module. Imported before MuJoCo: its OSMesa GL calls must bind first, or
    they reach the EGL library MuJoCo loads and draw nothing."""
    # Loaded from its file (a benchmark peer, never a dependency of the package).
    found = sorted(build.glob("MatterSim*.so"))
    if not found:
        raise FileNotFoundError(f"no MatterSim*.so in {build}")
    spec = importlib.util.spec_from_file_location("MatterSim", found[0])
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _mattersim(module, root: Path):
    sim = module.Simulator()
    sim.setDatasetPath(str(root / "scans"))
    sim.setNavGraphPath(str(root / "connectivity"))
    sim.setCameraResolution(W, H)
    sim.setCameraVFOV(math.radians(VFOV))
    sim.setElevationLimits(-1.5, 1.5)
    sim.setRenderingEnabled(True)
    sim.initialize()
    return sim


def _compare(views, root: Path, mattersim) -> dict:
    from havln_mj.render.skybox import load_skybox, skybox_view

    folder = root / "scans" / SCAN / "matterport_skybox_images"
    rng = np.random.default_rng(0)
    shots = [
        (vp, pose, rng.uniform(0, 2 * math.pi), rng.uniform(-0.9, 0.9))
        for vp, pose in views
        for _ in range(10)
    ]
    skies = {vp: load_skybox(folder, vp) for vp, _ in views}
    ours, times = [], []
    for vp, pose, heading, elevation in shots:
        t = time.perf_counter()
        rgb, _ = skybox_view(skies[vp], pose[:3, :3], heading, elevation, W, H, VFOV)
        times.append(time.perf_counter() - t)
        ours.append(rgb)
    result = {"views": len(shots), "havln_skybox_view_fps": round(1 / float(np.median(times)), 1)}
    if mattersim is None:
        return result
    sim, theirs, times = _mattersim(mattersim, root), [], []
    for vp, _, heading, elevation in shots:
        t = time.perf_counter()
        sim.newEpisode([SCAN], [vp], [heading], [elevation])
        state = sim.getState()[0]
        times.append(time.perf_counter() - t)
        theirs.append(np.array(state.rgb, copy=True)[..., ::-1])
    diff = np.abs(np.stack(ours).astype(int) - np.stack(theirs).astype(int))
    result |= {
        "mattersim_newEpisode_getState_fps": round(1 / float(np.median(times)), 1),
        "abs_diff_mean": round(float(diff.mean()), 3),
        "abs_diff_max": int(diff.max()),
        "pixels_identical": round(float(np.mean(diff.max(axis=-1) == 0)), 4),
        "pixels_within_2": round(float(np.mean(diff.max(axis=-1) <= 2)), 6),
    }
    return result


def _panorama_and_composite() -> dict:
    import mujoco

    from havln_mj import groups
    from havln_mj.humans.mujoco_people import PeopleWriter
    from havln_mj.humans.population import populate
    from havln_mj.render.camera import Camera
    from havln_mj.render.cubemap import render_faces
    from havln_mj.render.panorama import render_panorama
    from havln_mj.render.skybox import Skybox, render_skybox_frame
    from havln_mj.robot.point_body import CAMERA, PointBody
    from havln_mj.scene.scan import load_scan
    from havln_mj.sim.world import build_world

    scan = load_scan("proc-0")
    crowd = populate(scan, np.random.default_rng(0), count=4)
    model = build_world(scan, people=crowd.shapes).model
    data = mujoco.MjData(model)
    PeopleWriter(model, len(crowd)).write(data, *crowd.pose(0.0))
    graph = scan.graph
    vp = graph.nodes[5]
    eye = graph.position(vp)
    rotation = graph.connectivity.poses[graph.connectivity.ids.index(vp)][:3, :3]
    PointBody(eye).write(model, data)
    with Camera(model, CAMERA, 256, 256, geom_groups=groups.CAMERA_GROUPS) as square:
        t = time.perf_counter()
        render_panorama(model, data, square, eye, height=256)
        pano_s = time.perf_counter() - t
        faces = render_faces(model, data, square, eye, rotation)
    sky = Skybox(faces.rgb, faces.depth)
    times = []
    with Camera(model, CAMERA, W, H, VFOV, geom_groups=groups.CAMERA_GROUPS) as cam:
        for k in range(12):
            PointBody(eye, heading=0.5 * k).write(model, data)
            t = time.perf_counter()
            render_skybox_frame(model, data, cam, sky, rotation)
            times.append(time.perf_counter() - t)
    return {
        "panorama_512x256_s": round(pano_s, 3),
        "skybox_frame_with_people_fps": round(1 / float(np.median(times)), 1),
    }


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--mattersim-build", type=Path, default=None)
    args = ap.parse_args()
    mattersim = _import_mattersim(args.mattersim_build) if args.mattersim_build else None
    os.environ["HAVLN_CACHE"] = tempfile.mkdtemp(prefix="havln_bench_")
    root = Path(tempfile.mkdtemp(prefix="havln_skybox_"))
    views = _make_dataset(root)
    result = {"machine": machine(), "size": f"{W}x{H}", "vfov_deg": VFOV}
    result["skybox_vs_mattersim"] = _compare(views, root, mattersim)
    result |= _panorama_and_composite()
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
