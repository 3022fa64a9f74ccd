"""``havln_mj dataset build``: generate an HA-R2R style split of episodes in scenes.

Writes ``HA_<split>.json`` (the HA-R2R schema: paths, instructions, the people on each path)
and ``vocab_<split>.txt`` (see :mod:`havln_mj.tasks.procedural`).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from havln_mj import argchecks
from havln_mj.errors import HavlnError, InvalidArgumentError
from havln_mj.scene.scan import known_scene_ids

HELP = "generate R2R-like episodes with people and instructions (HA-R2R schema)"


def dataset_build(args: argparse.Namespace) -> int:
    """Generates a split with a progress bar; prints the files and instruction lengths."""
    from havln_mj.tasks.procedural import build_split

    problem = argchecks.scene_ids("--scenes", args.scenes, known_scene_ids())
    if problem:
        raise InvalidArgumentError(problem)

    built = build_split(args.scenes, args.split, args.episodes_per_scene, args.seed, args.out)
    words = built.word_counts()
    print(
        f"wrote {len(built.episodes)} paths, {len(words)} instructions to {built.dataset} "
        f"and {built.vocab}; words per instruction: mean {sum(words) / len(words):.1f}, "
        f"min {min(words)}, max {max(words)}"
    )
    return 0


def _dataset_problems(args: argparse.Namespace) -> list[str | None]:
    return [
        argchecks.in_range("--episodes-per-scene", args.episodes_per_scene, 1),
        argchecks.in_range("--seed", args.seed, 0),
        argchecks.writable_folder("--out", args.out),
    ]


def parser(prog: str = "havln_mj dataset") -> argparse.ArgumentParser:
    """The command's argument parser (``build``)."""
    p = argparse.ArgumentParser(prog=prog, description=HELP)
    sub = p.add_subparsers(dest="command", required=True, metavar="{build}")
    gen = sub.add_parser("build", help=HELP)
    gen.add_argument(
        "--scenes", nargs="+", required=True, help="scene ids: proc-<seed>, scan ids, folders"
    )
    gen.add_argument("--split", required=True, help="split name: writes HA_<split>.json")
    gen.add_argument(
        "--episodes-per-scene", type=int, default=20, help="paths per scene (default 20)"
    )
    gen.add_argument("--seed", type=int, default=0, help="seed; the simulator's people match it")
    gen.add_argument("--out", type=Path, default=Path("."), help="output folder (default .)")
    return p


def main(argv: Sequence[str] | None = None, prog: str = "havln_mj dataset") -> int:
    """Entry point; returns the exit code (2 on bad input)."""
    p = parser(prog)
    args = p.parse_args(argv)
    for problem in _dataset_problems(args):
        if problem:
            p.error(problem)
    try:
        return dataset_build(args)
    except HavlnError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
