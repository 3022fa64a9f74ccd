"""Top-down maps: floor plan (regions, a horizontal section of the mesh), graph, paths, people."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import trimesh
from matplotlib.collections import LineCollection
from matplotlib.patches import Circle, Polygon, Rectangle

from havln_mj.nav import NavGrid
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.regions import Regions

_PATH_COLOURS = ("#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b")


def section_segments(mesh: trimesh.Trimesh, z: float) -> np.ndarray:
    """(S, 2, 2) plan-view segments where the plane at height ``z`` cuts the mesh."""
    lines = trimesh.intersections.mesh_plane(mesh, plane_normal=[0, 0, 1], plane_origin=[0, 0, z])
    return np.asarray(lines)[:, :, :2].reshape(-1, 2, 2)


def draw_topdown(
    path: Path,
    graph: NavGraph,
    regions: Regions | None,
    mesh: trimesh.Trimesh | None,
    paths: Sequence[Sequence[str]] = (),
    level_floor: float = 0.0,
    title: str = "",
    navgrid: NavGrid | None = None,
    people: np.ndarray | None = None,
) -> None:
    """Writes a PNG map of one level.

    Args:
        path: Output PNG path.
        graph: Navigation graph (nodes and edges are drawn).
        regions: Regions to fill and label, and objects to draw, if known.
        mesh: Building mesh, cut 1 m above ``level_floor`` to draw walls and furniture.
        paths: Viewpoint-id paths to highlight (start ○, goal ★).
        level_floor: Floor height of the level drawn; viewpoints of other levels are skipped.
        title: Figure title.
        navgrid: Navigability grid of the level, shaded under the plan (blocked cells red
            where only the robot's radius blocks them, grey where geometry is).
        people: Pelvis positions ``(N, 3)`` of people to mark, each with its 1 m collision
            circle (those on other levels are skipped).
    """
    fig, ax = plt.subplots(figsize=(9, 9), dpi=110)
    cmap = plt.get_cmap("tab20")
    if navgrid is not None:
        image, extent = navgrid.image(alpha=110)
        ax.imshow(image, origin="lower", extent=extent, zorder=0, interpolation="nearest")
    if regions is not None:
        labels = sorted({r.label for r in regions.regions})
        for rg in regions.regions:
            if abs(regions.levels[rg.level].z_floor - level_floor) > 0.5:
                continue
            colour = cmap(labels.index(rg.label) % 20)
            ax.add_patch(Polygon(rg.polygon, closed=True, fc=(*colour[:3], 0.25), ec="none"))
            cx, cy = rg.polygon.mean(axis=0)
            ax.text(cx, cy, rg.name, ha="center", va="center", fontsize=7, alpha=0.8)
        for ob in regions.objects:
            if abs(ob.bbox[2] - level_floor) < 0.5:
                x0, y0, _, x1, y1, _ = ob.bbox
                ax.add_patch(
                    Rectangle((x0, y0), x1 - x0, y1 - y0, fc="0.55", ec="0.35", alpha=0.5, lw=0.5)
                )
    if mesh is not None:
        ax.add_collection(
            LineCollection(section_segments(mesh, level_floor + 1.0), colors="0.25", lw=1.0)
        )
    nodes = [n for n in graph.nodes if abs(graph.floor_z(n) - level_floor) < 0.5]
    pos = {n: graph.position(n) for n in nodes}
    edges = [(pos[a][:2], pos[b][:2]) for a, b, _ in graph.edges() if a in pos and b in pos]
    ax.add_collection(LineCollection(edges, colors="0.6", lw=0.6))
    xy = np.array([pos[n][:2] for n in nodes]).reshape(-1, 2)
    ax.scatter(xy[:, 0], xy[:, 1], s=8, c="0.3", zorder=3)
    for k, p in enumerate(paths):
        pts = np.array([graph.position(v)[:2] for v in p])
        c = _PATH_COLOURS[k % len(_PATH_COLOURS)]
        ax.plot(pts[:, 0], pts[:, 1], "-", c=c, lw=2.2, zorder=4)
        ax.plot(*pts[0], "o", c=c, ms=9, mfc="white", mew=2, zorder=5)
        ax.plot(*pts[-1], "*", c=c, ms=14, zorder=5)
    if people is not None:
        for x, y, z in np.asarray(people).reshape(-1, 3):
            if -0.2 < z - level_floor < 1.6:
                ax.add_patch(Circle((x, y), 1.0, fc=(1.0, 0.5, 0.0, 0.15), ec="#ff7f0e", lw=0.8))
                ax.plot(x, y, "P", c="#ff7f0e", ms=9, mec="black", mew=0.6, zorder=6)
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if title:
        ax.set_title(title)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
