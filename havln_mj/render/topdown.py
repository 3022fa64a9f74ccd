"""Top-down maps: floor plan, graph, planned and walked paths, people, collisions, a legend.

One level of a building is drawn in plan view (metres, Matterport frame): rooms filled by
region and named, furniture boxes, walls (a horizontal section of the mesh 1 m above the
floor), the navigation graph, each episode's planned path (start ○, goal ★) and beside it
the track actually walked, people with their 1 m collision circles and their tracks over the
episode, and where the agent collided with someone. A legend explains every mark shown, the
figure takes the map's aspect ratio with tight margins, and long titles wrap.
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import trimesh
from matplotlib.collections import LineCollection
from matplotlib.legend_handler import HandlerTuple
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Patch, Polygon, Rectangle

from havln_mj.errors import InvalidArgumentError
from havln_mj.nav import NavGrid
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.regions import Regions

_PATH_COLOURS = ("#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#8c564b", "#e377c2")
_PERSON = "#ff7f0e"
_MAP_INCHES = 8.0  # the map's longer side
_TITLE_PT = 11.0
_LEVEL_BAND = (-0.5, 2.5)  # metres above the drawn floor that count as on this level
_PELVIS_BAND = (-0.2, 1.6)


def section_segments(mesh: trimesh.Trimesh, z: float) -> np.ndarray:
    """(S, 2, 2) plan-view segments where the plane at height ``z`` cuts the mesh."""
    lines = trimesh.intersections.mesh_plane(mesh, plane_normal=[0, 0, 1], plane_origin=[0, 0, z])
    return np.asarray(lines)[:, :, :2].reshape(-1, 2, 2)


def _points(name: str, value: object, shape: str) -> np.ndarray:
    """``value`` as a float array of points ``(n, 2|3)``; raises naming ``name``."""
    arr = np.asarray(value, dtype=float)
    if arr.ndim != 2 or arr.shape[1] not in (2, 3):
        raise InvalidArgumentError(f"{name} must be {shape}, got an array of shape {arr.shape}")
    return arr


def _on_level(xyz: np.ndarray, floor: float, band: tuple[float, float]) -> np.ndarray:
    """Plan coordinates ``(n, 2)``, NaN where a 3-D point lies off the level (breaks lines)."""
    xy = xyz[:, :2].copy()
    if xyz.shape[1] == 3:
        dz = xyz[:, 2] - floor
        xy[(dz < band[0]) | (dz > band[1])] = np.nan
    return xy


class _Legend:
    """Legend entries in drawing order, each label once."""

    def __init__(self) -> None:
        self.handles: list = []
        self.labels: list[str] = []

    def add(self, label: str, handle: object) -> None:
        if label not in self.labels:
            self.labels.append(label)
            self.handles.append(handle)

    def marker(self, label: str, marker: str, **style: object) -> None:
        self.add(label, Line2D([], [], ls="none", marker=marker, **style))

    def line(self, label: str, **style: object) -> None:
        self.add(label, Line2D([], [], **style))

    def patch(self, label: str, **style: object) -> None:
        self.add(label, Patch(**style))


def _draw_navgrid(ax: plt.Axes, navgrid: NavGrid, legend: _Legend) -> None:
    image, extent = navgrid.image(alpha=110)
    ax.imshow(image, origin="lower", extent=extent, zorder=0, interpolation="nearest")
    # Legend colours come from the picture itself, so they always match it.
    for cells, label in (
        (navgrid.occupied, "blocked: walls, furniture (grid)"),
        (~navgrid.free & ~navgrid.occupied, "too close to walls for the robot (grid)"),
    ):
        if cells.any():
            rgba = image[cells][0] / 255.0
            legend.patch(label, fc=rgba, ec="none")


def _draw_plan(
    ax: plt.Axes,
    regions: Regions | None,
    mesh: trimesh.Trimesh | None,
    level_floor: float,
    legend: _Legend,
) -> None:
    """Rooms (filled, named), furniture boxes and the wall section."""
    if regions is not None:
        cmap = plt.get_cmap("Pastel1")
        labels = sorted({r.label for r in regions.regions})
        fills: dict[str, tuple] = {}
        for rg in regions.regions:
            if abs(regions.levels[rg.level].z_floor - level_floor) > 0.5:
                continue
            fills[rg.label] = (*cmap(labels.index(rg.label) % cmap.N)[:3], 0.45)
            ax.add_patch(Polygon(rg.polygon, closed=True, fc=fills[rg.label], ec="none"))
            if rg.label != "-":  # unlabelled regions (graph proxies) keep their fill only
                cx, cy = rg.polygon.mean(axis=0)
                ax.text(cx, cy, rg.name, ha="center", va="center", fontsize=7, alpha=0.8,
                        zorder=2)  # fmt: skip
        if fills:
            swatches = tuple(Patch(fc=c, ec="none") for c in list(fills.values())[:3])
            legend.add("room (region), coloured by kind", swatches)
        for ob in regions.objects:
            if abs(ob.bbox[2] - level_floor) < 0.5:
                x0, y0, _, x1, y1, _ = ob.bbox
                ax.add_patch(
                    Rectangle((x0, y0), x1 - x0, y1 - y0, fc="0.55", ec="0.35", alpha=0.5, lw=0.5)
                )
                legend.patch("furniture", fc="0.55", ec="0.35", alpha=0.5, lw=0.5)
    if mesh is not None:
        segments = section_segments(mesh, level_floor + 1.0)
        ax.add_collection(LineCollection(segments, colors="0.25", lw=1.0, zorder=1))
        if len(segments):
            legend.line("walls (mesh cut 1 m above the floor)", c="0.25", lw=1.0)


def _draw_graph(ax: plt.Axes, graph: NavGraph, level_floor: float, legend: _Legend) -> None:
    nodes = [n for n in graph.nodes if abs(graph.floor_z(n) - level_floor) < 0.5]
    pos = {n: graph.position(n) for n in nodes}
    edges = [(pos[a][:2], pos[b][:2]) for a, b, _ in graph.edges() if a in pos and b in pos]
    ax.add_collection(LineCollection(edges, colors="0.6", lw=0.6, zorder=2))
    xy = np.array([pos[n][:2] for n in nodes]).reshape(-1, 2)
    ax.scatter(xy[:, 0], xy[:, 1], s=8, c="0.3", zorder=3)
    if len(xy):
        legend.marker("viewpoint", "o", ms=3.5, c="0.3")
    if edges:
        legend.line("navigable edge", c="0.6", lw=0.8)


def _draw_paths(
    ax: plt.Axes,
    graph: NavGraph,
    paths: Sequence[Sequence[str]],
    walked: Sequence[np.ndarray],
    level_floor: float,
    legend: _Legend,
) -> None:
    """Planned paths (thick, pale), walked tracks (thin, dark) and their ends."""
    for k in range(max(len(paths), len(walked))):
        c = _PATH_COLOURS[k % len(_PATH_COLOURS)]
        if k < len(paths) and len(paths[k]):
            pts = np.array([graph.position(v)[:2] for v in paths[k]])
            ax.plot(pts[:, 0], pts[:, 1], "-", c=c, lw=3.2, alpha=0.55, zorder=4)
            ax.plot(*pts[0], "o", c=c, ms=9, mfc="white", mew=2, zorder=6)
            ax.plot(*pts[-1], "*", c=c, ms=15, mec="black", mew=0.5, zorder=6)
            legend.line("planned path (graph)", c="0.2", lw=3.2, alpha=0.55)
            legend.marker("start", "o", ms=8, c="0.2", mfc="white", mew=2)
            legend.marker("goal", "*", ms=12, c="0.2", mec="black", mew=0.5)
        if k < len(walked):
            xy = _on_level(_points("walked tracks", walked[k], "(n, 2) or (n, 3)"), level_floor,
                           _LEVEL_BAND)  # fmt: skip
            ax.plot(xy[:, 0], xy[:, 1], "-", c=c, lw=1.1, zorder=5)
            end = xy[np.isfinite(xy[:, 0])]
            if len(end):
                ax.plot(*end[-1], "s", c=c, ms=6, mec="black", mew=0.6, zorder=6)
                legend.line("walked track (true position)", c="0.2", lw=1.1)
                legend.marker("where the walk ended", "s", ms=6, c="0.2", mec="black", mew=0.6)
    if max(len(paths), len(walked)) > 1:
        for k in range(min(max(len(paths), len(walked)), len(_PATH_COLOURS))):
            legend.patch(f"episode {k + 1}", fc=_PATH_COLOURS[k], ec="none")


def _draw_people(
    ax: plt.Axes,
    people: np.ndarray | None,
    people_tracks: np.ndarray | None,
    level_floor: float,
    legend: _Legend,
) -> None:
    """People (with their 1 m collision circles) and their pelvis tracks."""
    if people_tracks is not None:
        tracks = np.asarray(people_tracks, dtype=float)
        if tracks.ndim != 3 or tracks.shape[2] != 3:
            raise InvalidArgumentError(
                f"people_tracks must be (T, P, 3) pelvis positions, got shape {tracks.shape}"
            )
        for p in range(tracks.shape[1]):
            xy = _on_level(tracks[:, p], level_floor, _PELVIS_BAND)
            if np.isfinite(xy).any():
                ax.plot(xy[:, 0], xy[:, 1], "-", c=_PERSON, lw=1.4, alpha=0.9, zorder=5)
                legend.line("person's track over the episode", c=_PERSON, lw=1.4)
        if people is None and len(tracks):
            people = tracks[0]
    if people is None:
        return
    for x, y, z in _points("people", np.reshape(people, (-1, 3)), "(N, 3)"):
        if _PELVIS_BAND[0] < z - level_floor < _PELVIS_BAND[1]:
            ax.add_patch(
                Circle((x, y), 1.0, fc=(1.0, 0.5, 0.0, 0.15), ec=_PERSON, lw=0.8, zorder=4)
            )
            ax.plot(x, y, "P", c=_PERSON, ms=9, mec="black", mew=0.6, zorder=9)
            legend.marker("person", "P", ms=9, c=_PERSON, mec="black", mew=0.6)
            legend.marker(
                "1 m collision radius", "o", ms=11, mfc=(1.0, 0.5, 0.0, 0.15), mec=_PERSON, mew=0.8
            )


def _draw_collisions(
    ax: plt.Axes, collisions: np.ndarray | None, level_floor: float, legend: _Legend
) -> None:
    if collisions is None:
        return
    xy = _on_level(_points("collisions", collisions, "(K, 2) or (K, 3)"), level_floor, _LEVEL_BAND)
    kept: list[np.ndarray] = []
    for p in xy[np.isfinite(xy[:, 0])]:  # one mark per 0.3 m of a collision stretch
        if not kept or np.hypot(*(p - kept[-1])) > 0.3:
            kept.append(p)
    if kept:
        xy = np.array(kept)
        ax.plot(xy[:, 0], xy[:, 1], "X", c="#e8000b", ms=8, mec="black", mew=0.6, ls="none",
                zorder=8)  # fmt: skip
        legend.marker("collision (agent within 1 m of a person)", "X", ms=8, c="#e8000b",
                      mec="black", mew=0.6)  # fmt: skip


def _finish(fig: plt.Figure, ax: plt.Axes, title: str, legend: _Legend) -> None:
    """Sizes the figure to the map, wraps the title and places the legend beside the map."""
    ax.set_aspect("equal")
    ax.margins(0.02)
    ax.autoscale_view()
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    w, h = max(x1 - x0, 1e-3), max(y1 - y0, 1e-3)
    scale = _MAP_INCHES / max(w, h)
    wide = w > 1.3 * h  # a wide map takes its legend underneath, a tall one beside it
    fig.set_size_inches(max(w * scale, 4.0), max(h * scale, 3.0))
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if title:
        _wrapped_title(fig, ax, title)
    if legend.handles:
        where = (
            {"loc": "upper center", "bbox_to_anchor": (0.5, -0.08), "ncol": 3}
            if wide
            else {"loc": "upper left", "bbox_to_anchor": (1.01, 1.0)}
        )
        ax.legend(legend.handles, legend.labels, fontsize=8, frameon=False,
                  handler_map={tuple: HandlerTuple(ndivide=None, pad=0)}, **where)  # fmt: skip


def _wrapped_title(fig: plt.Figure, ax: plt.Axes, title: str) -> None:
    """Sets the title, wrapped at word boundaries until it is no wider than the map."""
    renderer = fig.canvas.get_renderer()
    room = ax.get_window_extent(renderer).width
    chars = max(len(line) for line in title.splitlines() or [""])
    while True:
        text = "\n".join(textwrap.fill(part, chars) for part in title.splitlines())
        artist = ax.set_title(text, fontsize=_TITLE_PT)
        if chars <= 20 or artist.get_window_extent(renderer).width <= room:
            return
        chars = int(chars * 0.9)


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
    *,
    walked: Sequence[np.ndarray] = (),
    people_tracks: np.ndarray | None = None,
    collisions: np.ndarray | None = None,
) -> list[str]:
    """Writes a PNG map of one level, with a legend of every mark drawn.

    Args:
        path: Output PNG path (its folder is created).
        graph: Navigation graph (nodes and edges are drawn).
        regions: Regions to fill and label, and objects to draw, if known.
        mesh: Building mesh, cut 1 m above ``level_floor`` to draw walls and furniture.
        paths: Viewpoint-id paths planned, one per episode (start ○, goal ★).
        level_floor: Floor height of the level drawn; viewpoints, tracks and people of other
            levels are left out.
        title: Figure title; wrapped to the map's width.
        navgrid: Navigability grid of the level, shaded under the plan (blocked cells red
            where only the robot's radius blocks them, grey where geometry is).
        people: Pelvis positions ``(N, 3)`` of people to mark, each with its 1 m collision
            circle (default: the first sample of ``people_tracks``).
        walked: The track each episode's agent really walked (e.g. the GO1's trunk), points
            ``(n, 2)`` or ``(n, 3)`` in the order walked; the k-th is drawn beside
            ``paths[k]`` in its colour and ends in a square.
        people_tracks: Pelvis positions ``(T, P, 3)`` of the people over the episode, drawn
            as lines.
        collisions: Agent positions ``(K, 2)`` or ``(K, 3)`` where it was within the collision
            distance of a person, marked ✕.

    Returns:
        The legend's entries, in order.

    Raises:
        InvalidArgumentError: A track, person or collision array of the wrong shape.
    """
    fig, ax = plt.subplots(dpi=110)
    try:
        legend = _Legend()
        if navgrid is not None:
            _draw_navgrid(ax, navgrid, legend)
        _draw_plan(ax, regions, mesh, level_floor, legend)
        _draw_graph(ax, graph, level_floor, legend)
        _draw_paths(ax, graph, paths, walked, level_floor, legend)
        _draw_people(ax, people, people_tracks, level_floor, legend)
        _draw_collisions(ax, collisions, level_floor, legend)
        _finish(fig, ax, title, legend)
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, bbox_inches="tight", pad_inches=0.05)
        return legend.labels
    finally:
        plt.close(fig)
