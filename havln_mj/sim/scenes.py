"""Scan ids to navigation tables and rendered worlds, loaded on first use and cached.

With rendering off only navigation graphs are needed: a Matterport scan id reads
``<scan>_connectivity.json`` from the navigation-graph folder and nothing else (no mesh, no
proxy), so all 90 real graphs load in a second. A procedural id (``proc-<seed>``) or a scan
folder goes through ``load_scan``. With rendering on, every scan is loaded with
``load_scan`` (the user's mesh, else a graph proxy) and its world is built once; worlds are
kept in a least-recently-used cache of ``cache_size`` scans. A loaded scan's navigation table
carries the edges its body walks by a route (graph proxies); a real scan id with rendering
off has no proxy, and every edge is walked straight, as in MatterSim.
"""

from __future__ import annotations

from collections import OrderedDict
from pathlib import Path

from havln_mj.errors import UnknownScanError, UnknownSceneError, did_you_mean
from havln_mj.scene.ids import parse_scene_id
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.realscan import CONNECTIVITY_HOW_TO, resolve_connectivity_dir
from havln_mj.scene.scan import Scan, known_scene_ids, load_scan
from havln_mj.sim.crowd import NO_CROWD, Crowd
from havln_mj.sim.navigation import NavTable
from havln_mj.sim.rendering import SceneView, ViewSettings
from havln_mj.sim.world import WorldOptions


class SceneLibrary:
    """The scans one simulator uses.

    Args:
        connectivity_dir: Folder of ``<scan>_connectivity.json`` (default
            ``$HAVLN_CONNECTIVITY_DIR``).
        mp3d_dir: Root of the user's Matterport3D data (default ``$HAVLN_MP3D_DIR``).
        rendering: Whether worlds will be rendered (real scans then load through
            ``load_scan``).
        cache_size: How many built worlds to keep.
        world_options: How worlds are built.
    """

    def __init__(
        self,
        connectivity_dir: Path | str | None,
        mp3d_dir: Path | str | None,
        rendering: bool,
        cache_size: int,
        world_options: WorldOptions,
    ) -> None:
        self._conn_dir = resolve_connectivity_dir(connectivity_dir)
        self._mp3d_dir = mp3d_dir
        self._rendering = rendering
        self._cache_size = max(1, cache_size)
        self._world_options = world_options
        self._tables: dict[str, NavTable] = {}
        self._scans: dict[str, Scan] = {}
        self._views: OrderedDict[str, SceneView] = OrderedDict()

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
            graph = self._graph(scan_id)
            # A loaded scan's body walks some edges by a route (graph proxies); a bare graph
            # (a real scan id with rendering off) is MatterSim's: every edge straight.
            scan = self._scans.get(scan_id)
            routes = scan.routes if scan is not None and scan.graph is graph else None
            table = NavTable(scan_id, graph, routes)
            self._tables[scan_id] = table
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
            if not self._rendering:
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

    def view(self, scan_id: str, settings: ViewSettings, crowd: Crowd = NO_CROWD) -> SceneView:
        """The renderable world of ``scan_id`` with ``crowd``'s people, set to ``settings``."""
        view = self._views.get(scan_id)
        if view is None:
            view = SceneView(self.scan(scan_id), self._world_options, crowd)
            self._views[scan_id] = view
            while len(self._views) > self._cache_size:
                _, old = self._views.popitem(last=False)
                old.close()
        else:
            self._views.move_to_end(scan_id)
        view.configure(settings)
        return view

    def close(self) -> None:
        """Releases every world's renderer."""
        for view in self._views.values():
            view.close()
        self._views.clear()
