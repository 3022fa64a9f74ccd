"""``havln_mj scenes``: pre-build scenes, or export a built world as MJCF.

``havln_mj scenes build <ids...>`` builds each scene in its own process (scan folder,
collision geometry, compiled world), so later runs load from the cache at once; a scene that
fails is reported on its line and the others are still built. ``havln_mj scenes export ID
--out DIR`` writes a built world (building, collision, people at a chosen time, the robot) as
MJCF with its meshes and textures (see :mod:`havln_mj.sim.export`).
"""

from __future__ import annotations

import argparse
import signal
import sys
from collections.abc import Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from pathlib import Path

from tqdm import tqdm

from havln_mj import argchecks
from havln_mj.ctrl_c import CtrlC
from havln_mj.errors import HavlnError, InvalidArgumentError
from havln_mj.humans.mujoco_people import DRAW_STYLES
from havln_mj.scene.realscan import CONNECTIVITY_ENV, resolve_connectivity_dir
from havln_mj.scene.scan import known_scene_ids
from havln_mj.sim.prebuild import build_scene
from havln_mj.sim.world import COLLISION_MODES

HELP = "pre-build scenes, or export a built world as MJCF"


def _scene_ids(args: argparse.Namespace) -> list[str]:
    ids = list(args.ids)
    if args.all_connectivity:
        conn_dir = resolve_connectivity_dir(args.connectivity_dir)
        if conn_dir is None:
            raise InvalidArgumentError(
                f"--all-connectivity needs --connectivity-dir (or ${CONNECTIVITY_ENV})"
            )
        ids += sorted(
            p.name[: -len("_connectivity.json")] for p in conn_dir.glob("*_connectivity.json")
        )
    if not ids:
        raise InvalidArgumentError("no scene ids given (e.g. proc-0 proc-1, or --all-connectivity)")
    return list(dict.fromkeys(ids))  # each scene once, in the order given


def _summary(row: dict) -> str:
    """One built scene's line: kind, size, collision geometry, how its edges are walked."""
    geoms = f"{row['collision_geoms']} {row['collision']} collision geoms"
    routes = row["edges_by_route"]
    walks = f"{routes} edge{'' if routes == 1 else 's'} walked by route"
    if row["edges_by_flight"]:
        walks += f" ({row['edges_by_flight']} along a flight drawn for it)"
    if row["unwalkable_edges"] is not None:
        walks += f", {row['unwalkable_edges']} unwalkable"
    return (
        f"{row['scene']}: {row['kind']}, {row['viewpoints']} viewpoints, {geoms}, {walks}, "
        f"{row['seconds']} s"
    )


def _report(scene: str, future: Future) -> int:
    """Writes a built scene's line; returns 1 if it failed."""
    try:
        tqdm.write(_summary(future.result()))
    except HavlnError as exc:
        tqdm.write(f"{scene}: FAILED: {exc}")
    except Exception as exc:  # a crash in one scene must not lose the others
        tqdm.write(f"{scene}: FAILED unexpectedly ({type(exc).__name__}: {exc})")
    else:
        return 0
    return 1


def _interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


def _init_worker() -> None:
    """Makes a build worker clean up on SIGTERM as on Ctrl-C, and keep a lost Ctrl-C quiet.

    A pool whose worker died terminates the others; without this their staging folders stay.
    A worker whose Ctrl-C was lost finishes its scene, which is then kept whole.
    """
    signal.signal(signal.SIGTERM, _interrupt)
    CtrlC().install()


def scenes_build(args: argparse.Namespace) -> int:
    """Builds the scenes in parallel with a progress bar; prints one line per scene.

    A scene that fails is reported on its line and the others are still built.
    """
    ids = _scene_ids(args)
    problem = argchecks.scene_ids("scene ids", ids, known_scene_ids())
    if problem:
        raise InvalidArgumentError(problem)
    workers, note = argchecks.worker_count(args.workers, len(ids))
    if note:
        print(note, file=sys.stderr)
    failures = 0
    ctrl_c = CtrlC()
    ctrl_c.install()
    try:
        with ProcessPoolExecutor(max_workers=workers, initializer=_init_worker) as pool:
            futures = {
                pool.submit(build_scene, s, args.mp3d_dir, args.connectivity_dir, args.collision): s
                for s in ids
            }
            try:
                with tqdm(total=len(ids), desc="scenes", unit="scene") as bar:
                    for future in as_completed(futures):
                        failures += _report(futures[future], future)
                        bar.update()
                if ctrl_c.seen:
                    raise KeyboardInterrupt
            except KeyboardInterrupt:
                pool.shutdown(wait=True, cancel_futures=True)  # scenes not started stay unbuilt
                raise
    finally:
        ctrl_c.restore()
    print(f"built {len(ids) - failures} of {len(ids)} scenes")
    return 1 if failures else 0


