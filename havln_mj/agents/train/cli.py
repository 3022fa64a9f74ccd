"""``python -m havln_mj.agents.train``: the training command's arguments and exit codes."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

import torch

from havln_mj.agents.checkpoint import AGENTS
from havln_mj.agents.train.config import read_config
from havln_mj.agents.train.trainer import Trainer, checkpoint_to_resume
from havln_mj.errors import HavlnError

PROG = "python -m havln_mj.agents.train"


def parser(prog: str = PROG) -> argparse.ArgumentParser:
    """The command's argument parser."""
    p = argparse.ArgumentParser(
        prog=prog,
        description="Train a VLN-CM or VLN-DT agent from a JSON config.",
    )
    p.add_argument(
        "--agent", choices=AGENTS, default=None, help="the agent (default: the config's)"
    )
    p.add_argument(
        "--config", type=Path, required=True, help="JSON file, or a name in agents/configs/"
    )
    p.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a config key (dotted keys reach into sections; the value read as JSON)",
    )
    p.add_argument("--out", type=Path, default=None, help="output folder (default runs/<agent>)")
    p.add_argument(
        "--resume", action="store_true", help="continue from OUT/checkpoint.pt (it must exist)"
    )
    p.add_argument(
        "--device",
        default="cpu",
        help="cpu, cuda (data-parallel over every visible GPU) or cuda:N (default cpu)",
    )
    p.add_argument("--no-tensorboard", action="store_true", help="do not write TensorBoard events")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.add_argument(
        "--threads",
        type=int,
        default=None,
        help="torch threads (default: torch's; 1 on a busy machine)",
    )
    return p


def main(argv: Sequence[str] | None = None, prog: str = PROG) -> int:
    """Entry point; returns the exit code (2 on bad input, with the message on stderr)."""
    args = parser(prog).parse_args(argv)
    if args.threads is not None:
        torch.set_num_threads(max(1, args.threads))
    try:
        cfg = read_config(args.config, args.agent, args.overrides)
        out = (args.out or Path("runs") / cfg.agent).expanduser().resolve()
        if args.resume:
            checkpoint_to_resume(out)  # before the features are built
        trainer = Trainer(
            cfg,
            out,
            progress=not args.no_progress,
            device=args.device,
            tensorboard=not args.no_tensorboard,
        )
        last = trainer.run(resume=args.resume)
    except HavlnError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(json.dumps({"out": str(out), **last}))
    return 0
