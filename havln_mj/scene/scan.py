"""Loading scans: one loader for every scan folder, and the cache of built scans.

A built scan (procedural house, converted Matterport scan, graph proxy) is used from the cache
only when it is whole and was built from the inputs the scene would be built from now
(:mod:`havln_mj.scene.cache_keys`); otherwise it is rebuilt, with a warning when it was damaged.
"""

from __future__ import annotations

import json
import logging
import shutil
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

from havln_mj.cache import atomic_replace_dir, staging_dir
from havln_mj.errors import MalformedDataError, MissingDataError
from havln_mj.paths import cache_dir
from havln_mj.scene.boxes import BoxSet
from havln_mj.scene.cache_keys import read_manifest, write_manifest
from havln_mj.scene.graph_regions import levels_from_graph
from havln_mj.scene.ids import parse_scene_id
from havln_mj.scene.navgraph import NavGraph, level_groups
from havln_mj.scene.proxy.routes import Route, read_routes
from havln_mj.scene.regions import Regions
from havln_mj.scene.scanfolder import (
    BOXES,
    CONNECTIVITY,
    MANIFEST,
    MESH_GLB,
    MESH_OBJ,
    META,
    REGIONS,
    ROUTES,
)

if TYPE_CHECKING:
    import trimesh

    from havln_mj.scene.mesh import MeshPart
    from havln_mj.scene.rooms import RoomPlan

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Scan:
    """A building: its mesh, navigation graph, regions and (for procedural houses) exact boxes.

    Attributes:
        scene_id: ``proc-<seed>``, a Matterport scan id, or the folder name.
        kind: ``"procedural"``, ``"matterport"`` or ``"folder"``.
        folder: The scan folder.
        mesh_path: The visual mesh (``mesh.glb`` or ``mesh.obj``).
        graph: The navigation graph.
        regions: Levels, regions, objects and viewpoint regions (one unlabelled region per
            storey when the folder has no regions file).
        boxes: Exact box geometry when the folder has ``boxes.json``, else None (the world
            builder then decomposes the mesh with CoACD).
        meta: The folder's ``scan.json`` content.
        routes: Edges a body walks by a route rather than straight (``routes.json``; graph
            proxies), as ``(a, b) -> (a, ..., b)`` through viewpoints or floor points.
    """

    scene_id: str
    kind: str
    folder: Path
    mesh_path: Path
    graph: NavGraph
    regions: Regions | None
    boxes: BoxSet | None
    meta: dict[str, Any] = field(default_factory=dict)
    routes: dict[tuple[str, str], Route] = field(default_factory=dict)

    def route(self, a: str, b: str) -> Route | None:
        """The stops a body walks through from ``a`` to ``b``, or None when straight."""
        if (a, b) in self.routes:
            return self.routes[(a, b)]
        if (b, a) in self.routes:
            return self.routes[(b, a)][::-1]
        return None

    @cached_property
    def mesh_parts(self) -> list[MeshPart]:
        """The visual mesh, one part per material (loaded once)."""
        from havln_mj.scene.mesh import load_mesh_parts  # trimesh: only when meshes are read

        return load_mesh_parts(self.mesh_path, up=str(self.meta.get("up", "z")))

    @cached_property
    def room_plan(self) -> RoomPlan | None:
        """Its rooms and the portals between them, where it is one storey of rectangles."""
        from havln_mj.scene.rooms import room_plan

        return room_plan(self.regions, self.boxes)

    @cached_property
    def mesh(self) -> trimesh.Trimesh:
        """All mesh parts merged into one mesh (for sections, slices and decomposition)."""
        from havln_mj.scene.mesh import parts_to_trimesh

        return parts_to_trimesh(self.mesh_parts)

    @property
    def description(self) -> str:
        """One line saying what this scan is (printed in run banners and summaries)."""
        source = {
            "procedural": "procedural house",
            "matterport": "Matterport3D scan",
            "graph proxy": "graph proxy synthesised from the navigation graph, NOT the real mesh",
        }.get(self.kind, "scan folder")
        g = self.graph
        return f"{self.scene_id} ({source}; {g.num_nodes} viewpoints, {g.num_edges} edges)"


