"""Regions for a scan that has no region labels: one unlabelled region per storey."""

from __future__ import annotations

import numpy as np

from havln_mj.scene.navgraph import NavGraph, level_groups
from havln_mj.scene.regions import Level, Region, Regions


def levels_from_graph(graph: NavGraph) -> Regions:
    """One unlabelled region per storey (``level_groups``), for scans without region labels."""
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
