"""``havln_mj`` command line: ``havln_mj scenes build <ids...>`` pre-builds scans.

``havln_mj view --scene <id>`` opens the live viewer (:mod:`havln_mj.viewer`).

Each scene is built in its own process (scan folder, collision geometry, compiled world), so
later runs load from the cache at once. Run ``havln_mj scenes build --help`` for options.
``havln_mj dataset build --scenes <ids...> --split <name>`` writes an HA-R2R style split of
generated episodes (see :mod:`havln_mj.tasks.procedural`). ``havln_mj annotate --scene <id>``
serves a local page to place people and save them as HA3D placements
(see :mod:`havln_mj.annotator`).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

from tqdm import tqdm

from havln_mj.annotator import command as annotate_command
from havln_mj.errors import HavlnError, InvalidArgumentError
from havln_mj.sim.prebuild import build_scene
from havln_mj.sim.world import COLLISION_MODES


def _scene_ids(args: argparse.Namespace) -> list[str]:
    ids = list(args.ids)
    if args.all_connectivity:
        if args.connectivity_dir is None:
            raise InvalidArgumentError("--all-connectivity needs --connectivity-dir")
        ids += sorted(
            p.name[: -len("_connectivity.json")]
            for p in args.connectivity_dir.glob("*_connectivity.json")
        )
    if not ids:
        raise InvalidArgumentError("no scene ids given (e.g. proc-0 proc-1, or --all-connectivity)")
    return ids


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


def scenes_build(args: argparse.Namespace) -> int:
    """Builds the scenes in parallel with a progress bar; prints one line per scene."""
    ids = _scene_ids(args)
    failures = 0
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        futures = {
            pool.submit(build_scene, s, args.mp3d_dir, args.connectivity_dir, args.collision): s
            for s in ids
        }
        with tqdm(total=len(ids), desc="scenes", unit="scene") as bar:
            for future in as_completed(futures):
                scene = futures[future]
                try:
                    row = future.result()
                    tqdm.write(_summary(row))
                except HavlnError as exc:
                    failures += 1
                    tqdm.write(f"{scene}: FAILED: {exc}")
                bar.update()
    print(f"built {len(ids) - failures} of {len(ids)} scenes")
    return 1 if failures else 0


def dataset_build(args: argparse.Namespace) -> int:
    """Generates a split with a progress bar; prints the files and instruction lengths."""
    from havln_mj.tasks.procedural import build_split

    built = build_split(args.scenes, args.split, args.episodes_per_scene, args.seed, args.out)
    words = built.word_counts()
    print(
        f"wrote {len(built.episodes)} paths, {len(words)} instructions to {built.dataset} "
        f"and {built.vocab}; words per instruction: mean {sum(words) / len(words):.1f}, "
        f"min {min(words)}, max {max(words)}"
    )
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``havln_mj`` command."""
    parser = argparse.ArgumentParser(prog="havln_mj", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="group", required=True)
    scenes = sub.add_parser("scenes", help="scene tools").add_subparsers(
        dest="command", required=True
    )
    build = scenes.add_parser("build", help="pre-build scans, collision geometry and worlds")
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
    build.add_argument("--collision", choices=COLLISION_MODES, default="auto")
    build.add_argument("--workers", type=int, default=2, help="parallel processes (default 2)")
    dataset = sub.add_parser("dataset", help="episode datasets").add_subparsers(
        dest="command", required=True
    )
    gen = dataset.add_parser(
        "build", help="generate R2R-like episodes with people and instructions (HA-R2R schema)"
    )
    gen.add_argument(
        "--scenes", nargs="+", required=True, help="scene ids: proc-<seed>, scan ids, folders"
    )
    gen.add_argument("--split", required=True, help="split name: writes HA_<split>.json")
    gen.add_argument(
        "--episodes-per-scene", type=int, default=20, help="paths per scene (default 20)"
    )
    gen.add_argument("--seed", type=int, default=0, help="seed; the simulator's people match it")
    gen.add_argument("--out", type=Path, default=Path("."), help="output folder (default .)")
    from havln_mj import viewer

    viewer.add_arguments(
        sub.add_parser("view", help="the live MuJoCo viewer with keyboard control of the agent")
    )
    annotate_command.add_parser(sub)
    args = parser.parse_args(argv)
    if args.group == "view":
        return viewer.main(args)
    if args.group == "annotate":
        try:
            return annotate_command.annotate(args)
        except HavlnError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
    if args.group == "dataset":
        if args.episodes_per_scene < 1:
            parser.error(f"--episodes-per-scene must be at least 1, got {args.episodes_per_scene}")
    elif args.workers < 1:
        parser.error(f"--workers must be at least 1, got {args.workers}")
    try:
        return dataset_build(args) if args.group == "dataset" else scenes_build(args)
    except HavlnError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
