"""``python -m havln_mj.distributed.evaluate``: ``havln_mj eval`` with two Ray workers by default.

:func:`evaluate_split_ray` (:mod:`havln_mj.distributed.sharded`) is the sharded evaluation.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

from havln_mj.commands.evaluate import main as eval_main
from havln_mj.distributed.sharded import evaluate_split_ray

__all__ = ["evaluate_split_ray", "main"]


def main(argv: Sequence[str] | None = None) -> int:
    """``havln_mj eval`` on Ray actors: its arguments, with ``--workers`` 2 unless given."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if not any(a == "--workers" or a.startswith("--workers=") for a in argv):
        argv = ["--workers", "2", *argv]
    return eval_main(argv, prog="python -m havln_mj.distributed.evaluate")


if __name__ == "__main__":
    sys.exit(main())
