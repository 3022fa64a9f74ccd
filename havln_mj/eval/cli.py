"""The arguments of ``python -m havln_mj.eval``: parsed and checked before any work.

Every flag is checked here with the valid range in its message (argparse's exit 2, no
traceback); :func:`load_splits` then reads the episodes they name.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path

from havln_mj import argchecks
from havln_mj.errors import InvalidArgumentError
from havln_mj.eval.setup import AGENTS, protocol_of
from havln_mj.scene.ids import expand_scene_ranges
from havln_mj.tasks.datasets import load_dataset
from havln_mj.tasks.episodes import Episode
from havln_mj.tasks.metrics.config import COUNT_MODES, CRITICAL_MODES
from havln_mj.tasks.procedural import procedural_episodes
from havln_mj.tasks.protocol import PROTOCOL_NAMES, get_protocol

DESCRIPTION = "Run an agent over a split and score it with the HA-VLN metrics."


def _existing_dir(text: str) -> Path:
    path = Path(text).expanduser()
    if not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is not a folder")
    return path


def _existing_file(text: str) -> Path:
    path = Path(text).expanduser()
    if not path.is_file():
        raise argparse.ArgumentTypeError(f"{text!r} is not a file")
    return path


PROG = "python -m havln_mj.eval"


def parser(prog: str = PROG) -> argparse.ArgumentParser:
    """The command's argument parser."""
    p = argparse.ArgumentParser(prog=prog, description=DESCRIPTION)
    _add_episode_flags(p)
    _add_agent_flags(p)
    _add_world_flags(p)
    _add_output_flags(p)
    return p


def _add_episode_flags(p: argparse.ArgumentParser) -> None:
    """Which episodes: a dataset or procedural scenes."""
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--dataset", nargs="+", help="R2R/HA-R2R JSON files or split names")
    src.add_argument(
        "--scenes", nargs="+", help="procedural scene ids (proc-<seed>; proc-A:B for a range)"
    )
    p.add_argument("--split", default=None, help="name of the split in the tables")
    p.add_argument("--per-scene", type=int, default=10, help="episodes per procedural scene (≥ 1)")
    p.add_argument(
        "--skip", type=int, default=0, help="leave out each scene's first paths (val_seen; ≥ 0)"
    )


def _add_agent_flags(p: argparse.ArgumentParser) -> None:
    """The agent, its body and the scoring protocol."""
    p.add_argument(
        "--agent",
        default="shortest",
        help=f"{', '.join(AGENTS)}, module:callable or a trained agent's checkpoint (.pt)",
    )
    p.add_argument(
        "--body",
        choices=("point", "go1"),
        default="point",
        help="the agent's body: the point camera rig (default) or the simulated GO1",
    )
    argchecks.add_go1_controller_flag(p)
    p.add_argument(
        "--protocol",
        choices=PROTOCOL_NAMES,
        default="strict",
        help="strict (ours, the default) or ha3d (HA3D's code, to compare with the paper)",
    )
    p.add_argument(
        "--critical",
        choices=CRITICAL_MODES,
        default=None,
        help="unavoidable people: paper (crux points, clipped), ha3d (HA3D's whole metric "
        "rule: Beginning/End, unclipped, raw CR) or none (default: the protocol's)",
    )
    p.add_argument(
        "--count",
        choices=COUNT_MODES,
        default=None,
        help="collisions per step (HA3D) or per visited viewpoint (default: step)",
    )


def _add_world_flags(p: argparse.ArgumentParser) -> None:
    """The people and where the scans' data is."""
    p.add_argument("--seed", type=int, default=0, help="seed of people and random agents (≥ 0)")
    p.add_argument("--no-people", action="store_true", help="evaluate without people")
    p.add_argument(
        "--pinned-people",
        action="store_true",
        help="people play their motions on the spot where they were placed (HA3D's barely move)",
    )
    p.add_argument(
        "--connectivity-dir",
        type=_existing_dir,
        default=None,
        help="folder of <scan>_connectivity.json graphs (default $HAVLN_CONNECTIVITY_DIR)",
    )
    p.add_argument(
        "--human-placements",
        type=_existing_file,
        default=None,
        help="HA3D placement file for real scans (default $HAVLN_HA3D_PLACEMENTS)",
    )
    p.add_argument(
        "--data-dir", type=_existing_dir, default=None, help="folder with r2r/ and ha_r2r/"
    )


