"""HA3D's rules that annotate an R2R path with people and crux points (HA-R2R's extra keys).

Reproduces ``src/utils/get_info.py`` of the HA3D simulator:

* A person standing on viewpoint ``h`` is linked to a path when some path node sees ``h``
  (the connectivity ``visible`` flags). Then, taking the path node nearest ``h`` (3-D distance
  between viewpoint positions, the first one on ties): closer than 1.5 m to the first node is
  ``Beginning``, to the last ``End``, to a middle one ``Obstacle``; otherwise ``Around``.
* People are listed in order of first sight: path node by path node, each node's visible
  viewpoints in file order.
* Crux points: the start, the goal, and every next node that shares exactly one
  ``unobstructed`` neighbour with the node before it.

On HA-R2R val_seen these rebuild ``human`` and ``crux_points`` of all 340 paths exactly.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from itertools import pairwise

import numpy as np

from havln_mj.scene.navgraph import NavGraph
from havln_mj.tasks.episodes import HumanOnPath

REL_POS_RADIUS = 1.5  # metres, HA3D getRelPos


def _visible_from(graph: NavGraph, path: Sequence[str]) -> list[str]:
    """Viewpoints seen from the path's nodes, in order of first sight."""
    c = graph.connectivity
    seen: dict[str, None] = {}
    for vp in path:
        for j in np.flatnonzero(c.visible[graph.index(vp)]).tolist():
            seen.setdefault(c.ids[j])
    return list(seen)


def rel_pos(human_viewpoint: str, path: Sequence[str], graph: NavGraph) -> str | None:
    """HA3D's relative position of a person on ``human_viewpoint`` to ``path``.

    Returns:
        ``"Beginning"``, ``"Obstacle"``, ``"Around"`` or ``"End"``; None when no path node
        sees the viewpoint (the person is not linked to the path).

    Raises:
        UnknownViewpointError: A viewpoint is not in ``graph``.
    """
    here = graph.position(human_viewpoint)
    j = graph.index(human_viewpoint)
    visible = graph.connectivity.visible
    if not any(visible[graph.index(vp), j] for vp in path):
        return None
    dists = [math.dist(here, graph.position(vp)) for vp in path]
    k = min(range(len(path)), key=dists.__getitem__)
    if dists[k] >= REL_POS_RADIUS:
        return "Around"
    if k == 0:
        return "Beginning"
    return "End" if k == len(path) - 1 else "Obstacle"


def humans_on_path(
    path: Sequence[str], graph: NavGraph, placements: Mapping[str, object]
) -> tuple[HumanOnPath, ...]:
    """HA-R2R's ``human`` entries of a path.

    Args:
        path: The path's viewpoints.
        graph: The scan's graph.
        placements: The scan's HA3D placements, ``{viewpoint: ["region:activity", model id,
            heading in degrees]}`` (one scan of ``human_placements.json``); a plain
            ``{viewpoint: "region:activity"}`` works too.
    """
    out = []
    for vp in _visible_from(graph, path):
        if vp in placements:
            entry = placements[vp]
            text = entry if isinstance(entry, str) else entry[0]
            pos = rel_pos(vp, path, graph)
            if pos is not None:
                out.append(HumanOnPath(vp, pos, text))
    return tuple(out)


def crux_points(path: Sequence[str], graph: NavGraph) -> tuple[str, ...]:
    """HA3D's crux points of a path (``getCruxOnPath``)."""
    unob = graph.connectivity.unobstructed
    out = [path[0]]
    for here, nxt in pairwise(path):
        if nxt == path[-1]:
            out.append(nxt)
            break
        shared = unob[graph.index(here)] & unob[graph.index(nxt)]
        if int(np.count_nonzero(shared)) == 1:
            out.append(nxt)
    return tuple(out)
