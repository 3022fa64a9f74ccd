"""Real buildings as scan folders.

Matterport3D meshes are used when the user has them, graph proxies built from the public
connectivity graphs otherwise.

Both are written once into the scan cache; the licensed mesh is referenced by path from
``scan.json``, never copied. A cached folder records what it was built from (the graph's and
the ``.house`` file's contents, the mesh's path, size and time, the builder's version and
parameters; :mod:`havln_mj.scene.cache_keys`): a change to any of them rebuilds it.
"""

from __future__ import annotations

import json
import os
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from havln_mj.cache import atomic_replace_dir, atomic_write_bytes, atomic_write_json, staging_dir
from havln_mj.errors import MissingDataError
from havln_mj.scene.cache_keys import file_digest, params_digest, stat_stamp, write_manifest
from havln_mj.scene.connectivity import check_buildable, read_connectivity
from havln_mj.scene.graph_regions import levels_from_graph
from havln_mj.scene.matterport.house import read_house
from havln_mj.scene.matterport.layout import (
    MatterportFiles,
    find_house_file,
    find_matterport_files,
    resolve_mp3d_root,
)
from havln_mj.scene.mesh import boxes_to_parts, load_mesh_parts, parts_to_trimesh, write_glb
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.proxy.params import ProxyParams
from havln_mj.scene.proxy.routes import write_routes
from havln_mj.scene.scanfolder import BOXES, CONNECTIVITY, META, REGIONS, ROUTES

CONNECTIVITY_ENV = "HAVLN_CONNECTIVITY_DIR"
CONNECTIVITY_HOW_TO = (
    "the 90 public connectivity graphs are the connectivity/ folder of the "
    "Matterport3DSimulator repository (<scan>_connectivity.json); pass --connectivity-dir or "
    f"set {CONNECTIVITY_ENV}"
)
# Bump when proxies or converted scans change: cached ones are rebuilt.
REAL_SCAN_VERSION = 7


def resolve_connectivity_dir(arg: Path | str | None) -> Path | None:
    """``arg``, else ``$HAVLN_CONNECTIVITY_DIR``, else None."""
    value = arg if arg is not None else os.environ.get(CONNECTIVITY_ENV)
    return Path(value).expanduser() if value else None


@dataclass(frozen=True)
class RealScanSources:
    """Where a real building's inputs are: its graph, the user's mesh and ``.house`` file.

    Attributes:
        scan_id: The Matterport scan id.
        connectivity: The ``<scan>_connectivity.json`` file (None when no folder is known).
        root: The Matterport3D root looked in (None when none is known).
        files: The user's Matterport files when the mesh was found.
        house: The ``.house`` file (with or without the mesh), or None.
        mesh_error: Why no mesh was found (for messages), or None.
    """

    scan_id: str
    connectivity: Path | None
    root: Path | None
    files: MatterportFiles | None
    house: Path | None
    mesh_error: MissingDataError | None

    @classmethod
    def find(
        cls,
        scan_id: str,
        mp3d_dir: Path | str | None,
        connectivity_dir: Path | str | None,
        cached: Path | None = None,
    ) -> RealScanSources:
        """Finds the inputs in the given folders, else in those a cached build recorded.

        Args:
            scan_id: The Matterport scan id.
            mp3d_dir: Matterport3D root (default ``$HAVLN_MP3D_DIR``).
            connectivity_dir: Folder of connectivity graphs (default
                ``$HAVLN_CONNECTIVITY_DIR``).
            cached: A cached scan folder whose recorded folders fill in those not given.
        """
        recorded = _read_meta(cached) if cached is not None else {}
        conn_dir = resolve_connectivity_dir(connectivity_dir)
        if conn_dir is None and recorded.get("connectivity"):
            conn_dir = Path(recorded["connectivity"]).parent
        root = resolve_mp3d_root(mp3d_dir)
        if root is None and recorded.get("mp3d_root"):
            root = Path(recorded["mp3d_root"])
        files, mesh_error = None, None
        try:
            files = find_matterport_files(scan_id, root)
        except MissingDataError as exc:
            mesh_error = exc
        return cls(
            scan_id=scan_id,
            connectivity=conn_dir / f"{scan_id}_connectivity.json" if conn_dir else None,
            root=root,
            files=files,
            house=files.house if files else find_house_file(scan_id, root),
            mesh_error=mesh_error,
        )

    def inputs(self) -> dict[str, Any] | None:
        """What the scan folder is derived from, or None when its graph cannot be found.

        See :mod:`havln_mj.scene.cache_keys`.
        """
        if self.connectivity is None or not self.connectivity.is_file():
            return None
        return {
            "kind": "real",
            "version": REAL_SCAN_VERSION,
            "scan_id": self.scan_id,
            "connectivity": file_digest(self.connectivity),
            "house": file_digest(self.house) if self.house else None,
            "mesh": stat_stamp(self.files.mesh) if self.files else None,
            "proxy": None if self.files else params_digest(ProxyParams()),
        }


