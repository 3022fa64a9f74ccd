"""``havln_mj eval``: score an agent or expert on a split, in one process or on Ray actors.

The flags are :mod:`havln_mj.eval.cli`'s; the scoring is :mod:`havln_mj.eval.run`'s. With
``--workers`` above 1 or an ``--address``, the instructions run on Ray actors
(:mod:`havln_mj.distributed.sharded`, the ``distributed`` extra); the scores equal a single
process's.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from havln_mj.eval.cli import PROG, parse_args
from havln_mj.eval.cli import parser as parser  # the command's flags, for ``havln_mj eval``
from havln_mj.eval.run import run_cli
from havln_mj.tasks.episodes import Episode


def main(argv: Sequence[str] | None = None, prog: str = PROG) -> int:
    """Entry point; returns the process exit code."""
    args = parse_args(argv, prog)
    if args.workers > 1 or args.address is not None:
        from havln_mj.distributed.sharded import evaluate_split_ray  # the Ray extra

        def sharded(a: argparse.Namespace, episodes: Sequence[Episode], split: str) -> dict:
            return evaluate_split_ray(a, episodes, split, workers=a.workers, address=a.address)

        return run_cli(args, sharded)
    return run_cli(args)
