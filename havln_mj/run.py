"""``python -m havln_mj.run``: build a scene and walk shortest paths through it on camera.

People are placed by HA3D's rule and go about their activities while the agent walks; the
agent's collisions with them (within 1 m, checked at 16 Hz along the way) are counted per
episode. Everything goes through the :class:`~havln_mj.sim.simulator.Simulator`: each path
is walked as graph actions (turn toward the next viewpoint, then move to it) and filmed
during the actions. With ``--robot go1`` the same episodes are walked again by the simulated
GO1 and compared with the point body.

Writes to ``--out``: ``egocentric.mp4`` (the agent's view), ``frame.png`` (the view showing
people best, else the most detailed view of the first episode), ``topdown.png`` (floor plan,
rooms, graph, the walked paths, people), ``go1.mp4`` (with ``--robot go1``: the GO1's head
camera beside a chase view) and, last, ``summary.json``, which lists the files of the run.
Outputs are written to a staging folder and moved into place only when the run completes;
files an earlier run left in the folder that this run did not write are removed, so a folder
never mixes two runs. An interrupted run leaves the folder as it was and exits 130.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from havln_mj import __version__, argchecks
from havln_mj.errors import HavlnError, InvalidArgumentError
from havln_mj.frames import heading_to
from havln_mj.recording import OUTPUTS, Recording, staged_outputs
from havln_mj.scene.ids import parse_scene_id
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.procedural.recipe import load_recipe
from havln_mj.scene.scan import known_scene_ids
from havln_mj.sim.world import COLLISION_MODES, WorldOptions


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


def make_simulator(args: argparse.Namespace, body: str):
    """The simulator a run walks with: rendering on, RGB, the run's camera and people."""
    from havln_mj.sim.legged import LeggedOptions
    from havln_mj.sim.simulator import Simulator

    sim = Simulator(
        humans=not args.no_people,
        human_placements=args.human_placements,
        human_motions=args.haps_dir,
        smpl_model=args.smpl_model,
        body=body,
        legged=LeggedOptions(
            estimate=args.go1_estimate,
            camera_height=args.go1_camera_height,
            controller=args.go1_controller,
        ),
        together=args.together,
        reactions=not args.no_reactions,
    )
    if args.connectivity_dir is not None:
        sim.setNavGraphPath(args.connectivity_dir)
    if args.mp3d_dir is not None:
        sim.setDatasetPath(args.mp3d_dir)
    sim.setCameraResolution(args.width, args.height)
    sim.setCameraVFOV(math.radians(args.vfov))
    sim.setRestrictedNavigation(False)
    sim.set_color_order("RGB")
    sim.set_human_mask_enabled(True)
    sim.setSeed(args.seed)
    collision = args.collision if body == "point" else "auto"
    sim.set_world_options(
        WorldOptions(
            collision=collision,
            offscreen=(args.width, args.height),
            vfov_deg=args.vfov,
            people_style=args.people_style,
        )
    )
    sim.initialize()
    return sim


def walk(sim, scene: str, path: Sequence[str]) -> list:
    """Walks ``path`` with graph actions; returns the state after the start and each step.

    Each hop is two actions: turn to face the next viewpoint, then move to it. The walk
    stops early when the body falls, its physics diverges, or a move does not arrive.
    """
    graph = sim.graph(scene)
    start, nxt = graph.position(path[0]), graph.position(path[1])
    sim.newEpisode([scene], [path[0]], [heading_to(start, nxt)], [0.0])
    states = [sim.getState()[0]]
    for target in path[1:]:
        state = states[-1]
        ids = [v.viewpointId for v in state.navigableLocations]
        if target not in ids:
            raise InvalidArgumentError(
                f"viewpoint {target} is not navigable from {state.location.viewpointId}"
            )
        turn = state.navigableLocations[ids.index(target)].rel_heading
        if abs(turn) > 1e-6:
            sim.makeAction([0], [turn], [0.0])
            state = sim.getState()[0]
            ids = [v.viewpointId for v in state.navigableLocations]
        sim.makeAction([ids.index(target)], [0.0], [0.0])
        states.append(sim.getState()[0])
        last = states[-1]
        if last.fell or last.diverged or not last.arrived:
            break
    return states


