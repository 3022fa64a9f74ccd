"""Loading scans: one loader for every scan folder, and the cache of built procedural houses."""

from __future__ import annotations

import json
import logging
import shutil
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

from havln_mj.cache import atomic_replace_dir, staging_dir
from havln_mj.errors import MalformedDataError, MissingDataError
from havln_mj.paths import cache_dir
from havln_mj.scene.boxes import BoxSet
from havln_mj.scene.ids import parse_scene_id
from havln_mj.scene.mesh import MeshPart, load_mesh_parts
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.regions import Regions
from havln_mj.scene.scanfolder import BOXES, CONNECTIVITY, MESH_GLB, MESH_OBJ, META, REGIONS

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
        regions: Levels, regions, objects and viewpoint regions (None if the folder has none).
        boxes: Exact box geometry when the folder has ``boxes.json``, else None (the world
            builder then decomposes the mesh with CoACD).
        meta: The folder's ``scan.json`` content.
    """

    scene_id: str
    kind: str
    folder: Path
    mesh_path: Path
    graph: NavGraph
    regions: Regions | None
    boxes: BoxSet | None
    meta: dict[str, Any] = field(default_factory=dict)

    @cached_property
    def mesh_parts(self) -> list[MeshPart]:
        """The visual mesh, one part per material (loaded once)."""
        return load_mesh_parts(self.mesh_path)

    @property
    def description(self) -> str:
        """One line saying what this scan is (printed in run banners and summaries)."""
        source = {"procedural": "procedural house", "matterport": "Matterport3D scan"}.get(
            self.kind, "scan folder"
        )
        g = self.graph
        return f"{self.scene_id} ({source}; {g.num_nodes} viewpoints, {g.num_edges} edges)"


def read_scan_folder(folder: Path, scene_id: str | None = None) -> Scan:
    """Reads a scan folder of the contract (mesh, connectivity, regions, optional boxes).

    Raises:
        MissingDataError: The folder, its mesh or its connectivity file is missing.
        MalformedDataError: A file does not follow its schema.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise MissingDataError(f"scan folder not found: {folder}")
    mesh = next((folder / n for n in (MESH_GLB, MESH_OBJ) if (folder / n).is_file()), None)
    if mesh is None:
        raise MissingDataError(f"scan folder {folder} has no {MESH_GLB} or {MESH_OBJ}")
    meta: dict[str, Any] = {}
    if (folder / META).is_file():
        try:
            meta = json.loads((folder / META).read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise MalformedDataError(f"{folder / META}: invalid JSON ({exc})") from exc
        if not isinstance(meta, dict):
            raise MalformedDataError(f"{folder / META}: expected a JSON object")
    graph = NavGraph.from_file(folder / CONNECTIVITY)
    regions = Regions.read(folder / REGIONS) if (folder / REGIONS).is_file() else None
    boxes = BoxSet.read(folder / BOXES) if (folder / BOXES).is_file() else None
    return Scan(
        scene_id=scene_id or str(meta.get("scene_id", folder.name)),
        kind=str(meta.get("kind", "folder")),
        folder=folder,
        mesh_path=mesh,
        graph=graph,
        regions=regions,
        boxes=boxes,
        meta=meta,
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
        atomic_replace_dir(staging, target)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise


def _procedural_is_current(folder: Path) -> bool:
    from havln_mj.scene.procedural.generate import GENERATOR_VERSION
    from havln_mj.scene.procedural.recipe import load_recipe

    try:
        meta = json.loads((folder / META).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return (
        meta.get("generator_version") == GENERATOR_VERSION
        and meta.get("recipe") == load_recipe().digest
    )


def load_scan(scene: str, *, rebuild: bool = False) -> Scan:
    """Loads a scene by id, building and caching procedural houses on first use.

    Args:
        scene: ``proc-<seed>``, a Matterport scan id with a built scan in the cache, or the
            path of a scan folder.
        rebuild: Regenerate a procedural house even if a cached copy exists.

    Returns:
        The scan.

    Raises:
        UnknownSceneError: ``scene`` is not a valid id (the message gives the valid forms and
            the nearest known id).
        MissingDataError: A Matterport scan that has not been built or supplied.
    """
    sid = parse_scene_id(scene, known_scene_ids())
    if sid.kind == "folder":
        return read_scan_folder(sid.path)
    target = scans_dir() / sid.text
    if sid.kind == "matterport":
        if not target.is_dir():
            raise MissingDataError(
                f"Matterport3D scan {sid.text!r} is not available: no scan folder at {target}. "
                "Supply the scan (mesh, connectivity, regions) as a scan folder there or pass "
                "its folder path as the scene."
            )
        return read_scan_folder(target, sid.text)
    assert sid.seed is not None
    if rebuild or not _procedural_is_current(target):
        _build_procedural(sid.seed, target)
        return _validated(read_scan_folder(target, sid.text))
    try:
        return _validated(read_scan_folder(target, sid.text))
    except (MalformedDataError, MissingDataError) as exc:
        log.warning("cached scan %s is damaged (%s); rebuilding it", target, exc)
        _build_procedural(sid.seed, target)
        return _validated(read_scan_folder(target, sid.text))


def _validated(scan: Scan) -> Scan:
    """Reads the mesh once so a damaged cache entry is caught here, not in the builder."""
    scan.mesh_parts  # noqa: B018 - loads and caches the parts
    return scan
