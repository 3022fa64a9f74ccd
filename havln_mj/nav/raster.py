"""Plan-view convex polygons filled into a boolean grid at sub-cell precision.

A cell is filled when a polygon overlaps it at all (OpenCV's polygon fill at 1/256-cell
precision), so the centre of the last filled cell lies within half a cell of the polygon's
edge, on either side.
"""

from __future__ import annotations

from collections.abc import Iterable

import cv2
import numpy as np

_SHIFT = 8  # OpenCV fixed-point bits: polygons are placed at 1/256 of a cell
_LIMIT = float(2**30 >> _SHIFT)  # fixed-point bound that keeps OpenCV's int32 arithmetic safe


def rasterise(
    footprints: Iterable[np.ndarray],
    origin: tuple[float, float],
    shape: tuple[int, int],
    resolution: float,
) -> np.ndarray:
    """Cells overlapped by the convex hull of any of ``footprints``.

    Args:
        footprints: (k, 2) plan-view point sets; each is filled as its convex hull (an empty
            one adds nothing).
        origin: (x0, y0) of the grid's lower-left corner.
        shape: (H, W) cells, row 0 at the lowest y.
        resolution: Cell size in metres.

    Returns:
        (H, W) bool array.
    """
    image = np.zeros(shape, dtype=np.uint8)
    x0 = np.asarray(origin, dtype=float)
    for xy in footprints:
        if not len(xy):
            continue
        # OpenCV puts pixel (col, row) centres at integer coordinates.
        u = np.clip((xy - x0) / resolution - 0.5, -_LIMIT, _LIMIT)
        fixed = np.round(u * (1 << _SHIFT)).astype(np.int32).reshape(-1, 1, 2)
        cv2.fillConvexPoly(image, cv2.convexHull(fixed), 1, lineType=cv2.LINE_8, shift=_SHIFT)
    return image.astype(bool)
