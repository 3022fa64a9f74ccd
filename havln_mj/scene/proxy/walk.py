"""Whether a body can walk a path through box geometry: the check graph proxies are held to.

A path is a polyline of floor points (a graph edge is two: its viewpoints' floor points; a
route is the floor points of the viewpoints it passes). The body is a vertical column of
square footprint (half side ``body_radius``), sampled every half cell along the path. Under
each sample the *support* is the box top nearest to the floor height interpolated along the
path (within ``layer_gap``). The path fails with:

* ``"no_floor"``: a sample has no support, or the support at either end is more than
  ``step / 2`` from that end's floor (the body must stand on its viewpoint's floor). A box
  top buried inside another box is no support: the body stands on top of that box;
* ``"step"``: the support rises or drops by more than ``step`` between neighbouring samples
  (a stair riser);
* ``"steep"``: over some stretch of at least ``grade_window`` metres the support climbs or
  drops faster than ``max_grade`` (rise over horizontal run; 1.0 is 45°, steeper than any
  stair a building code allows). A straight edge whose ends differ by more than
  ``max_grade`` × its horizontal length is steep whatever geometry is drawn;
* ``"blocked"``: a box meets the footprint in the body band, ``body_z`` above the support
  (the band's bottom above the highest support within one body radius along the path, so
  the stairs ahead are stepped onto, not bumped into).
"""

from __future__ import annotations

import numpy as np

from havln_mj.scene.boxes import BoxSet
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.proxy.params import ProxyParams

CAUSES = ("no_floor", "step", "steep", "blocked")


