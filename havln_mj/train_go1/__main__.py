"""Trains the GO1's learned controller, or exports a checkpoint.

``python -m havln_mj.train_go1 --config CONFIG.json --out RUN [--resume] [--iterations N]``
``python -m havln_mj.train_go1 --out RUN --export POLICY.npz``
"""

from __future__ import annotations

import argparse
import sys

import torch

from havln_mj.errors import HavlnError
from havln_mj.train_go1.config import load_config
from havln_mj.train_go1.trainer import CHECKPOINT, Trainer, export_checkpoint


def main(argv: list[str] | None = None) -> int:
    """The command line."""
    p = argparse.ArgumentParser(
        prog="python -m havln_mj.train_go1", description=__doc__.splitlines()[0]
    )
    p.add_argument("--config", default=None, help="training config JSON (default: built-in)")
    p.add_argument("--out", required=True, help="run folder")
    p.add_argument("--resume", action="store_true", help="continue the run in --out")
    p.add_argument("--iterations", type=int, default=None, help="train to this many in all")
    p.add_argument("--device", default="cpu", help="cpu or cuda")
    p.add_argument("--threads", type=int, default=1, help="torch CPU threads")
    p.add_argument("--export", default=None, help="write the run's policy .npz here and exit")
    a = p.parse_args(argv)
    torch.set_num_threads(a.threads)
    try:
        if a.export:
            export_checkpoint(f"{a.out}/{CHECKPOINT}", a.export)
            return 0
        if a.device.startswith("cuda") and not torch.cuda.is_available():
            print("--device cuda: no CUDA device here", file=sys.stderr)
            return 2
        Trainer(load_config(a.config), a.out, resume=a.resume, device=a.device).train(a.iterations)
    except HavlnError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
