"""Check that a mesh and a connectivity graph share one frame: viewpoints stand on the floor.

Every viewpoint of a MatterSim connectivity file has a camera position and a ``height`` above
the floor, so the floor under it is expected at ``z − height``. Casting rays straight down
from the camera finds the mesh's floor there; when too few viewpoints agree, the files are
not in one frame and nothing built from them (collision, rendering, humans) would line up.

Rays: for each sampled viewpoint, five vertical rays start at the camera (one at the camera,
four :data:`RING_RADIUS_M` around it, so a hole or a chair leg under the tripod does not
decide alone). The viewpoint's floor is the median of the rays' first hits below the camera.
At most ``max_viewpoints`` included viewpoints are checked, evenly spread over the file order
(deterministic). Ray casting is trimesh's (``mesh.ray``; without Embree it needs ``rtree``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import trimesh

from havln_mj.errors import CorruptMeshError, FrameMismatchError, InvalidArgumentError
from havln_mj.scene.connectivity import Connectivity

RING_RADIUS_M = 0.15
"""Horizontal offset of the four extra rays around each camera, metres."""

MAX_VIEWPOINTS = 200
"""Default largest number of viewpoints checked."""

_RING = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]]) * RING_RADIUS_M


@dataclass(frozen=True)
class FrameReport:
    """Result of :func:`check_frame`.

    Attributes:
        checked: Viewpoints sampled.
        agreeing: Sampled viewpoints whose floor hit lies within the tolerance of
            ``z − height``.
        missed: Sampled viewpoints with no mesh surface below the camera.
        median_offset: Median of (floor hit − expected floor) in metres over the viewpoints
            with a hit; NaN when none had one.
    """

    checked: int
    agreeing: int
    missed: int
    median_offset: float

    @property
    def fraction(self) -> float:
        """Share of the sampled viewpoints that agree (1.0 when none was sampled)."""
        return self.agreeing / self.checked if self.checked else 1.0


def sample_viewpoints(connectivity: Connectivity, max_viewpoints: int) -> np.ndarray:
    """Indices of at most ``max_viewpoints`` included viewpoints, evenly spread, sorted."""
    included = np.flatnonzero(connectivity.included)
    if len(included) <= max_viewpoints:
        return included
    picks = np.linspace(0, len(included) - 1, max_viewpoints).round().astype(int)
    return included[np.unique(picks)]


def floor_hits(mesh: trimesh.Trimesh, positions: np.ndarray) -> np.ndarray:
    """The floor height under each position (median of its rays' first hits), NaN if none.

    Args:
        mesh: The building's mesh (z up).
        positions: (N, 3) camera positions.

    Returns:
        (N,) floor heights.
    """
    n = len(positions)
    origins = np.repeat(positions, len(_RING), axis=0)
    origins[:, :2] += np.tile(_RING, (n, 1))
    directions = np.tile([0.0, 0.0, -1.0], (len(origins), 1))
    first = np.full(len(origins), np.nan)
    if n:
        locations, ray_index, _ = mesh.ray.intersects_location(
            origins, directions, multiple_hits=True
        )
        # The first hit below a camera is the highest one on its downward ray.
        order = np.argsort(-locations[:, 2], kind="stable")
        ray_sorted = ray_index[order]
        _, first_of = np.unique(ray_sorted, return_index=True)
        hit_rays = ray_sorted[first_of]
        first[hit_rays] = locations[order[first_of], 2]
    per_viewpoint = first.reshape(n, len(_RING))
    out = np.full(n, np.nan)
    has_hit = ~np.all(np.isnan(per_viewpoint), axis=1)
    out[has_hit] = np.nanmedian(per_viewpoint[has_hit], axis=1)
    return out


def check_frame(
    mesh: trimesh.Trimesh,
    connectivity: Connectivity,
    *,
    tolerance: float = 0.2,
    min_fraction: float = 0.8,
    max_viewpoints: int = MAX_VIEWPOINTS,
) -> FrameReport:
    """Checks that the connectivity's viewpoints stand on the mesh's floor.

    Args:
        mesh: The building's mesh in the z-up world frame (e.g.
            :func:`havln_mj.scene.mesh.parts_to_trimesh` of the loaded parts).
        connectivity: The scan's viewpoints.
        tolerance: Largest ``|floor hit − (z − height)|`` that counts as agreeing, metres.
        min_fraction: Smallest share of sampled viewpoints that must agree.
        max_viewpoints: Most viewpoints checked (evenly spread; deterministic).

    Returns:
        How many viewpoints were checked and agreed, and the typical offset.

    Raises:
        InvalidArgumentError: ``tolerance``, ``min_fraction`` or ``max_viewpoints`` is out
            of range.
        CorruptMeshError: The mesh has no triangles.
        FrameMismatchError: Fewer than ``min_fraction`` of the sampled viewpoints agree; the
            message gives the share, the typical offset and likely causes.
    """
    if not (math.isfinite(tolerance) and tolerance > 0):
        raise InvalidArgumentError(f"tolerance must be a positive number, got {tolerance!r}")
    if not 0.0 <= min_fraction <= 1.0:
        raise InvalidArgumentError(f"min_fraction must be in [0, 1], got {min_fraction!r}")
    if isinstance(max_viewpoints, bool) or not int(max_viewpoints) >= 1:
        raise InvalidArgumentError(f"max_viewpoints must be >= 1, got {max_viewpoints!r}")
    if len(mesh.faces) == 0:
        raise CorruptMeshError("the mesh holds no triangles; cannot check its frame")
    picks = sample_viewpoints(connectivity, int(max_viewpoints))
    positions = connectivity.positions[picks]
    expected = connectivity.floor_z[picks]
    hits = floor_hits(mesh, positions)
    offsets = hits - expected
    hit = ~np.isnan(offsets)
    agreeing = int(np.sum(np.abs(offsets[hit]) <= tolerance))
    median = float(np.median(offsets[hit])) if hit.any() else math.nan
    report = FrameReport(len(picks), agreeing, int(np.sum(~hit)), median)
    if report.checked and report.fraction < min_fraction:
        raise FrameMismatchError(_mismatch_message(mesh, connectivity, report, tolerance))
    return report


def _mismatch_message(
    mesh: trimesh.Trimesh, connectivity: Connectivity, report: FrameReport, tolerance: float
) -> str:
    lo, hi = mesh.bounds
    cams = connectivity.positions[connectivity.included]
    offset = "none" if math.isnan(report.median_offset) else f"{report.median_offset:+.2f} m"
    lines = [
        f"{connectivity.source}: the viewpoints do not stand on the mesh's floor: "
        f"{report.agreeing}/{report.checked} sampled viewpoints ({report.fraction:.0%}) have "
        f"the mesh floor within {tolerance:g} m of z − height; typical offset (median of "
        f"floor hit − expected floor) {offset}; {report.missed} had no surface below.",
        f"Mesh bounds x [{lo[0]:.2f}, {hi[0]:.2f}] y [{lo[1]:.2f}, {hi[1]:.2f}] "
        f"z [{lo[2]:.2f}, {hi[2]:.2f}]; cameras z [{cams[:, 2].min():.2f}, "
        f"{cams[:, 2].max():.2f}].",
        "Likely causes: the mesh is from a different scan than the connectivity file; the "
        "mesh is stored y-up (a glTF exported y-up, or a habitat .glb converted to y-up: load "
        "it with up='y'); the connectivity file belongs to another scan or was edited.",
    ]
    return " ".join(lines)
