"""Which people each scan gets, for the simulator.

Scans listed in an HA3D placement file (``human_motion_text.json``; for the 90 real scans)
get HA3D's people at HA3D's viewpoints; every other scan is populated by HA3D's rule on its
regions (see :mod:`havln_mj.humans.population`). A graph proxy without a ``.house`` file has
no region labels, so it gets no people unless the placement file lists it. A HAPS folder
(motions) and an SMPL model file (skinned bodies) change how people move and look.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from havln_mj.humans.crowd import Crowd
from havln_mj.humans.loaders import load_haps_folder
from havln_mj.humans.population import Sources, populate, populate_ha3d, read_ha3d_placements
from havln_mj.humans.smpl_model import load_smpl_model
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.scan import Scan

PLACEMENTS_ENV = "HAVLN_HA3D_PLACEMENTS"
HAPS_ENV = "HAVLN_HAPS_DIR"
SMPL_ENV = "HAVLN_SMPL_MODEL"


def _given(arg: Path | str | None, env: str) -> Path | None:
    value = arg if arg is not None else os.environ.get(env)
    return Path(value).expanduser() if value else None


class HumanCrowds:
    """Makes the crowd of a scan from ``(scan id, graph, generator)``.

    Args:
        load: Loads a scan by id (the simulator's scene library).
        placements: HA3D placement file (default ``$HAVLN_HA3D_PLACEMENTS``).
        haps: HAPS ``human_motion_meshes`` folder (default ``$HAVLN_HAPS_DIR``).
        smpl_model: SMPL model file, npz or chumpy-free pkl (default ``$HAVLN_SMPL_MODEL``).
        together: Chance that a person placed by HA3D's rule is joined by others.
    """

    def __init__(
        self,
        load: Callable[[str], Scan],
        placements: Path | str | None = None,
        haps: Path | str | None = None,
        smpl_model: Path | str | None = None,
        together: float = 0.0,
    ) -> None:
        self._load = load
        self._together = together
        path = _given(placements, PLACEMENTS_ENV)
        self._placements = read_ha3d_placements(path) if path else {}
        smpl_path, haps_path = _given(smpl_model, SMPL_ENV), _given(haps, HAPS_ENV)
        smpl = load_smpl_model(smpl_path) if smpl_path else None
        motions = load_haps_folder(haps_path, model=smpl) if haps_path else None
        self._sources = Sources(motions, smpl)

    def __call__(self, scan_id: str, graph: NavGraph, rng: np.random.Generator) -> Crowd:
        """The people of ``scan_id``, drawn from ``rng``."""
        entries = self._placements.get(scan_id)
        if entries is not None:
            return populate_ha3d(graph, entries, rng, sources=self._sources)
        return populate(self._load(scan_id), rng, sources=self._sources, together=self._together)