def _read_meta(folder: Path) -> dict[str, Any]:
    try:
        meta = json.loads((folder / META).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return meta if isinstance(meta, dict) else {}


def build_real_scan(sources: RealScanSources, target: Path) -> None:
    """Writes the scan folder of a real building: its mesh if found, else its graph proxy.

    Raises:
        MissingDataError: Neither the mesh nor the connectivity graph was found; the message
            lists every path looked at and how to get the data.
        MalformedDataError: The graph is no building's (see ``check_buildable``).
        FrameMismatchError: The mesh and the connectivity graph disagree on the frame.
    """
    # Mesh checks and proxy synthesis pull in trimesh and scipy: only when a scan is built.
    from havln_mj.scene.matterport.frame import check_frame
    from havln_mj.scene.proxy.build import build_proxy

    scan_id, conn_path, files = sources.scan_id, sources.connectivity, sources.files
    inputs = sources.inputs()
    if inputs is None or conn_path is None:
        looked = f"looked for {conn_path}" if conn_path else "no connectivity folder was given"
        found = f" The mesh was found at {files.mesh}." if files else ""
        meshes = "" if files else f" Meshes (optional, licensed): {sources.mesh_error}"
        raise MissingDataError(
            f"Matterport3D scan {scan_id!r}: its connectivity graph is needed ({looked})."
            f"{found} Graphs: {CONNECTIVITY_HOW_TO}.{meshes}"
        )
    connectivity = read_connectivity(conn_path)
    check_buildable(connectivity)
    graph = NavGraph(connectivity)
    staging = staging_dir(target)
    try:
        atomic_write_bytes(staging / CONNECTIVITY, conn_path.read_bytes())
        meta = {
            "scene_id": scan_id,
            "version": REAL_SCAN_VERSION,
            "connectivity": str(conn_path.resolve()),
            "mp3d_root": str(sources.root.resolve()) if sources.root else None,
        }
        # Region labels come from the .house file, which a proxy can use without the mesh.
        regions = (
            read_house(sources.house, viewpoint_ids=connectivity.ids)
            if sources.house
            else levels_from_graph(graph)
        )
        if files is not None:
            parts = load_mesh_parts(files.mesh, up=files.up)
            report = check_frame(parts_to_trimesh(parts), connectivity)
            meta.update(
                kind="matterport",
                mesh=str(files.mesh.resolve()),
                layout=files.layout,
                up=files.up,
                frame_check={"checked": report.checked, "agreeing": report.agreeing},
            )
        else:
            proxy = build_proxy(graph, ProxyParams())
            write_glb(boxes_to_parts(proxy.boxes), staging / "mesh.glb")
            proxy.boxes.write(staging / BOXES)
            write_routes(staging / ROUTES, proxy.routes)
            meta.update(
                kind="graph proxy",
                unwalkable_edges=len(proxy.unwalkable),
                edges_by_route=len(proxy.routes),
                edges_by_flight=len(proxy.flights),
                mesh_search=(
                    str(sources.mesh_error).split(". ")[0] if sources.mesh_error else None
                ),
            )
        regions.write(staging / REGIONS)
        atomic_write_json(staging / META, meta, indent=1)
        write_manifest(staging, inputs)
        atomic_replace_dir(staging, target)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
