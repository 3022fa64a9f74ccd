"""Which people of an episode are unavoidable, so their collisions are not held against the agent.

Two definitions exist (see ``MetricConfig``):

* The HA-VLN paper discounts collisions at *critical nodes*: nodes of the reference path the
  agent cannot avoid (start, goal and bottlenecks). HA3D stores them per episode as
  ``crux_points`` (``src/utils/get_info.py::getCruxOnPath``), and a person is unavoidable when
  standing within the collision radius of one of them.
* HA3D's evaluation code instead subtracts one per person labelled ``Beginning`` or ``End``
  (within 1.5 m of the path's first or last node), ignoring ``crux_points``.
"""

from __future__ import annotations

from collections.abc import Sequence
from itertools import pairwise

import numpy as np

from havln_mj.scene.navgraph import NavGraph
from havln_mj.tasks.metrics.config import MetricConfig
from havln_mj.tasks.metrics.episode import EvalEpisode, Person

_HA3D_LABELS = ("Beginning", "End")


def crux_points(graph: NavGraph, path: Sequence[str]) -> list[str]:
    """Computes a path's critical nodes with HA3D's ``getCruxOnPath`` rule.

    The start is critical; walking the path, the next node is critical when it and the
    current node share exactly one neighbour, and the goal always is. HA3D reads neighbours
    from its ``con_info`` files; here they come from the graph (included viewpoints only).

    Args:
        graph: The scan's navigation graph.
        path: The reference path, start first.

    Returns:
        The critical nodes in path order.

    Raises:
        UnknownViewpointError: A path viewpoint is unknown or excluded.
    """
    crux = [path[0]]
    for here, nxt in pairwise(path):
        if nxt == path[-1]:
            crux.append(nxt)
            break
        if len(set(graph.neighbors(here)) & set(graph.neighbors(nxt))) == 1:
            crux.append(nxt)
    return crux


def unavoidable_people(episode: EvalEpisode, graph: NavGraph, config: MetricConfig) -> list[int]:
    """Indices into ``episode.people`` of the people whose collisions are unavoidable.

    Args:
        episode: The episode, with its people (and ``crux_points`` when known).
        graph: The scan's navigation graph (person and node positions, ``"paper"`` mode).
        config: Holds the mode (``critical``) and the collision radius.

    Raises:
        UnknownViewpointError: In ``"paper"`` mode, a person's or a crux point's viewpoint is
            not in the scan.
    """
    if config.critical == "none" or not episode.people:
        return []
    if config.critical == "ha3d":
        return [i for i, p in enumerate(episode.people) if p.rel_pos in _HA3D_LABELS]
    nodes = episode.crux_points
    if nodes is None:
        nodes = tuple(crux_points(graph, episode.reference_path))
    node_pos = np.array([graph.position(vp) for vp in nodes])
    return [
        i
        for i, person in enumerate(episode.people)
        # A small tolerance keeps a person exactly at the radius (HA3D: <= 1 m) inside.
        if np.linalg.norm(node_pos - _position(person, graph), axis=1).min()
        <= config.collision_radius + 1e-9
    ]


def _position(person: Person, graph: NavGraph) -> np.ndarray:
    if person.position is not None:
        return np.asarray(person.position, dtype=float)
    # Person guarantees a viewpoint when it has no position.
    return graph.position(str(person.viewpoint))