def samples(points: np.ndarray, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Points every ``spacing`` (or closer) along a polyline of floor points.

    Args:
        points: (K, 3) floor points ``(x, y, floor_z)``, K ≥ 2.
        spacing: Largest gap between samples along each segment (3-D length).

    Returns:
        (n, 3) samples, the polyline's vertices among them, and (n,) horizontal distance of
        each sample from the start along the path.
    """
    pieces, runs, run0 = [], [], 0.0
    for k in range(len(points) - 1):
        a, b = points[k], points[k + 1]
        n = max(2, int(np.ceil(np.linalg.norm(b - a) / spacing)) + 1)
        t = np.linspace(0.0, 1.0, n)[:, None]
        seg = a + t * (b - a)
        flat = float(np.hypot(*(b[:2] - a[:2])))
        if k:
            seg, t = seg[1:], t[1:]
        pieces.append(seg)
        runs.append(run0 + t[:, 0] * flat)
        run0 += flat
    return np.concatenate(pieces), np.concatenate(runs)


def path_fault(points: np.ndarray, boxes: BoxSet, p: ProxyParams) -> str | None:
    """Why a body cannot walk the polyline ``points`` (one of ``CAUSES``), or None if it can.

    Args:
        points: (K, 3) floor points, K ≥ 2.
        boxes: The geometry (axis-aligned boxes).
        p: The body and the limits.
    """
    r = p.body_radius
    points = np.asarray(points, dtype=float)
    legs = np.diff(points, axis=0)
    if np.any(np.abs(legs[:, 2]) > p.max_grade * np.hypot(legs[:, 0], legs[:, 1]) + 1e-9):
        return "steep"  # a straight leg this steep is no walk, whatever is drawn
    pts, run = samples(points, p.cell / 2)
    x, y, f = pts[:, :1], pts[:, 1:2], pts[:, 2:]
    support, lo, hi = _support(pts, boxes, p)
    if support is None:
        return "no_floor"
    if np.abs(support[[0, -1]] - f[[0, -1], 0]).max() > p.step / 2 + 1e-6:
        return "no_floor"
    if np.abs(np.diff(support)).max(initial=0.0) > p.step + 1e-6:
        return "step"
    if _too_steep(support, run, p.max_grade, p.grade_window):
        return "steep"
    # On a slope the floor under the front of the body is higher than under its centre:
    # the band starts above the highest support within one body radius along the path.
    k = int(np.ceil(r / (p.cell / 2)))
    padded = np.pad(support, k, mode="edge")
    ahead = np.lib.stride_tricks.sliding_window_view(padded, 2 * k + 1).max(axis=1)[:, None]
    meets = (
        (lo[..., 0] < x + r) & (hi[..., 0] > x - r) & (lo[..., 1] < y + r) & (hi[..., 1] > y - r)
    )
    meets &= (lo[..., 2] < support[:, None] + p.body_z[1]) & (hi[..., 2] > ahead + p.body_z[0])
    return "blocked" if meets.any() else None


def _support(pts: np.ndarray, boxes: BoxSet, p: ProxyParams):
    """The support under each sample (see the module doc), None where one has none.

    Returns:
        The support heights (or None), and the near boxes' lo and hi, shaped (1, B, 3).
    """
    r = p.body_radius
    x, y, f = pts[:, :1], pts[:, 1:2], pts[:, 2:]
    # Only boxes near the path matter.
    lo_xy, hi_xy = pts[:, :2].min(axis=0) - r, pts[:, :2].max(axis=0) + r
    near = np.all(boxes.lo[:, :2] <= hi_xy, axis=1) & np.all(boxes.hi[:, :2] >= lo_xy, axis=1)
    lo, hi = boxes.lo[near][None], boxes.hi[near][None]  # (1, B, 3)
    over = (lo[..., 0] <= x) & (hi[..., 0] >= x) & (lo[..., 1] <= y) & (hi[..., 1] >= y)
    gap = np.where(over, np.abs(hi[..., 2] - f), np.inf)
    if gap.shape[1] == 0:
        return None, lo, hi
    nearest = gap.argmin(axis=1)
    support = np.where(gap.min(axis=1) <= p.layer_gap, hi[0, nearest, 2], np.inf)
    if not np.isfinite(support).all():
        return None, lo, hi
    # A top inside another box is no floor: the body stands on top of the solid around it.
    for _ in range(len(boxes)):
        buried = over & (lo[..., 2] <= support[:, None]) & (hi[..., 2] > support[:, None] + 1e-9)
        if not buried.any():
            break
        support = np.maximum(support, np.where(buried, hi[..., 2], -np.inf).max(axis=1))
    return support, lo, hi


def stair_steps(
    points: np.ndarray,
    boxes: BoxSet,
    p: ProxyParams,
    spacing: float = 0.01,
    least: float = 0.03,
) -> tuple[np.ndarray, np.ndarray]:
    """The risers and treads a path crosses: its support sampled every ``spacing``.

    A riser is a rise or drop of more than ``least`` between neighbouring samples (heights
    in metres, signed along the path); a tread is the run between two risers (the flat runs
    before the first and after the last are landings, not treads).

    Returns:
        Risers and treads (m); both empty where the path has no support.
    """
    pts, run = samples(np.asarray(points, dtype=float), spacing)
    support, _, _ = _support(pts, boxes, p)
    if support is None:
        return np.zeros(0), np.zeros(0)
    at = np.flatnonzero(np.abs(np.diff(support)) > least)
    if not len(at):
        return np.zeros(0), np.zeros(0)
    # A riser split between neighbouring samples counts once.
    groups = np.split(at, np.flatnonzero(np.diff(at) > 1) + 1)
    risers = np.array([support[g[-1] + 1] - support[g[0]] for g in groups])
    return risers, np.diff([run[g[0]] for g in groups])


def _too_steep(support: np.ndarray, run: np.ndarray, grade: float, window: float) -> bool:
    """Whether the support climbs faster than ``grade`` over some stretch ≥ ``window`` long.

    A path shorter than ``window`` is judged end to end.
    """
    if run[-1] <= window:
        return abs(support[-1] - support[0]) > grade * max(run[-1], 1e-9) + 1e-6
    j = np.searchsorted(run, run + window)
    i = np.flatnonzero(j < len(run))
    rise = np.abs(support[j[i]] - support[i])
    return bool(np.any(rise > grade * (run[j[i]] - run[i]) + 1e-6))


def floor_point(graph: NavGraph, vp: str) -> np.ndarray:
    """The floor point ``(x, y, floor_z)`` under viewpoint ``vp``."""
    x, y, _ = graph.position(vp)
    return np.array([x, y, graph.floor_z(vp)])


def edge_grade(graph: NavGraph, a: str, b: str) -> float:
    """End-to-end grade of the straight edge a-b: floor difference over horizontal length."""
    pa, pb = floor_point(graph, a), floor_point(graph, b)
    return abs(pb[2] - pa[2]) / max(float(np.hypot(*(pb[:2] - pa[:2]))), 1e-9)