def floor_heights(scan: Scan) -> list[float]:
    """Floor heights of a building's levels, lowest first.

    From the scan's regions when it has levels; otherwise the viewpoints' floor heights,
    grouped by ``level_groups`` (each level at its lowest viewpoint floor).

    Raises:
        MalformedDataError: The scan has neither levels nor viewpoints.
    """
    if scan.regions is not None and scan.regions.levels:
        return sorted(float(lv.z_floor) for lv in scan.regions.levels)
    groups = level_groups(scan.graph)
    if not groups:
        raise MalformedDataError(f"scan {scan.scene_id!r} has no levels and no viewpoints")
    return [scan.graph.floor_z(g[0]) for g in groups]


def read_scan_folder(folder: Path, scene_id: str | None = None) -> Scan:
    """Reads a scan folder of the contract (mesh, connectivity, regions, optional boxes).

    Raises:
        MissingDataError: The folder, its mesh or its connectivity file is missing.
        MalformedDataError: A file does not follow its schema.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise MissingDataError(f"scan folder not found: {folder}")
    meta: dict[str, Any] = {}
    if (folder / META).is_file():
        try:
            meta = json.loads((folder / META).read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise MalformedDataError(f"{folder / META}: invalid JSON ({exc})") from exc
        if not isinstance(meta, dict):
            raise MalformedDataError(f"{folder / META}: expected a JSON object")
    # A converted Matterport scan names the user's mesh instead of holding a copy.
    candidates = [folder / MESH_GLB, folder / MESH_OBJ]
    if "mesh" in meta:
        candidates.insert(0, Path(meta["mesh"]))
    mesh = next((m for m in candidates if m.is_file()), None)
    if mesh is None:
        raise MissingDataError(
            f"scan folder {folder} has no mesh: looked for {', '.join(map(str, candidates))}"
        )
    graph = NavGraph.from_file(folder / CONNECTIVITY)
    if (folder / REGIONS).is_file():
        regions = Regions.read(folder / REGIONS)
    else:
        log.warning(
            "scan folder %s has no %s: using one unlabelled region per storey, so people are "
            "placed only from a placement file",
            folder,
            REGIONS,
        )
        regions = levels_from_graph(graph)
    boxes = BoxSet.read(folder / BOXES) if (folder / BOXES).is_file() else None
    routes = read_routes(folder / ROUTES)
    return Scan(
        scene_id=scene_id or str(meta.get("scene_id", folder.name)),
        kind=str(meta.get("kind", "folder")),
        folder=folder,
        mesh_path=mesh,
        graph=graph,
        regions=regions,
        boxes=boxes,
        meta=meta,
        routes=routes,
    )


def scans_dir() -> Path:
    """Where built scans are cached: ``$HAVLN_CACHE/scans``."""
    return cache_dir("scans")


def known_scene_ids() -> list[str]:
    """Scene ids with a built scan in the cache (for "did you mean" suggestions)."""
    return sorted(
        p.name for p in scans_dir().iterdir() if p.is_dir() and not p.name.startswith(".")
    )


def _build_procedural(seed: int, target: Path) -> None:
    # Imported here: generation pulls in the whole generator, which cached loads never need.
    from havln_mj.scene.procedural.generate import generate_house, write_scan

    staging = staging_dir(target)
    try:
        write_scan(generate_house(seed), staging)
        write_manifest(staging, _procedural_inputs(seed))
        atomic_replace_dir(staging, target)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise


def _procedural_inputs(seed: int) -> dict[str, Any]:
    """What a procedural house is derived from: seed, generator, recipe, material library."""
    from havln_mj.scene.procedural.generate import GENERATOR_VERSION
    from havln_mj.scene.procedural.materials import library_digest
    from havln_mj.scene.procedural.recipe import load_recipe

    return {
        "kind": "procedural",
        "seed": seed,
        "generator_version": GENERATOR_VERSION,
        "recipe": load_recipe().digest,
        "materials": library_digest(),
    }


def load_scan(
    scene: str,
    *,
    rebuild: bool = False,
    mp3d_dir: Path | str | None = None,
    connectivity_dir: Path | str | None = None,
) -> Scan:
    """Loads a scene by id, building and caching it on first use.

    A cached scan is used only when it is whole (every file as written) and was built from the
    inputs the scene would be built from now (:mod:`havln_mj.scene.cache_keys`); otherwise it
    is rebuilt, with a warning when it was damaged.

    Args:
        scene: ``proc-<seed>``, a Matterport scan id, or the path of a scan folder.
        rebuild: Rebuild the cached scan even if it is current.
        mp3d_dir: Root of the user's Matterport3D data (raw or habitat layout); default
            ``$HAVLN_MP3D_DIR``, else the root the cached scan was built from.
        connectivity_dir: Folder of ``<scan>_connectivity.json`` graphs; default
            ``$HAVLN_CONNECTIVITY_DIR``, else the folder the cached scan was built from.

    Returns:
        The scan. A Matterport scan uses the user's mesh when found, else a graph proxy.

    Raises:
        UnknownSceneError: ``scene`` is not a valid id (the message gives the valid forms and
            the nearest known id).
        MissingDataError: A Matterport scan whose graph (and mesh) cannot be found; the message
            says where it looked and how to get the data.
        MalformedDataError: A Matterport graph no building can be built around.
    """
    sid = parse_scene_id(scene, known_scene_ids())
    if sid.kind == "folder":
        return read_scan_folder(sid.path)
    target = scans_dir() / sid.text
    if sid.kind == "matterport":
        from havln_mj.scene.realscan import RealScanSources, build_real_scan

        sources = RealScanSources.find(sid.text, mp3d_dir, connectivity_dir, target)
        return _cached(
            target, sid.text, sources.inputs(), lambda: build_real_scan(sources, target), rebuild
        )
    assert sid.seed is not None
    seed = sid.seed
    return _cached(
        target, sid.text, _procedural_inputs(seed), lambda: _build_procedural(seed, target), rebuild
    )


def _cached(
    target: Path,
    scene_id: str,
    inputs: dict[str, Any] | None,
    build: Callable[[], None],
    rebuild: bool,
) -> Scan:
    """The scan cached at ``target``, (re)built first unless whole and built from ``inputs``.

    ``inputs`` None (they cannot be found now) accepts any whole cached scan.
    """
    if not rebuild and target.is_dir():
        try:
            built_from = read_manifest(target)
            if inputs is None or built_from == json.loads(json.dumps(inputs)):
                return _cross_checked(read_scan_folder(target, scene_id))
            log.info("cached scan %s was built from other inputs; rebuilding it", target)
        except (MalformedDataError, MissingDataError) as exc:
            if (target / MANIFEST).is_file():
                log.warning("cached scan %s is damaged (%s); rebuilding it", target, exc)
            else:
                log.info("cached scan %s has no manifest (%s); rebuilding it", target, exc)
    build()
    return _cross_checked(read_scan_folder(target, scene_id))


def _cross_checked(scan: Scan) -> Scan:
    """A built scan whose files agree with each other (else MalformedDataError)."""
    where = f"cached scan {scan.folder}"
    if scan.kind in ("procedural", "graph proxy") and scan.boxes is None:
        raise MalformedDataError(f"{where}: a {scan.kind} needs its {BOXES}")
    ids = set(scan.graph.ids)
    assert scan.regions is not None  # read_scan_folder always gives regions
    stray = sorted(set(scan.regions.viewpoint_region) - ids)
    if stray:
        raise MalformedDataError(
            f"{where}: {REGIONS} names viewpoints not in the graph: {stray[:3]}"
        )
    unknown = sorted({v for edge in scan.routes for v in edge} - ids)
    if unknown:
        raise MalformedDataError(
            f"{where}: {ROUTES} names viewpoints not in the graph: {unknown[:3]}"
        )
    return scan
