"""What the annotation page draws as its map: a scan's plan as plain JSON, per level.

Coordinates are Matterport metres rounded to the centimetre: viewpoints (with their region,
whether the simulator uses them, and the heading facing their room's centre), navigable edges,
rooms, furniture boxes and the wall section 1 m above each floor.
"""

from __future__ import annotations

import math

import numpy as np

from havln_mj.frames import heading_to
from havln_mj.render.topdown import section_segments
from havln_mj.scene.regions import Region
from havln_mj.scene.scan import Scan, floor_heights


def _r(values: object) -> list:
    return np.round(np.asarray(values, float), 2).tolist()


def level_of(floors: list[float], z: float) -> int:
    """Index of the level a floor height ``z`` stands on (the highest floor ≤ z + 0.5 m)."""
    below = [k for k, f in enumerate(floors) if f <= z + 0.5]
    return below[-1] if below else 0


def _facing(region: Region | None, pos: np.ndarray) -> float:
    """Degrees of the heading that faces the room's centre, as automatic placement does."""
    if region is None:
        return 0.0
    centre = region.polygon.mean(axis=0)
    if np.linalg.norm(centre - pos[:2]) < 0.3:
        return 0.0
    return round(math.degrees(heading_to(pos, centre)), 1)


def scene_plan(scan: Scan) -> dict:
    """The plan of ``scan`` for the page's map (JSON-ready)."""
    graph, regions = scan.graph, scan.regions
    floors = floor_heights(scan)
    index = {vp: k for k, vp in enumerate(graph.ids)}
    viewpoints = []
    for vp in graph.ids:  # excluded ones too: HA3D stands people on some of them
        region = regions.region_of(vp) if regions is not None else None
        x, y, z = graph.position(vp)
        viewpoints.append(
            {
                "id": vp,
                "x": round(float(x), 2),
                "y": round(float(y), 2),
                "z": round(float(z), 2),
                "level": level_of(floors, graph.floor_z(vp)),
                "included": vp in graph,
                "region": None if region is None else region.label,
                "region_name": None if region is None else region.name,
                "face_deg": _facing(region, graph.position(vp)),
            }
        )
    rooms, furniture = [], []
    if regions is not None:
        for rg in regions.regions:
            level = level_of(floors, regions.levels[rg.level].z_floor)
            rooms.append(
                {"level": level, "label": rg.label, "name": rg.name, "polygon": _r(rg.polygon)}
            )
        for ob in regions.objects:
            x0, y0, z0, x1, y1, _ = ob.bbox
            furniture.append({"level": level_of(floors, z0), "box": _r([x0, y0, x1, y1])})
    mesh = scan.mesh
    walls = [_r(section_segments(mesh, f + 1.0).reshape(-1, 4)) for f in floors]
    lo, hi = mesh.bounds
    return {
        "scene": scan.scene_id,
        "description": scan.description,
        "levels": [{"index": k, "floor": round(f, 2)} for k, f in enumerate(floors)],
        "viewpoints": viewpoints,
        "edges": [[index[a], index[b]] for a, b, _ in graph.edges()],
        "rooms": rooms,
        "furniture": furniture,
        "walls": walls,
        "bounds": _r([lo[0], lo[1], hi[0], hi[1]]),
    }