PROG = "python -m havln_mj.run"


def parser(prog: str = PROG) -> argparse.ArgumentParser:
    """The command's argument parser."""
    p = argparse.ArgumentParser(prog=prog, description=__doc__.splitlines()[0])
    _add_run_flags(p)
    _add_view_flags(p)
    _add_people_flags(p)
    _add_robot_flags(p)
    argchecks.add_data_flags(
        p, "--human-placements", "--haps-dir", "--smpl-model", "--mp3d-dir", "--connectivity-dir"
    )
    return p


def _add_run_flags(p: argparse.ArgumentParser) -> None:
    """Which scene, how many episodes, where the outputs go."""
    p.add_argument(
        "--scene",
        default=None,
        help="proc-<seed>, a Matterport scan id, or a scan folder (default: built-in house)",
    )
    p.add_argument("--episodes", type=int, default=3, help="episodes to walk (default 3)")
    p.add_argument("--seed", type=int, default=0, help="seed of episodes and people (default 0)")
    p.add_argument(
        "--out", type=Path, default=None, help="output folder (default ./havln_runs/<scene>)"
    )


def _add_view_flags(p: argparse.ArgumentParser) -> None:
    """The pictures, the video and the map's collision geometry."""
    p.add_argument("--width", type=int, default=640, help="image width, pixels (default 640)")
    p.add_argument("--height", type=int, default=480, help="image height, pixels (default 480)")
    p.add_argument("--vfov", type=float, default=60.0, help="vertical field of view, degrees")
    p.add_argument("--fps", type=float, default=10.0, help="video frames per simulated second")
    p.add_argument(
        "--collision",
        choices=COLLISION_MODES,
        default="auto",
        help="collision geometry for the map's walkable area (default auto)",
    )


def _add_people_flags(p: argparse.ArgumentParser) -> None:
    """The people in the scene and how they are drawn."""
    p.add_argument("--no-people", action="store_true", help="leave the scene empty")
    p.add_argument(
        "--together",
        type=float,
        default=0.3,
        help="chance a person placed is joined by others (talking, walking along; default 0.3)",
    )
    p.add_argument(
        "--no-reactions",
        action="store_true",
        help="people ignore the agent (by default walkers yield and others glance at it)",
    )
    p.add_argument(
        "--people-style",
        choices=("pieces", "skinned", "capsules"),
        default="pieces",
        help="how people are drawn (default pieces: dressed bodies, fastest)",
    )


def _add_robot_flags(p: argparse.ArgumentParser) -> None:
    """The GO1 run beside the point agent."""
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
    argchecks.add_go1_controller_flag(p)
    p.add_argument(
        "--go1-camera-height",
        type=float,
        default=None,
        help="raise the GO1's camera on a mast to this height (m); default: its head camera",
    )


