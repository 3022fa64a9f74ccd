"""Real buildings as scan folders.

Matterport3D meshes are used when the user has them, graph proxies built from the public
connectivity graphs otherwise.

Both are written once into the scan cache; the licensed mesh is referenced by path from
``scan.json``, never copied.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np

from havln_mj.cache import atomic_replace_dir, atomic_write_bytes, atomic_write_json, staging_dir
from havln_mj.errors import MissingDataError
from havln_mj.scene.connectivity import read_connectivity
from havln_mj.scene.matterport.house import read_house
from havln_mj.scene.matterport.layout import (
    find_house_file,
    find_matterport_files,
    resolve_mp3d_root,
)
from havln_mj.scene.mesh import boxes_to_parts, load_mesh_parts, parts_to_trimesh, write_glb
from havln_mj.scene.navgraph import NavGraph, level_groups
from havln_mj.scene.proxy.routes import write_routes
from havln_mj.scene.regions import Level, Region, Regions
from havln_mj.scene.scanfolder import BOXES, CONNECTIVITY, META, REGIONS, ROUTES

CONNECTIVITY_ENV = "HAVLN_CONNECTIVITY_DIR"
CONNECTIVITY_HOW_TO = (
    "the 90 public connectivity graphs are the connectivity/ folder of the "
    "Matterport3DSimulator repository (<scan>_connectivity.json); pass --connectivity-dir or "
    f"set {CONNECTIVITY_ENV}"
)
# Bump when proxies or converted scans change: cached ones are rebuilt.
REAL_SCAN_VERSION = 5


def resolve_connectivity_dir(arg: Path | str | None) -> Path | None:
    """``arg``, else ``$HAVLN_CONNECTIVITY_DIR``, else None."""
    value = arg if arg is not None else os.environ.get(CONNECTIVITY_ENV)
    return Path(value).expanduser() if value else None


def _levels_from_graph(graph: NavGraph) -> Regions:
    """One unlabelled region per storey (``level_groups``) when no ``.house`` file is found."""
    levels, regions, vp_region = [], [], {}
    for k, members in enumerate(level_groups(graph)):
        z = float(np.median([graph.floor_z(v) for v in members]))
        xy = np.array([graph.position(v)[:2] for v in members])
        lo, hi = xy.min(axis=0) - 1.0, xy.max(axis=0) + 1.0
        levels.append(Level(k, z, z + 2.5))
        polygon = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
        bbox = np.array([lo[0], lo[1], z, hi[0], hi[1], z + 2.5])
        regions.append(Region(k, k, "-", polygon, bbox, 2.5))
        vp_region.update({v: k for v in members})
    return Regions(tuple(levels), tuple(regions), (), vp_region)


def build_real_scan(
    scan_id: str, target: Path, mp3d_dir: Path | str | None, connectivity_dir: Path | str | None
) -> None:
    """Writes the scan folder of a real building: its mesh if found, else its graph proxy.

    Raises:
        MissingDataError: Neither the mesh nor the connectivity graph was found; the message
            lists every path looked at and how to get the data.
        FrameMismatchError: The mesh and the connectivity graph disagree on the frame.
    """
    # Mesh checks and proxy synthesis pull in trimesh and scipy: only when a scan is built.
    from havln_mj.scene.matterport.frame import check_frame
    from havln_mj.scene.proxy.build import ProxyParams, build_proxy

    conn_dir = resolve_connectivity_dir(connectivity_dir)
    conn_path = conn_dir / f"{scan_id}_connectivity.json" if conn_dir else None
    root = resolve_mp3d_root(mp3d_dir)
    files, mesh_error = None, None
    try:
        files = find_matterport_files(scan_id, root)
    except MissingDataError as exc:
        mesh_error = exc
    if conn_path is None or not conn_path.is_file():
        looked = f"looked for {conn_path}" if conn_path else "no connectivity folder was given"
        found = f" The mesh was found at {files.mesh}." if files else ""
        meshes = "" if files else f" Meshes (optional, licensed): {mesh_error}"
        raise MissingDataError(
            f"Matterport3D scan {scan_id!r}: its connectivity graph is needed ({looked})."
            f"{found} Graphs: {CONNECTIVITY_HOW_TO}.{meshes}"
        )
    connectivity = read_connectivity(conn_path)
    graph = NavGraph(connectivity)
    staging = staging_dir(target)
    try:
        atomic_write_bytes(staging / CONNECTIVITY, conn_path.read_bytes())
        meta = {
            "scene_id": scan_id,
            "version": REAL_SCAN_VERSION,
            "connectivity": str(conn_path.resolve()),
        }
        # Region labels come from the .house file, which a proxy can use without the mesh.
        house = files.house if files else find_house_file(scan_id, root)
        regions = (
            read_house(house, viewpoint_ids=connectivity.ids)
            if house
            else _levels_from_graph(graph)
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
                mesh_search=str(mesh_error).split(". ")[0] if mesh_error else None,
            )
        regions.write(staging / REGIONS)
        atomic_write_json(staging / META, meta, indent=1)
        atomic_replace_dir(staging, target)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise


def real_scan_is_current(
    folder: Path, mp3d_dir: Path | str | None, connectivity_dir: Path | str | None
) -> bool:
    """Whether a cached real scan matches the data the user points at now.

    It is stale when built by another version, from another connectivity file, from another
    mesh than the one the given Matterport root holds, or as a proxy once a mesh is found.
    """
    try:
        meta = json.loads((folder / META).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    if meta.get("version") != REAL_SCAN_VERSION:
        return False
    conn_dir = resolve_connectivity_dir(connectivity_dir)
    if conn_dir is not None:
        conn = (conn_dir / f"{meta.get('scene_id')}_connectivity.json").resolve()
        if str(conn) != meta.get("connectivity"):
            return False
    root = resolve_mp3d_root(mp3d_dir)
    try:
        mesh = str(find_matterport_files(meta.get("scene_id", ""), root).mesh.resolve())
    except MissingDataError:
        mesh = None
    if meta.get("kind") == "matterport":
        if root is None:  # nothing new to compare with: keep it while its mesh is there
            return Path(meta.get("mesh", "")).is_file()
        return mesh == meta.get("mesh")
    return mesh is None
