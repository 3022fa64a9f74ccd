"""Which people each scan gets, for the simulator.

Scans listed in an HA3D placement file (``human_motion_text.json``; for the 90 real scans)
get HA3D's people at HA3D's viewpoints; every other scan is populated by HA3D's rule on its
regions (see :mod:`havln_mj.humans.population`). A real (Matterport) scan that the placement
file does not list and whose ``.house`` file cannot be found has no region labels to place
people by: asking for its people raises :class:`~havln_mj.errors.MissingDataError` naming
what would give it some, rather than leaving the building silently empty. A HAPS folder
(motions) and an SMPL model file (skinned bodies) change how people move and look.
:class:`PinnedCrowd` keeps people on the floor points they were placed at.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np

from havln_mj.errors import MissingDataError, UnknownSceneError
from havln_mj.humans.crowd import Crowd
from havln_mj.humans.loaders import load_haps_folder
from havln_mj.humans.population import Sources, populate, populate_ha3d, read_ha3d_placements
from havln_mj.humans.smpl_model import load_smpl_model
from havln_mj.scene.ids import parse_scene_id
from havln_mj.scene.matterport.layout import find_house_file, resolve_mp3d_root
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
        mp3d_dir: The user's Matterport3D root (default ``$HAVLN_MP3D_DIR``), where a real
            scan's ``.house`` file (its region labels) is looked for.
    """

    def __init__(
        self,
        load: Callable[[str], Scan],
        placements: Path | str | None = None,
        haps: Path | str | None = None,
        smpl_model: Path | str | None = None,
        together: float = 0.0,
        mp3d_dir: Path | str | None = None,
    ) -> None:
        self._load = load
        self._together = together
        self._mp3d_dir = mp3d_dir
        path = _given(placements, PLACEMENTS_ENV)
        self.placements_file = path
        self._placements = read_ha3d_placements(path) if path else {}
        smpl_path, haps_path = _given(smpl_model, SMPL_ENV), _given(haps, HAPS_ENV)
        smpl = load_smpl_model(smpl_path) if smpl_path else None
        motions = load_haps_folder(haps_path, model=smpl) if haps_path else None
        self._sources = Sources(motions, smpl)

    def source(self, scan_id: str) -> str:
        """Where the people of ``scan_id`` come from, in words (for banners and reports).

        Raises:
            MissingDataError: A real scan with no placements and no region labels.
        """
        if scan_id in self._placements:
            return f"HA3D placements ({self.placements_file})"
        self._check_regions(scan_id)
        return "HA3D's rule on the scan's regions (one person per 67 m², ≥ 3 m apart)"

    def _check_regions(self, scan_id: str) -> None:
        """Raises unless ``scan_id`` has region labels or is not a real scan."""
        try:
            kind = parse_scene_id(scan_id).kind
        except UnknownSceneError:
            return  # the scene library reports bad ids
        if kind != "matterport" or find_house_file(scan_id, resolve_mp3d_root(self._mp3d_dir)):
            return
        listed = (
            f"the placement file {self.placements_file} does not list it"
            if self.placements_file
            else "no HA3D placement file was given"
        )
        raise MissingDataError(
            f"scan {scan_id!r} has nobody to place: {listed}, and without its Matterport3D "
            ".house file its graph has no region labels for HA3D's placement rule. Give HA3D's "
            "placements (human_motion_text.json: --human-placements, "
            f"Simulator(human_placements=...) or ${PLACEMENTS_ENV}), the scan's .house file "
            "(--mp3d-dir or $HAVLN_MP3D_DIR), or run without people (--no-people, "
            "humans=False)"
        )

    def __call__(self, scan_id: str, graph: NavGraph, rng: np.random.Generator) -> Crowd:
        """The people of ``scan_id``, drawn from ``rng``.

        Raises:
            MissingDataError: A real scan with no placements and no region labels.
        """
        entries = self._placements.get(scan_id)
        if entries is not None:
            return populate_ha3d(graph, entries, rng, sources=self._sources)
        self._check_regions(scan_id)
        return populate(self._load(scan_id), rng, sources=self._sources, together=self._together)


class PinnedCrowd:
    """A crowd whose people keep to their anchors: each pelvis stays above its floor point.

    People still play their motions, in place (a walker walks on the spot); what moves them
    about the room is taken out. HA3D's people barely leave the viewpoints they were placed
    at; with this, the collision signal and the drawings agree on that. Satisfies
    :class:`havln_mj.sim.crowd.Crowd` (and keeps ``people``, whose anchors the HA3D distance
    reads).

    Args:
        crowd: The people (:class:`havln_mj.humans.crowd.Crowd`).
    """

    def __init__(self, crowd: Crowd) -> None:
        self.crowd = crowd
        self.people = crowd.people
        self._anchor_xy = np.array([p.anchor[:2] for p in crowd.people], float).reshape(-1, 2)

    def __len__(self) -> int:
        return len(self.crowd)

    @property
    def shapes(self) -> list:
        """Each person's body."""
        return self.crowd.shapes

    @property
    def skins(self) -> list:
        """Each person's skin (or None)."""
        return self.crowd.skins

    def positions(self, times: np.ndarray, people: np.ndarray | None = None) -> np.ndarray:
        """Pelvis positions ``(len(times), P, 3)``: the anchors' x, y at the motion's height."""
        out = np.array(self.crowd.positions(times, people), float)
        out[..., :2] = self._anchor_xy if people is None else self._anchor_xy[people]
        return out

    def footprint(self) -> tuple[np.ndarray, np.ndarray]:
        """Each pelvis never leaves its anchor."""
        return self._anchor_xy, np.zeros(len(self._anchor_xy))

    def _shift(self, t: float) -> np.ndarray:
        """``(P, 3)``: what moves each pelvis from where its motion puts it to its anchor."""
        shift = np.zeros((len(self), 3))
        shift[:, :2] = self._anchor_xy - self.crowd.positions(np.array([float(t)]))[0][:, :2]
        return shift

    def pose(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """World joint positions and orientations at ``t``, each body moved onto its anchor."""
        joints, quats = self.crowd.pose(t)
        return joints + self._shift(t)[:, None], quats

    def skin_vertices(self, t: float) -> dict:
        """Skinned people's world vertices at ``t``, moved as :meth:`pose` moves them."""
        shift = self._shift(t)
        return {k: v + shift[k] for k, v in self.crowd.skin_vertices(t).items()}

    def states(self, t: float) -> list:
        """Each person's state at ``t``, on their anchor and not going anywhere."""
        shift = self._shift(t)
        out = []
        for k, s in enumerate(self.crowd.states(t)):
            velocity = np.array(s.velocity, float)
            velocity[:2] = 0.0
            out.append(replace(s, position=np.asarray(s.position) + shift[k], velocity=velocity))
        return out