def parse_args(argv: Sequence[str] | None, prog: str = PROG) -> argparse.Namespace:
    """Parses and checks the command-line arguments (before any work is done)."""
    p = parser(prog)
    args = p.parse_args(argv)
    checks = [
        (
            args.scene is None or args.scene.strip(),
            f"--scene must name a scene, got {args.scene!r}",
        ),
        (args.episodes >= 1, f"--episodes must be at least 1, got {args.episodes}"),
        (args.seed >= 0, f"--seed must be ≥ 0, got {args.seed}"),
        (1 <= args.width <= 8192, f"--width must be in [1, 8192] pixels, got {args.width}"),
        (1 <= args.height <= 8192, f"--height must be in [1, 8192] pixels, got {args.height}"),
        (0 < args.vfov < 180, f"--vfov must be in (0, 180) degrees, got {args.vfov}"),
        (0 < args.fps <= 120, f"--fps must be in (0, 120], got {args.fps}"),
        (0 <= args.together <= 1, f"--together must be a chance in [0, 1], got {args.together}"),
        (
            args.go1_camera_height is None or 0.1 <= args.go1_camera_height <= 3.0,
            f"--go1-camera-height must be in [0.1, 3] m, got {args.go1_camera_height}",
        ),
    ]
    checks += [
        (message is None, message)
        for message in (
            argchecks.existing("--human-placements", args.human_placements, "file"),
            argchecks.existing("--haps-dir", args.haps_dir),
            argchecks.existing("--smpl-model", args.smpl_model, "file"),
            argchecks.existing("--mp3d-dir", args.mp3d_dir),
            argchecks.existing("--connectivity-dir", args.connectivity_dir),
        )
    ]
    for ok, message in checks:
        if not ok:
            p.error(message)
    return args


def run(args: argparse.Namespace) -> dict:
    """Builds the scene, walks the episodes, writes the outputs; returns the summary."""
    t_start = time.perf_counter()
    scene = args.scene or default_scene()
    parse_scene_id(scene, known_scene_ids())  # fail at once on a bad id
    out = (args.out or Path.cwd() / "havln_runs" / scene.replace("/", "_")).expanduser().resolve()
    with staged_outputs(out) as stage:
        sim = make_simulator(args, "point")
        source = sim.people_source(scene)  # fails before a graph proxy is built for nobody
        scan, crowd = sim.scan(scene), sim.crowd(scene)
        print(f"havln_mj {__version__}: {scan.description}", flush=True)
        print(
            f"people: {len(crowd)}", *(f"{p.text} ({p.region})" for p in crowd.people), sep="\n  "
        )
        episodes = sample_episodes(scan.graph, args.episodes, np.random.default_rng(args.seed))
        paths = [e.path for e in episodes]
        point = Recording(sim, crowd, stage / OUTPUTS["video"], args.fps, "point body")
        records = point.walk_all(scene, paths, walk)
        sim.close()
        go1, walked = None, None
        if args.robot == "go1":
            print("walking the episodes with the GO1 ...", flush=True)
            sim = make_simulator(args, "go1")
            robot = Recording(sim, crowd, stage / OUTPUTS["go1_video"], args.fps, "GO1", True)
            go1 = robot.compare(scene, paths, walk, records)
            walked = robot.tracks  # the map shows where the robot really went
            sim.close()
        point.write_frame(stage / OUTPUTS["frame"])
        point.write_map(stage / OUTPUTS["topdown"], scan, args.collision, episodes, records, walked)
        summary = {
            "havln_mj": __version__,
            "scene": scan.scene_id,
            "scene_kind": scan.kind,
            "description": scan.description,
            "seed": args.seed,
            "resolution": [args.width, args.height],
            "vfov_deg": args.vfov,
            "people_source": source,
            "people": [
                {
                    "activity": p.activity,
                    "text": p.text,
                    "region": p.region,
                    "viewpoint": p.viewpoint,
                }
                for p in crowd.people
            ],
            "human_collisions": sum(r["human_collisions"] for r in records),
            "episodes": records,
            "steps": sum(r["steps"] for r in records),
            "frames": point.frames,
            "timing": {
                "render_s": round(point.render_s, 3),
                "render_fps": round(point.frames / point.render_s, 1) if point.render_s else None,
                "total_s": round(time.perf_counter() - t_start, 3),
            },
        }
        if go1 is not None:
            summary["go1"] = go1
        summary = stage.finish(summary)
    print(f"wrote {out} ({summary['frames']} frames, {summary['steps']} steps)")
    return summary


def main(argv: Sequence[str] | None = None, prog: str = PROG) -> int:
    """Entry point; returns the process exit code."""
    args = parse_args(argv, prog)
    try:
        run(args)
    except HavlnError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted: the output folder is as it was before this run", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