def scenes_export(args: argparse.Namespace) -> int:
    """Exports one scene as MJCF; prints what was written."""
    from havln_mj.sim.export import export_scene

    done = export_scene(
        args.id,
        args.out,
        time=args.time,
        body=args.body,
        seed=args.seed,
        humans=not args.no_people,
        together=args.together,
        people_style=args.people_style,
        viewpoint=args.viewpoint,
        collision=args.collision,
        solid_people=args.solid_people,
        mp3d_dir=args.mp3d_dir,
        connectivity_dir=args.connectivity_dir,
        human_placements=args.human_placements,
    )
    print(
        f"wrote {done.xml} ({done.ngeom} geoms, {done.people} people at t = {args.time:g} s, "
        f"{done.meshes} meshes, {done.textures} textures); view it with "
        f"python -m mujoco.viewer --mjcf={done.xml}"
    )
    return 0


def _add_export(scenes: argparse._SubParsersAction) -> None:
    export = scenes.add_parser(
        "export", help="write a built world (building, people, robot) as MJCF with its assets"
    )
    export.add_argument("id", help="scene id: proc-<seed>, a Matterport scan id, a scan folder")
    export.add_argument("--out", type=Path, required=True, help="output folder")
    export.add_argument(
        "--time", type=float, default=0.0, help="simulated seconds at which people are posed"
    )
    export.add_argument(
        "--body", choices=("point", "go1"), default="point", help="the agent: camera rig or GO1"
    )
    export.add_argument("--seed", type=int, default=0, help="simulator seed: which people")
    export.add_argument("--no-people", action="store_true", help="leave the people out")
    export.add_argument(
        "--together", type=float, default=0.0, help="chance a placed person is joined by others"
    )
    export.add_argument(
        "--people-style",
        choices=DRAW_STYLES,
        default="pieces",
        help="how people are drawn: dressed rigid pieces, one skinned mesh, or capsules",
    )
    export.add_argument(
        "--viewpoint", default=None, help="where the agent stands (default: the first one)"
    )
    export.add_argument(
        "--collision", choices=COLLISION_MODES, default="auto", help="collision geometry"
    )
    export.add_argument(
        "--solid-people", action="store_true", help="people's bodies collide (push a robot)"
    )
    argchecks.add_data_flags(export, "--human-placements", "--mp3d-dir", "--connectivity-dir")


def _build_problems(args: argparse.Namespace) -> list[str | None]:
    return [
        argchecks.in_range("--workers", args.workers, 1),
        argchecks.existing("--mp3d-dir", args.mp3d_dir),
        argchecks.existing("--connectivity-dir", args.connectivity_dir),
    ]


def _export_problems(args: argparse.Namespace) -> list[str | None]:
    return [
        argchecks.in_range("--time", args.time, 0.0, unit=" s"),
        argchecks.in_range("--together", args.together, 0.0, 1.0),
        argchecks.existing("--mp3d-dir", args.mp3d_dir),
        argchecks.existing("--connectivity-dir", args.connectivity_dir),
        argchecks.existing("--human-placements", args.human_placements, "file"),
        argchecks.writable_folder("--out", args.out),
    ]


def parser(prog: str = "havln_mj scenes") -> argparse.ArgumentParser:
    """The command's argument parser (``build`` and ``export``)."""
    p = argparse.ArgumentParser(prog=prog, description=HELP)
    sub = p.add_subparsers(dest="command", required=True, metavar="{build,export}")
    build = sub.add_parser("build", help="pre-build scans, collision geometry and worlds")
    build.add_argument(
        "ids", nargs="*", help="scene ids: proc-<seed>, Matterport scan ids, scan folders"
    )
    build.add_argument(
        "--all-connectivity", action="store_true", help="every scan in --connectivity-dir"
    )
    build.add_argument("--mp3d-dir", type=Path, default=None, help="Matterport3D data root")
    build.add_argument(
        "--connectivity-dir", type=Path, default=None, help="folder of connectivity graphs"
    )
    build.add_argument(
        "--collision",
        choices=COLLISION_MODES,
        default="auto",
        help="collision geometry: auto (boxes when the scan has them, else CoACD hulls)",
    )
    build.add_argument(
        "--workers",
        type=int,
        default=2,
        help="parallel processes (default 2; at most one per scene and per CPU)",
    )
    _add_export(sub)
    return p


def main(argv: Sequence[str] | None = None, prog: str = "havln_mj scenes") -> int:
    """Entry point; returns the exit code (2 on bad input, 130 when interrupted)."""
    p = parser(prog)
    args = p.parse_args(argv)
    export = args.command == "export"
    for problem in _export_problems(args) if export else _build_problems(args):
        if problem:
            p.error(problem)
    try:
        return scenes_export(args) if export else scenes_build(args)
    except HavlnError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted: finished scenes are kept, unfinished ones left out", file=sys.stderr)
        return 130
