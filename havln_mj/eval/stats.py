"""``python -m havln_mj.eval.stats``: how much of the buildings people reach (HA-VLN paper).

Over every navigation graph that HA3D's placement file lists (the paper: 90 buildings), two
shares of the included viewpoints, each definition written from HA3D's code:

* **directly affected** (the paper: 8.16 %): the viewpoint's camera is within
  :data:`AFFECTED_M` (3-D) of a person's viewpoint, the distance within which HA3D's
  ``getRelPos`` links a person to a path node as an obstacle (``src/utils/get_info.py``);
  the share within the 1 m collision radius is given too.
* **people in view** (the paper: 46.47 %): a person stands on the viewpoint, or the
  viewpoint's ``visible`` list in the connectivity file names a person's viewpoint: HA3D's
  ``getHumanInfo`` / ``countPointsSeenHuman`` rule.

Prints (and with ``--out`` writes) a JSON report with the counts, the shares and the paper's
numbers beside them.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from havln_mj.cache import atomic_write_json
from havln_mj.errors import HavlnError, MissingDataError
from havln_mj.humans.population import read_ha3d_placements
from havln_mj.scene.connectivity import read_connectivity
from havln_mj.sim.crowd import COLLISION_DISTANCE

AFFECTED_M = 1.5
"""Metres within which HA3D's ``getRelPos`` links a person to a path node."""
PAPER = {"affected": 0.0816, "in_view": 0.4647}


def viewpoint_stats(connectivity_dir: Path, placements: Path) -> dict:
    """The shares of viewpoints directly affected by people and with people in view.

    Raises:
        MissingDataError: The placement file, or a listed scan's graph, does not exist.
    """
    people = read_ha3d_placements(placements)
    counts = {"viewpoints": 0, "people": 0, "on": 0, "affected": 0, "within_1m": 0, "in_view": 0}
    scans = sorted(people)
    for scan in scans:
        path = Path(connectivity_dir) / f"{scan}_connectivity.json"
        if not path.is_file():
            raise MissingDataError(f"{path} not found: the placements list scan {scan}")
        c = read_connectivity(path)
        index = {vp: i for i, vp in enumerate(c.ids)}
        held = np.zeros(len(c.ids), bool)
        held[[index[vp] for vp in people[scan]]] = True
        pos = c.positions
        gap = np.linalg.norm(pos[:, None] - pos[held][None], axis=2)  # (N, people)
        inc = np.asarray(c.included, bool)
        counts["viewpoints"] += int(inc.sum())
        counts["people"] += int(held.sum())
        counts["on"] += int((held & inc).sum())
        counts["affected"] += int(((gap <= AFFECTED_M).any(axis=1) & inc).sum())
        counts["within_1m"] += int(((gap <= COLLISION_DISTANCE).any(axis=1) & inc).sum())
        seen = held | np.asarray(c.visible, bool)[:, held].any(axis=1)
        counts["in_view"] += int((seen & inc).sum())
    n = max(counts["viewpoints"], 1)
    return {
        "scans": len(scans),
        **counts,
        "share_affected": round(counts["affected"] / n, 4),
        "share_within_1m": round(counts["within_1m"] / n, 4),
        "share_in_view": round(counts["in_view"] / n, 4),
        "paper": {"share_affected": PAPER["affected"], "share_in_view": PAPER["in_view"]},
        "definitions": {
            "affected": f"camera within {AFFECTED_M} m (3-D) of a person's viewpoint "
            "(HA3D getRelPos)",
            "within_1m": "camera within the 1 m collision radius of a person's viewpoint",
            "in_view": "a person on the viewpoint, or its 'visible' list names a person's "
            "viewpoint (HA3D getHumanInfo)",
        },
    }


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit code."""
    p = argparse.ArgumentParser(
        prog="python -m havln_mj.eval.stats", description=__doc__.splitlines()[0]
    )
    p.add_argument("--connectivity-dir", type=Path, required=True)
    p.add_argument("--human-placements", type=Path, required=True)
    p.add_argument("--out", type=Path, default=None, help="JSON file to write")
    args = p.parse_args(argv)
    try:
        report = viewpoint_stats(args.connectivity_dir, args.human_placements)
    except HavlnError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.out is not None:
        atomic_write_json(args.out, report, indent=1)
    print(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