def _add_output_flags(p: argparse.ArgumentParser) -> None:
    """Outputs, resuming and parallelism."""
    p.add_argument(
        "--out", type=Path, default=Path("havln_eval"), help="output folder (default havln_eval)"
    )
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue the interrupted evaluation in --out (same arguments)",
    )
    p.add_argument(
        "--record",
        type=int,
        default=0,
        metavar="N",
        help="film the first N instructions: a video and a top-down map each (≥ 0)",
    )
    p.add_argument(
        "--threads", type=int, default=None, help="torch threads of a trained agent (≥ 1)"
    )
    p.add_argument(
        "--workers",
        type=int,
        default=1,
        help="Ray actors to shard the instructions over (default 1: in this process); the "
        "'distributed' extra",
    )
    p.add_argument(
        "--address",
        default=None,
        help="Ray cluster: auto, ray://host:10001 (default: a local Ray when --workers > 1)",
    )


def parse_args(argv: Sequence[str] | None, prog: str = PROG) -> argparse.Namespace:
    """Parses and checks the command-line arguments, before any work is done."""
    p = parser(prog)
    args = p.parse_args(argv)
    checks = [
        (args.workers >= 1, f"--workers must be at least 1, got {args.workers}"),
        (args.per_scene >= 1, f"--per-scene must be at least 1, got {args.per_scene}"),
        (args.skip >= 0, f"--skip must be ≥ 0, got {args.skip}"),
        (0 <= args.seed < 2**32, f"--seed must be in [0, 2^32), got {args.seed}"),
        (args.record >= 0, f"--record must be ≥ 0 instructions, got {args.record}"),
        (
            args.threads is None or args.threads >= 1,
            f"--threads must be at least 1, got {args.threads}",
        ),
        (not args.out.is_file(), f"--out {str(args.out)!r} is a file; give a folder"),
        (args.split is None or args.split.strip(), f"--split must be a name, got {args.split!r}"),
        (args.agent.strip(), "--agent must name an agent"),
    ]
    for ok, message in checks:
        if not ok:
            p.error(message)
    if args.critical is None:
        args.critical = get_protocol(args.protocol).metrics.critical
    return args


def settings(args: argparse.Namespace) -> dict:
    """What decides an evaluation's results (``run.json``; ``--resume`` must match it)."""

    def path(p: Path | None) -> str | None:
        return None if p is None else str(Path(p).expanduser().resolve())

    protocol = protocol_of(args)
    return {
        "agent": args.agent,
        "body": args.body,
        "protocol": protocol.name,
        "metrics": asdict(protocol.metrics),
        "seed": args.seed,
        "people": not args.no_people,
        "pinned_people": args.pinned_people,
        "human_placements": path(args.human_placements),
        "connectivity_dir": path(args.connectivity_dir),
        "dataset": [str(d) for d in args.dataset] if args.dataset else None,
        "scenes": args.scenes,
        "per_scene": args.per_scene if args.scenes else None,
        "skip": args.skip if args.scenes else None,
        "split": args.split,
    }


def load_splits(args: argparse.Namespace) -> list[tuple[str, list[Episode]]]:
    """The splits ``args`` names: ``(name, episodes)`` each.

    Raises:
        InvalidArgumentError: A dataset with no episodes, or a path with no instructions.
        MissingDataError: A dataset file that does not exist.
    """
    if args.scenes:
        scenes = expand_scene_ranges(args.scenes)
        episodes = procedural_episodes(scenes, args.per_scene, args.seed, args.skip)
        return [(args.split or "procedural", episodes)]
    splits = []
    for name in args.dataset:
        data = load_dataset(name, connectivity_dir=args.connectivity_dir, data_dir=args.data_dir)
        if not data.episodes:
            raise InvalidArgumentError(f"dataset {data.source} has no episodes")
        _check_instructions(data.source, data.episodes)
        splits.append((args.split or Path(str(name)).stem, list(data.episodes)))
    return splits


def _check_instructions(source: str, episodes: Sequence[Episode]) -> None:
    """Refuses paths without instructions: they would be dropped from the split unseen."""
    ids = [e.path_id for e in episodes if not e.instructions]
    if ids:
        shown = ", ".join(map(str, ids[:5])) + (" ..." if len(ids) > 5 else "")
        raise InvalidArgumentError(
            f"dataset {source}: {len(ids)} path(s) with no instructions (path_id {shown}); "
            "every path needs at least one"
        )
