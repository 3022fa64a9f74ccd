"""Which people each scan gets, for the simulator.

Scans listed in an HA3D placement file (``human_motion_text.json``; for the 90 real scans)
get HA3D's people at HA3D's viewpoints; every other scan is populated by HA3D's rule on its
regions (see :mod:`havln_mj.humans.population`). A graph proxy without a ``.house`` file has
no region labels, so it gets no people unless the placement file lists it.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from havln_mj.humans.crowd import Crowd
from havln_mj.humans.population import populate, populate_ha3d, read_ha3d_placements
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.scan import Scan

PLACEMENTS_ENV = "HAVLN_HA3D_PLACEMENTS"


class HumanCrowds:
    """Makes the crowd of a scan from ``(scan id, graph, generator)``.

    Args:
        load: Loads a scan by id (the simulator's scene library).
        placements: HA3D placement file; default ``$HAVLN_HA3D_PLACEMENTS`` if set.
    """

    def __init__(self, load: Callable[[str], Scan], placements: Path | str | None = None) -> None:
        self._load = load
        path = placements if placements is not None else os.environ.get(PLACEMENTS_ENV)
        self._placements = read_ha3d_placements(path) if path else {}

    def __call__(self, scan_id: str, graph: NavGraph, rng: np.random.Generator) -> Crowd:
        """The people of ``scan_id``, drawn from ``rng``."""
        entries = self._placements.get(scan_id)
        if entries is not None:
            return populate_ha3d(graph, entries, rng)
        return populate(self._load(scan_id), rng)
