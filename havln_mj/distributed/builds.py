"""``havln_mj scenes build`` as Ray tasks: every scene is built on some node of the cluster."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from havln_mj.distributed._ray import ensure_ray


def build_scenes_ray(
    scene_ids: Sequence[str],
    *,
    mp3d_dir: Path | None = None,
    connectivity_dir: Path | None = None,
    collision: str = "auto",
    address: str | None = None,
    num_cpus: float = 1,
) -> list[dict]:
    """Builds scenes as Ray tasks, one per scene, with :func:`havln_mj.sim.prebuild.build_scene`.

    Each task builds the scan, its collision geometry (CoACD hulls where ``collision`` asks
    for them) and its world.

    The caches are written on the node that runs each task; on a cluster give the nodes a
    shared cache folder (``$HAVLN_CACHE`` / the scans folder) so later runs find them.

    Returns:
        One row per scene, in the order of ``scene_ids``: ``build_scene``'s summary, or
        ``{"scene": id, "error": message}`` for a scene that failed.
    """
    ray = ensure_ray(address)
    from havln_mj.sim.prebuild import build_scene

    def build(scene: str) -> dict:
        try:
            return build_scene(scene, mp3d_dir, connectivity_dir, collision)
        except Exception as exc:
            return {"scene": scene, "error": f"{type(exc).__name__}: {exc}"}

    task = ray.remote(num_cpus=num_cpus)(build)
    return ray.get([task.remote(s) for s in scene_ids])
