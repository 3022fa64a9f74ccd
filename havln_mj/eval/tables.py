"""Result tables in the HA-VLN paper's layout from evaluation folders.

``python -m havln_mj.eval.tables --row "VLN-CM 0 %=runs/a,runs/b,runs/c" --row ... --out T.md``
reads each folder's ``summary.json`` (written by ``python -m havln_mj.eval``), averages the
runs of a row (mean ± standard deviation over seeds when there are several) and writes one
line per row with NE / TCR / CR / SR for every split, followed by the paper's rows for
comparison (``--paper``).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from havln_mj.cache import atomic_write_bytes, atomic_write_json
from havln_mj.errors import HavlnError, InvalidArgumentError, MissingDataError

METRICS = ("ne", "tcr", "cr", "sr")
# The HA-VLN paper's numbers (NE, TCR, CR, SR; None: not stated), val seen / val unseen.
PAPER = {
    "paper: sub-optimal expert (Oracle)": {
        "val_seen": (0.67, 0.04, 0.04, 0.89),
        "val_unseen": (0.62, 0.01, 0.01, 0.91),
    },
    "paper: optimal expert": {
        "val_seen": (None, 0.14, 0.22, 1.00),
        "val_unseen": (None, 0.09, 0.18, 1.00),
    },
    "paper: VLN-CM (0 % random data)": {
        "val_seen": (7.31, 0.38, 0.73, 0.19),
        "val_unseen": (8.22, 0.42, 0.62, 0.12),
    },
    "paper: VLN-DT (100 % random data)": {
        "val_seen": (8.51, 0.30, 0.77, 0.21),
        "val_unseen": (8.22, 0.37, 0.58, 0.11),
    },
}


def read_row(folders: Sequence[Path]) -> dict[str, dict[str, list[float]]]:
    """Split → metric → the values of each folder's ``summary.json``.

    Raises:
        MissingDataError: A folder has no ``summary.json``.
    """
    out: dict[str, dict[str, list[float]]] = {}
    for folder in folders:
        path = Path(folder) / "summary.json"
        if not path.is_file():
            raise MissingDataError(f"{path} does not exist; run python -m havln_mj.eval first")
        for summary in json.loads(path.read_text()):
            split = out.setdefault(summary["split"], {m: [] for m in METRICS})
            for m in METRICS:
                split[m].append(float(summary[m]))
    return out


def _cell(values: Sequence[float | None]) -> str:
    vals = [v for v in values if v is not None]
    if not vals:
        return "–"
    if len(vals) == 1:
        return f"{vals[0]:.2f}"
    return f"{np.mean(vals):.2f} ± {np.std(vals):.2f}"


def markdown(
    rows: dict[str, dict[str, dict[str, list[float]]]], splits: Sequence[str], paper: bool
) -> str:
    """The table: a row per agent, NE / TCR / CR / SR per split."""
    head = "| agent | " + " | ".join(f"{s} NE | TCR | CR | SR" for s in splits) + " |"
    lines = [head, "|---|" + "---|---|---|---|" * len(splits)]
    for name, row in rows.items():
        cells = [_cell(row.get(s, {}).get(m, [])) for s in splits for m in METRICS]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    if paper:
        for name, row in PAPER.items():
            cells = []
            for s in splits:
                vals = row.get(s, (None,) * 4)
                cells += [_cell([v]) for v in vals]
            lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


PROG = "python -m havln_mj.eval.tables"


def parser(prog: str = PROG) -> argparse.ArgumentParser:
    """The command's argument parser."""
    p = argparse.ArgumentParser(prog=prog, description=__doc__.splitlines()[0])
    p.add_argument(
        "--row",
        action="append",
        required=True,
        metavar="NAME=DIR[,DIR...]",
        help="a row: its name and the evaluation folders (--out of havln_mj eval) it reads",
    )
    p.add_argument(
        "--splits",
        nargs="+",
        default=["val_seen", "val_unseen"],
        help="the splits, as columns (default val_seen val_unseen)",
    )
    p.add_argument("--paper", action="store_true", help="append the paper's rows")
    p.add_argument("--out", type=Path, required=True, help="markdown file (a .json beside it)")
    return p


def main(argv: Sequence[str] | None = None, prog: str = PROG) -> int:
    """Entry point; returns the exit code."""
    args = parser(prog).parse_args(argv)
    try:
        rows = {}
        for item in args.row:
            name, sep, dirs = item.partition("=")
            if not sep or not dirs:
                raise InvalidArgumentError(f"--row {item!r} is not NAME=DIR[,DIR...]")
            rows[name] = read_row([Path(d) for d in dirs.split(",")])
    except HavlnError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    table = markdown(rows, args.splits, args.paper)
    atomic_write_bytes(args.out, table.encode())
    atomic_write_json(args.out.with_suffix(".json"), rows, indent=1)
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
