"""``python -m havln_mj.run``: build a scene and walk shortest paths through it on camera.

People are placed by HA3D's rule and go about their activities while the agent walks; the
agent's collisions with them (within 1 m, checked at 16 Hz along the way) are counted per
episode. Writes to ``--out``: ``egocentric.mp4`` (the agent's view), ``frame.png`` (the view
showing people best, else the most detailed view of the first episode), ``topdown.png``
(floor plan, rooms, graph, the walked paths, people) and ``summary.json``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import mujoco
import numpy as np
from tqdm import tqdm

from havln_mj import __version__, groups
from havln_mj.errors import HavlnError, InvalidArgumentError
from havln_mj.frames import heading_to, wrap_angle
from havln_mj.humans.crowd import Crowd
from havln_mj.humans.mujoco_people import PeopleWriter
from havln_mj.humans.skinned import SkinWriter
from havln_mj.nav import NavGrid
from havln_mj.render.camera import Camera
from havln_mj.render.topdown import draw_topdown
from havln_mj.robot.point_body import CAMERA, PointBody
from havln_mj.run_go1 import run_go1
from havln_mj.scene.ids import parse_scene_id
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.procedural.recipe import load_recipe
from havln_mj.scene.scan import known_scene_ids, load_scan
from havln_mj.sim.crowd import COLLISION_DISTANCE, SAMPLE_HZ, Proximity, track_proximity
from havln_mj.sim.legged import LeggedOptions
from havln_mj.sim.people import HumanCrowds
from havln_mj.sim.world import COLLISION_MODES, WorldOptions, build_world


def default_scene() -> str:
    """The built-in default scene id (from ``scenes/procedural.json``)."""
    return str(load_recipe()["default_scene"])


@dataclass(frozen=True)
class Episode:
    """A start and goal and the shortest path between them."""

    start: str
    goal: str
    path: list[str]
    distance: float


def sample_episodes(
    graph: NavGraph, n: int, rng: np.random.Generator, min_distance: float = 3.0
) -> list[Episode]:
    """Random start/goal pairs in the largest component, preferring ≥ ``min_distance`` apart."""
    nodes = graph.components()[0]
    if len(nodes) < 2:
        raise InvalidArgumentError(
            f"scene {graph.name!r} has no two connected viewpoints to walk between"
        )
    episodes = []
    for _ in range(n):
        for _try in range(50):
            a, b = (nodes[i] for i in rng.choice(len(nodes), size=2, replace=False))
            if graph.distance(a, b) >= min_distance:
                break
        episodes.append(Episode(a, b, graph.shortest_path(a, b), graph.distance(a, b)))
    return episodes


def walk(body: PointBody, graph: NavGraph, path: Sequence[str], fps: float):
    """Moves the body along a path, turning toward each next viewpoint and then walking to it.

    Yields:
        The simulated time (s) after each sample, at ``fps`` samples per simulated second; the
        body holds the pose of that moment.
    """
    t = 0.0
    yield t
    for nxt in path[1:]:
        start, target = body.position.copy(), graph.position(nxt)
        turn = wrap_angle(heading_to(start, target) - body.heading)
        h0 = body.heading
        duration = body.turn_duration(turn)
        steps = max(1, math.ceil(duration * fps))
        for k in range(1, steps + 1):
            body.set_pose(start, h0 + turn * k / steps)
            yield t + duration * k / steps
        t += duration
        duration = body.move_duration(target)
        steps = max(1, math.ceil(duration * fps))
        for k in range(1, steps + 1):
            body.set_pose(start + (target - start) * k / steps, body.heading)
            yield t + duration * k / steps
        t += duration


def _nearest_person(crowd: Crowd, t: float, position: np.ndarray) -> float:
    """Horizontal distance from ``position`` to the nearest pelvis at time ``t`` (inf if none)."""
    if not len(crowd):
        return math.inf
    pelvis = crowd.positions(np.array([t]))[0]
    return float(np.min(np.hypot(*(pelvis[:, :2] - position[:2]).T)))


def _collisions(crowd: Crowd, track: np.ndarray) -> Proximity:
    """The people an episode's track ``(n, 4)`` of ``(t, x, y, z)`` came within 1 m of.

    The track is piecewise linear between samples, so resampling it at 16 Hz is exact.
    """
    t = track[:, 0]
    dense = np.union1d(t, np.arange(t[0], t[-1], 1.0 / SAMPLE_HZ))
    xyz = np.column_stack([np.interp(dense, t, track[:, i]) for i in (1, 2, 3)])
    return track_proximity(crowd, dense, xyz)


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    """Parses command-line arguments."""
    p = argparse.ArgumentParser(prog="python -m havln_mj.run", description=__doc__.splitlines()[0])
    p.add_argument(
        "--scene",
        default=None,
        help="proc-<seed>, a Matterport scan id, or a scan folder (default: built-in house)",
    )
    p.add_argument("--episodes", type=int, default=3, help="episodes to walk (default 3)")
    p.add_argument("--seed", type=int, default=0, help="seed for start/goal sampling (default 0)")
    p.add_argument(
        "--out", type=Path, default=None, help="output folder (default ./havln_runs/<scene>)"
    )
    p.add_argument("--width", type=int, default=640)
    p.add_argument("--height", type=int, default=480)
    p.add_argument("--vfov", type=float, default=60.0, help="vertical field of view, degrees")
    p.add_argument("--fps", type=float, default=10.0, help="video frames per simulated second")
    p.add_argument("--collision", choices=COLLISION_MODES, default="auto")
    p.add_argument("--no-people", action="store_true", help="leave the scene empty")
    p.add_argument(
        "--robot",
        choices=("point", "go1"),
        default="point",
        help="go1: also walk the episodes with the simulated GO1 and compare (go1.mp4)",
    )
    p.add_argument(
        "--go1-estimate",
        choices=("truth", "odometry"),
        default="truth",
        help="what the GO1's primitives are closed on (default: ground truth)",
    )
    p.add_argument(
        "--go1-camera-height",
        type=float,
        default=None,
        help="raise the GO1's camera on a mast to this height (m); default: its head camera",
    )
    p.add_argument(
        "--human-placements",
        type=Path,
        default=None,
        help="HA3D placement file for real scans (default $HAVLN_HA3D_PLACEMENTS)",
    )
    p.add_argument(
        "--haps-dir",
        type=Path,
        default=None,
        help="HAPS motion folder to play instead of built-in motions (default $HAVLN_HAPS_DIR)",
    )
    p.add_argument(
        "--smpl-model",
        type=Path,
        default=None,
        help="SMPL model file to draw people as skinned meshes (default $HAVLN_SMPL_MODEL)",
    )
    p.add_argument(
        "--mp3d-dir",
        type=Path,
        default=None,
        help="Matterport3D data root (raw or habitat layout; default $HAVLN_MP3D_DIR)",
    )
    p.add_argument(
        "--connectivity-dir",
        type=Path,
        default=None,
        help="folder of <scan>_connectivity.json graphs (default $HAVLN_CONNECTIVITY_DIR)",
    )
    args = p.parse_args(argv)
    if args.episodes < 1:
        p.error(f"--episodes must be at least 1, got {args.episodes}")
    if not (0 < args.fps <= 120):
        p.error(f"--fps must be in (0, 120], got {args.fps}")
    return args


def run(args: argparse.Namespace) -> dict:
    """Builds the scene, walks the episodes, writes the outputs; returns the summary."""
    t_start = time.perf_counter()
    scene = args.scene or default_scene()
    parse_scene_id(scene, known_scene_ids())  # fail at once on a bad id
    out = (args.out or Path.cwd() / "havln_runs" / scene.replace("/", "_")).expanduser().resolve()
    out.mkdir(parents=True, exist_ok=True)

    t0 = time.perf_counter()
    scan = load_scan(scene, mp3d_dir=args.mp3d_dir, connectivity_dir=args.connectivity_dir)
    t_scan = time.perf_counter() - t0
    print(f"havln_mj {__version__}: {scan.description}", flush=True)
    crowd = Crowd([])
    if not args.no_people:
        make = HumanCrowds(lambda _: scan, args.human_placements, args.haps_dir, args.smpl_model)
        crowd = make(scan.scene_id, scan.graph, np.random.default_rng([args.seed, 1]))
    print(f"people: {len(crowd)}", *(f"{p.text} ({p.region})" for p in crowd.people), sep="\n  ")
    world = build_world(
        scan,
        WorldOptions(
            collision=args.collision, offscreen=(args.width, args.height), vfov_deg=args.vfov
        ),
        crowd.shapes,
        crowd.skins,
    )
    print(
        f"world: {world.model.ngeom} geoms, collision {world.collision} "
        f"({world.n_collision_geoms} geoms), built in {world.build_seconds:.2f} s",
        flush=True,
    )

    graph = scan.graph
    rng = np.random.default_rng(args.seed)
    episodes = sample_episodes(graph, args.episodes, rng)
    model, data = world.model, mujoco.MjData(world.model)
    video_path, frame_path = out / "egocentric.mp4", out / "frame.png"
    writer = cv2.VideoWriter(
        str(video_path), cv2.VideoWriter_fourcc(*"mp4v"), args.fps, (args.width, args.height)
    )
    if not writer.isOpened():
        raise HavlnError(f"cannot open an MP4 writer for {video_path}")
    people = PeopleWriter(model, len(crowd))
    skinned = [k for k, skin in enumerate(crowd.skins) if skin is not None]
    skins = SkinWriter(model, skinned) if skinned else None
    human_geom = model.geom_group == groups.HUMANS
    records, render_s, frames, clock = [], 0.0, 0, 0.0
    best_detail, best_frame = -1.0, None
    with Camera(
        model, CAMERA, args.width, args.height, args.vfov, geom_groups=groups.CAMERA_GROUPS
    ) as cam:
        for k, ep in enumerate(tqdm(episodes, desc="episodes", unit="ep")):
            start = graph.position(ep.start)
            body = PointBody(start, heading=heading_to(start, graph.position(ep.path[1])))
            sim_t, ep_frames, track = 0.0, 0, []
            for sim_t in walk(body, graph, ep.path, args.fps):
                track.append((clock + sim_t, *body.position))
                people.write(data, *crowd.pose(clock + sim_t))
                if skins is not None:
                    verts = crowd.skin_vertices(clock + sim_t)
                    for mesh in skins.write(model, data, verts):
                        cam.upload_mesh(mesh)
                body.write(model, data)
                t0 = time.perf_counter()
                rgb = cam.render(data, depth=False).rgb
                render_s += time.perf_counter() - t0
                bgr = cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR)
                near = _nearest_person(crowd, clock + sim_t, body.position)
                cv2.putText(
                    bgr,
                    f"episode {k + 1}/{len(episodes)}  t={sim_t:5.1f}s"
                    + ("  COLLISION" if near <= COLLISION_DISTANCE else ""),
                    (8, 20),
                    cv2.FONT_HERSHEY_SIMPLEX,
                    0.5,
                    (255, 255, 255),
                    1,
                    cv2.LINE_AA,
                )
                writer.write(bgr)
                # Keep the view showing people best (checked a few times a second), else
                # the most detailed first-episode view.
                score = float(rgb.std()) / 1e3 if k == 0 else -1.0
                if len(crowd) and ep_frames % max(1, round(args.fps / 3)) == 0:
                    ids = cam.render_geom_ids(data)
                    seen = float((human_geom[np.maximum(ids, 0)] & (ids >= 0)).mean())
                    score += seen if seen < 0.1 else 0.0  # whole people, not one up close
                if score > best_detail:
                    best_detail, best_frame = score, rgb

                ep_frames += 1
            frames += ep_frames
            contact = _collisions(crowd, np.array(track))
            clock += sim_t
            records.append(
                {
                    "start": ep.start,
                    "goal": ep.goal,
                    "path": ep.path,
                    "steps": len(ep.path) - 1,
                    "geodesic_m": round(ep.distance, 3),
                    "path_length_m": round(graph.path_length(ep.path), 3),
                    "sim_seconds": round(sim_t, 3),
                    "frames": ep_frames,
                    "human_collisions": len(contact.people),
                    "people_hit": [crowd.people[i].text for i in contact.people],
                    "min_human_distance_m": (
                        round(contact.min_distance, 3) if len(crowd) else None
                    ),
                }
            )
    writer.release()
    cv2.imwrite(str(frame_path), cv2.cvtColor(best_frame, cv2.COLOR_RGB2BGR))
    map_path = out / "topdown.png"
    level = graph.floor_z(episodes[0].start)
    navgrid = None
    if world.collision != "none":
        navgrid = NavGrid.from_model(model, level)
        for ep, rec in zip(episodes, records, strict=True):
            if abs(graph.floor_z(ep.goal) - level) < 0.5:
                d = navgrid.distance(graph.position(ep.start), graph.position(ep.goal))
                rec["grid_geodesic_m"] = round(d, 3) if math.isfinite(d) else None
    draw_topdown(
        map_path,
        graph,
        scan.regions,
        scan.mesh,
        [e.path for e in episodes],
        level_floor=level,
        title=scan.description,
        navgrid=navgrid,
        people=crowd.positions(np.array([0.0]))[0],
    )
    go1 = None
    if args.robot == "go1":
        print("walking the episodes with the GO1 ...", flush=True)
        go1 = run_go1(
            scan,
            crowd,
            [e.path for e in episodes],
            out,
            width=args.width,
            height=args.height,
            vfov=args.vfov,
            fps=args.fps,
            options=LeggedOptions(estimate=args.go1_estimate, camera_height=args.go1_camera_height),
            collision="auto" if args.collision == "none" else args.collision,
        )
    summary = {
        "havln_mj": __version__,
        "scene": scan.scene_id,
        "scene_kind": scan.kind,
        "description": scan.description,
        "seed": args.seed,
        "resolution": [args.width, args.height],
        "vfov_deg": args.vfov,
        "collision": world.collision,
        "people": [
            {"activity": p.activity, "text": p.text, "region": p.region, "viewpoint": p.viewpoint}
            for p in crowd.people
        ],
        "human_collisions": sum(r["human_collisions"] for r in records),
        "episodes": records,
        "steps": sum(r["steps"] for r in records),
        "frames": frames,
        "timing": {
            "scan_load_s": round(t_scan, 3),
            "world_build_s": round(world.build_seconds, 3),
            "render_s": round(render_s, 3),
            "render_fps": round(frames / render_s, 1) if render_s > 0 else None,
            "total_s": round(time.perf_counter() - t_start, 3),
        },
        "files": {"video": str(video_path), "frame": str(frame_path), "topdown": str(map_path)},
    }
    if go1 is not None:
        summary["go1"] = go1
        summary["files"]["go1_video"] = go1["video"]
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    print(
        f"wrote {out} ({frames} frames, {summary['steps']} steps, {summary['timing']['total_s']} s)"
    )
    return summary


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the process exit code."""
    args = parse_args(argv)
    try:
        run(args)
    except HavlnError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
