"""Building a scene ahead of use: its scan folder, collision geometry and compiled world."""

from __future__ import annotations

import time
from pathlib import Path

from havln_mj.scene.scan import load_scan
from havln_mj.sim.world import WorldOptions, build_world


def build_scene(
    scene: str, mp3d_dir: Path | None, connectivity_dir: Path | None, collision: str
) -> dict:
    """Builds one scene and its world (both cached); returns a summary row.

    Args:
        scene: Scene id: ``proc-<seed>``, a Matterport scan id, or a scan folder.
        mp3d_dir: Matterport3D data root (default ``$HAVLN_MP3D_DIR``).
        connectivity_dir: Folder of connectivity graphs (default ``$HAVLN_CONNECTIVITY_DIR``).
        collision: Collision mode of :data:`havln_mj.sim.world.COLLISION_MODES`.
    """
    t0 = time.perf_counter()
    scan = load_scan(scene, mp3d_dir=mp3d_dir, connectivity_dir=connectivity_dir)
    world = build_world(scan, WorldOptions(collision=collision))
    return {
        "scene": scan.scene_id,
        "kind": scan.kind,
        "viewpoints": scan.graph.num_nodes,
        "collision": world.collision,
        "collision_geoms": world.n_collision_geoms,
        "edges_by_route": len(scan.routes),
        "edges_by_flight": scan.meta.get("edges_by_flight"),
        "unwalkable_edges": scan.meta.get("unwalkable_edges"),
        "seconds": round(time.perf_counter() - t0, 2),
    }
