"""Scan ids to navigation tables and scans, loaded on first use and cached.

A Matterport scan id's graph is always read from ``<scan>_connectivity.json`` in the
navigation-graph folder, in every mode, so navigable locations never depend on rendering; the
scan itself (the user's mesh, else a graph proxy) is loaded only when something needs its
geometry (rendering, a legged body). All 90 real graphs load in a second. A procedural id
(``proc-<seed>``) or a scan folder goes through ``load_scan`` for its graph too.
"""

from __future__ import annotations

from pathlib import Path

from havln_mj.errors import UnknownScanError, UnknownSceneError, did_you_mean
from havln_mj.scene.ids import parse_scene_id
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.realscan import CONNECTIVITY_HOW_TO, resolve_connectivity_dir
from havln_mj.scene.scan import Scan, known_scene_ids, load_scan
from havln_mj.sim.navigation import NavTable


class SceneLibrary:
    """The scans one simulator uses.

    Args:
        connectivity_dir: Folder of ``<scan>_connectivity.json`` (default
            ``$HAVLN_CONNECTIVITY_DIR``).
        mp3d_dir: Root of the user's Matterport3D data (default ``$HAVLN_MP3D_DIR``).
    """

    def __init__(self, connectivity_dir: Path | str | None, mp3d_dir: Path | str | None) -> None:
        self._conn_dir = resolve_connectivity_dir(connectivity_dir)
        self._mp3d_dir = mp3d_dir
        self._tables: dict[str, NavTable] = {}
        self._scans: dict[str, Scan] = {}

    def connectivity_ids(self) -> list[str]:
        """Scan ids listed in the navigation-graph folder (``scans.txt``, else its files)."""
        if self._conn_dir is None or not self._conn_dir.is_dir():
            return []
        listing = self._conn_dir / "scans.txt"
        if listing.is_file():
            return listing.read_text().split()
        files = self._conn_dir.glob("*_connectivity.json")
        return sorted(p.name.removesuffix("_connectivity.json") for p in files)

    def table(self, scan_id: str) -> NavTable:
        """The navigation table of ``scan_id``.

        Raises:
            UnknownScanError: No graph can be found for ``scan_id`` (an ``IndexError``, as
                MatterSim raises); the message says where it looked.
        """
        table = self._tables.get(scan_id)
        if table is None:
            table = self._tables[scan_id] = NavTable(scan_id, self._graph(scan_id))
        return table

    def _graph(self, scan_id: str) -> NavGraph:
        known = self.connectivity_ids()
        try:
            sid = parse_scene_id(scan_id, known + known_scene_ids())
        except UnknownSceneError as exc:
            raise UnknownScanError(str(exc)) from None
        if sid.kind == "matterport":
            path = self._conn_dir / f"{scan_id}_connectivity.json" if self._conn_dir else None
            if path is None or not path.is_file():
                where = f"looked for {path}" if path else "no navigation-graph folder is set"
                raise UnknownScanError(
                    f"unknown scan {scan_id!r}: {where} (setNavGraphPath). "
                    f"Graphs: {CONNECTIVITY_HOW_TO}.{did_you_mean(scan_id, known)}"
                )
            return NavGraph.from_file(path)
        return self.scan(scan_id).graph

    def scan(self, scan_id: str) -> Scan:
        """The loaded scan (built and cached on first use)."""
        scan = self._scans.get(scan_id)
        if scan is None:
            try:
                scan = load_scan(scan_id, mp3d_dir=self._mp3d_dir, connectivity_dir=self._conn_dir)
            except UnknownSceneError as exc:
                raise UnknownScanError(str(exc)) from None
            self._scans[scan_id] = scan
        return scan
