"""A scan's navigation graph, with the rules of Matterport3DSimulator and R2R evaluation.

Two views of the same ``unobstructed`` flags are kept apart, as the original code does:

* ``neighbors`` follows MatterSim's ``navigableLocations``: directed, j is reachable from i
  when ``unobstructed[i][j]`` is true and j is included.
* The graph used for distances, paths and components follows R2R ``eval.py``: undirected,
  an edge joins included i and j when either ``unobstructed[i][j]`` or ``unobstructed[j][i]``
  is set, weighted by the Euclidean distance between the two positions.

Nodes are the included viewpoints (isolated ones too). In the 90 MatterSim files the flags
are symmetric, so both views agree there.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from itertools import pairwise
from pathlib import Path

import numpy as np

from havln_mj.errors import InvalidArgumentError, UnknownViewpointError, did_you_mean
from havln_mj.scene.connectivity import Connectivity, read_connectivity


class NavGraph:
    """The navigation graph of one scan.

    All-pairs geodesic distances and predecessors are computed once, on first use, and
    reused by ``distance``, ``distances_from`` and ``shortest_path``.

    Attributes:
        connectivity: The underlying ``Connectivity``.
        name: The scan id (or the data's source when it is not a connectivity file).
        ids: All viewpoint ids, included or not, in file order.
        nodes: The included viewpoint ids, in file order.
    """

    def __init__(self, connectivity: Connectivity) -> None:
        """Builds the graph.

        Args:
            connectivity: The scan's viewpoints and flags.
        """
        c = connectivity
        self.connectivity = c
        self.name = c.scan
        self.ids: tuple[str, ...] = c.ids
        self._index = {vp: i for i, vp in enumerate(c.ids)}
        self._positions = c.positions
        self._positions.flags.writeable = False
        self._floor_z = c.floor_z

        # Graph-local numbering: node k is file entry self._node_ix[k].
        self._node_ix = np.flatnonzero(c.included)
        self.nodes: tuple[str, ...] = tuple(c.ids[i] for i in self._node_ix)
        self._node = {vp: k for k, vp in enumerate(self.nodes)}

        sub = c.unobstructed[np.ix_(self._node_ix, self._node_ix)]
        adj = sub | sub.T
        np.fill_diagonal(adj, False)  # a viewpoint is not its own neighbour
        self._adjacency = adj
        self._node_pos = self._positions[self._node_ix]
        self._dist: np.ndarray | None = None
        self._pred: np.ndarray | None = None

    @classmethod
    def from_file(cls, path: str | Path) -> NavGraph:
        """Reads a ``<scan>_connectivity.json`` file (see ``read_connectivity``) into a graph.

        Raises:
            MissingDataError: The file does not exist.
            MalformedDataError: The file does not follow the connectivity schema.
        """
        return cls(read_connectivity(path))

    def __repr__(self) -> str:
        return (
            f"NavGraph({self.name!r}, viewpoints={len(self.ids)}, nodes={self.num_nodes}, "
            f"edges={self.num_edges})"
        )

    def __contains__(self, vp: object) -> bool:
        """Whether ``vp`` is a node, i.e. an included viewpoint id."""
        return vp in self._node

    # Viewpoint look-ups.

    def index(self, vp: str) -> int:
        """Returns the viewpoint's index in the connectivity file (MatterSim's ``ix``).

        Raises:
            UnknownViewpointError: ``vp`` is not in this scan.
        """
        try:
            return self._index[vp]
        except (KeyError, TypeError):
            raise UnknownViewpointError(
                f"unknown viewpoint {vp!r} in scan {self.name}.{did_you_mean(str(vp), self.ids)}"
            ) from None

    def is_included(self, vp: str) -> bool:
        """Whether the simulator uses ``vp`` (False for excluded overlapping duplicates).

        Raises:
            UnknownViewpointError: ``vp`` is not in this scan.
        """
        return bool(self.connectivity.included[self.index(vp)])

    def position(self, vp: str) -> np.ndarray:
        """Returns the viewpoint's (3,) position in metres, z up (included or not).

        Raises:
            UnknownViewpointError: ``vp`` is not in this scan.
        """
        return self._positions[self.index(vp)].copy()

    def floor_z(self, vp: str) -> float:
        """Returns the floor height under the viewpoint: position z minus camera height.

        Raises:
            UnknownViewpointError: ``vp`` is not in this scan.
        """
        return float(self._floor_z[self.index(vp)])

    def _node_index(self, vp: str) -> int:
        """Graph-local index of an included viewpoint; raises for unknown or excluded ones."""
        k = self._node.get(vp) if isinstance(vp, str) else None
        if k is None:
            self.index(vp)  # raises for an unknown viewpoint
            raise UnknownViewpointError(
                f"viewpoint {vp!r} in scan {self.name} is excluded (an overlapping duplicate); "
                "it is not part of the navigation graph"
            )
        return k

    # Structure.

    def neighbors(self, vp: str) -> list[str]:
        """Returns the viewpoints MatterSim lets the agent move to from ``vp``, in file order.

        The rule is directed: j is listed when ``unobstructed[vp][j]`` is set and j is
        included. ``vp`` itself is never listed.

        Raises:
            UnknownViewpointError: ``vp`` is unknown or excluded (MatterSim raises ValueError).
        """
        k = self._node_index(vp)
        row = self.connectivity.unobstructed[self._node_ix[k], self._node_ix].copy()
        row[k] = False
        return [self.nodes[j] for j in np.flatnonzero(row)]

    @property
    def num_nodes(self) -> int:
        """Number of included viewpoints."""
        return len(self.nodes)

    @property
    def num_edges(self) -> int:
        """Number of undirected edges."""
        return int(np.count_nonzero(self._adjacency)) // 2

    def edges(self) -> list[tuple[str, str, float]]:
        """Returns every undirected edge once as ``(a, b, length)``, a before b in file order."""
        rows, cols = np.nonzero(np.triu(self._adjacency, 1))
        lengths = self._edge_lengths(rows, cols)
        return [
            (self.nodes[i], self.nodes[j], float(w))
            for i, j, w in zip(rows.tolist(), cols.tolist(), lengths.tolist(), strict=True)
        ]

    def degree(self, vp: str) -> int:
        """Returns the number of undirected edges at ``vp``.

        Raises:
            UnknownViewpointError: ``vp`` is unknown or excluded.
        """
        return int(np.count_nonzero(self._adjacency[self._node_index(vp)]))

    def components(self) -> list[list[str]]:
        """Returns the connected components, largest first, each in file order.

        Ties in size keep file order of the components' first viewpoints. An included
        viewpoint without edges is a component of its own.
        """
        if not self.nodes:
            return []
        from scipy.sparse.csgraph import connected_components  # a large import, used rarely

        _, labels = connected_components(self._sparse(), directed=False)
        groups: dict[int, list[str]] = {}
        for vp, label in zip(self.nodes, labels.tolist(), strict=True):
            groups.setdefault(label, []).append(vp)
        # Dicts keep insertion order, i.e. order of first appearance in the file.
        return sorted(groups.values(), key=len, reverse=True)

    def is_connected(self) -> bool:
        """Whether every included viewpoint can reach every other."""
        return len(self.components()) <= 1

    # Geodesics.

    def _all_pairs(self) -> tuple[np.ndarray, np.ndarray]:
        if self._dist is None or self._pred is None:
            from scipy.sparse.csgraph import dijkstra  # a large import, used rarely

            dist, pred = dijkstra(self._sparse(), directed=False, return_predecessors=True)
            dist.flags.writeable = False
            self._dist, self._pred = dist, pred
        return self._dist, self._pred

    def distance_matrix(self) -> np.ndarray:
        """Returns the read-only (num_nodes, num_nodes) geodesic distances, ordered as ``nodes``.

        Unreachable pairs hold ``inf``.
        """
        return self._all_pairs()[0]

    def distance(self, a: str, b: str) -> float:
        """Returns the geodesic distance in metres from ``a`` to ``b``.

        Returns:
            The length of a shortest path, ``0.0`` when ``a == b`` and ``math.inf`` when ``b``
            cannot be reached.

        Raises:
            UnknownViewpointError: ``a`` or ``b`` is unknown or excluded.
        """
        i, j = self._node_index(a), self._node_index(b)
        return float(self._all_pairs()[0][i, j])

    def distances_from(self, a: str) -> dict[str, float]:
        """Returns the geodesic distance from ``a`` to every node, ``math.inf`` if unreachable.

        Raises:
            UnknownViewpointError: ``a`` is unknown or excluded.
        """
        row = self._all_pairs()[0][self._node_index(a)]
        return dict(zip(self.nodes, row.tolist(), strict=True))

    def shortest_path(self, a: str, b: str) -> list[str]:
        """Returns a shortest path from ``a`` to ``b``: ``a`` first, ``b`` last.

        Raises:
            UnknownViewpointError: ``a`` or ``b`` is unknown or excluded.
            InvalidArgumentError: ``b`` cannot be reached from ``a``.
        """
        i, j = self._node_index(a), self._node_index(b)
        dist, pred = self._all_pairs()
        if math.isinf(dist[i, j]):
            raise InvalidArgumentError(
                f"no path from {a!r} to {b!r} in scan {self.name}: they lie in different "
                "connected components"
            )
        path = [j]
        while path[-1] != i:
            path.append(int(pred[i, path[-1]]))
        return [self.nodes[k] for k in reversed(path)]

    def path_length(self, path: Sequence[str]) -> float:
        """Returns the summed Euclidean length of the edges along ``path``.

        Repeated consecutive viewpoints (staying in place) add nothing; an empty or
        one-viewpoint path has length 0.

        Raises:
            UnknownViewpointError: A viewpoint is unknown or excluded.
            InvalidArgumentError: Two consecutive distinct viewpoints are not joined by an edge.
        """
        ks = [self._node_index(vp) for vp in path]
        total = 0.0
        for step, (i, j) in enumerate(pairwise(ks)):
            if i == j:
                continue
            if not self._adjacency[i, j]:
                raise InvalidArgumentError(
                    f"path step {step}: {path[step]!r} -> {path[step + 1]!r} is not an edge "
                    f"of scan {self.name}"
                )
            total += math.dist(self._node_pos[i], self._node_pos[j])
        return total

    def _sparse(self):
        """The edges as a ``scipy.sparse`` matrix of lengths (made on each use)."""
        from scipy.sparse import csr_matrix

        rows, cols = np.nonzero(self._adjacency)
        # Explicit zeros in a sparse matrix stay edges of length 0 for csgraph.
        n = len(self.nodes)
        return csr_matrix((self._edge_lengths(rows, cols), (rows, cols)), shape=(n, n))

    def _edge_lengths(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        return np.linalg.norm(self._node_pos[rows] - self._node_pos[cols], axis=1)


LEVEL_GAP = 1.0  # metres: viewpoint floors further apart than this are separate storeys
STAIR_CLIMB = 0.3
"""Metres of floor height an edge must climb (or descend) to be a stair edge."""


def stair_edges(graph: NavGraph, path: Sequence[str]) -> list[tuple[str, str]]:
    """The edges of ``path`` that climb or descend more than :data:`STAIR_CLIMB`."""
    return [
        (a, b)
        for a, b in itertools.pairwise(path)
        if abs(graph.floor_z(a) - graph.floor_z(b)) > STAIR_CLIMB
    ]


def level_groups(graph: NavGraph, gap: float = LEVEL_GAP) -> list[list[str]]:
    """Included viewpoints grouped into storeys, lowest first.

    A storey starts at the lowest viewpoint floor not yet assigned and takes every viewpoint
    whose floor is at most ``gap`` above that.
    """
    nodes = sorted(graph.nodes, key=graph.floor_z)
    groups: list[list[str]] = []
    for vp in nodes:
        if not groups or graph.floor_z(vp) - graph.floor_z(groups[-1][0]) > gap:
            groups.append([])
        groups[-1].append(vp)
    return groups
