"""Dynamic time warping and its normalised form, nDTW (Ilharco et al. 2019)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.scene.navgraph import NavGraph


def dtw(cost: np.ndarray) -> float:
    """Returns the dynamic-time-warping distance for a (len R, len Q) cost matrix.

    The cost of the cheapest monotone alignment of the whole of both sequences:
    ``D[i, j] = cost[i, j] + min(D[i-1, j], D[i, j-1], D[i-1, j-1])``, result ``D[n-1, m-1]``.

    Raises:
        InvalidArgumentError: ``cost`` is not a non-empty 2-D array.
    """
    cost = np.asarray(cost, dtype=float)
    if cost.ndim != 2 or 0 in cost.shape:
        raise InvalidArgumentError(f"cost must be a non-empty 2-D array, got shape {cost.shape}")
    n, m = cost.shape
    acc = np.full((n + 1, m + 1), math.inf)
    acc[0, 0] = 0.0
    for i in range(1, n + 1):
        for j in range(1, m + 1):
            acc[i, j] = cost[i - 1, j - 1] + min(acc[i - 1, j], acc[i, j - 1], acc[i - 1, j - 1])
    return float(acc[n, m])


def ndtw(
    graph: NavGraph, reference: Sequence[str], query: Sequence[str], threshold: float = 3.0
) -> float:
    """Returns nDTW, ``exp(-DTW(R, Q) / (|R| * d_th))``, over geodesic distances.

    Args:
        graph: Supplies geodesic distances between viewpoints.
        reference: The reference path R.
        query: The agent's path Q (consecutive repeats should already be merged).
        threshold: The success distance d_th in metres.

    Raises:
        InvalidArgumentError: A path is empty or ``threshold`` is not positive.
        UnknownViewpointError: A viewpoint is unknown or excluded.
    """
    if not reference or not query:
        raise InvalidArgumentError("nDTW needs non-empty reference and query paths")
    if not threshold > 0:
        raise InvalidArgumentError(f"nDTW threshold must be > 0, got {threshold!r}")
    cost = np.array([[graph.distance(r, q) for q in query] for r in reference])
    return math.exp(-dtw(cost) / (len(reference) * threshold))
