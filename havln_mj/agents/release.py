"""``python -m havln_mj.agents.release IN OUT``: a trained checkpoint made ready to ship.

Writes ``IN`` (a ``best.pt`` or ``checkpoint.pt`` of :mod:`havln_mj.agents.train`) to ``OUT``
without what only resuming needs (:meth:`~havln_mj.agents.checkpoint.AgentBundle.released`):
the network, vocabulary, view encoder, feature settings, training configuration and history
stay, so ``python -m havln_mj.eval --agent OUT`` evaluates it as before.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from havln_mj.agents.checkpoint import AgentBundle
from havln_mj.errors import HavlnError


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit code (2 on bad input)."""
    p = argparse.ArgumentParser(
        prog="python -m havln_mj.agents.release", description=__doc__.splitlines()[0]
    )
    p.add_argument("source", type=Path, help="a trained checkpoint (best.pt)")
    p.add_argument("target", type=Path, help="where the released checkpoint is written")
    args = p.parse_args(argv)
    try:
        bundle = AgentBundle.load(args.source)
        bundle.released().save(args.target)
    except HavlnError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    sizes = {"source_bytes": args.source.stat().st_size, "target_bytes": args.target.stat().st_size}
    print(json.dumps({"agent": bundle.agent, "target": str(args.target), **sizes}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
