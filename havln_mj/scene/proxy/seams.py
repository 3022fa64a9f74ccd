"""Floor boxes that overlap where they meet, so that no foot is caught between two of them.

A legged body's feet are soft spheres: a loaded foot sinks until its centre nears the floor's
top. Where two coplanar boxes meet face to face, MuJoCo's sphere–box contact then takes the
side face of each, and their two opposed pushes clamp the foot (with the friction on them, a
swing cannot lift it): the body trips on a flat floor. A box that reaches ``SEAM_OVERLAP`` past
the line puts its neighbour's face inside itself, where only an upward push is left.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from havln_mj.scene.proxy.params import ProxyParams

# metres: more than a loaded foot's centre sinks below the top
SEAM_OVERLAP = 0.02
_EPS = 1e-6  # metres


@dataclass(frozen=True)
class LipRoom:
    """Where one layer's floor boxes may reach past their cells, and which floors they meet.

    A lip fits in a cell that is spare, or inside the layer's wall there, or clear of the band
    of every body walking a path (of any layer) within reach of the cell: above the band, or
    low enough to be stepped over (a lip over a floor a step lower only moves its ledge).
    """

    tops: np.ndarray  # (layers, rows, cols) drawn floor tops, nan where not free
    supports: np.ndarray  # (layers, rows, cols) the tops under paths, nan elsewhere
    spare: np.ndarray  # cells where any box may stand
    wall_z0: np.ndarray  # the layer's walls, nan where none
    wall_z1: np.ndarray
    p: ProxyParams

    def seam(self, cells: tuple[slice, slice], top: float) -> bool:
        """Whether a floor of ``top`` (of any layer) is free in any of ``cells``."""
        with np.errstate(invalid="ignore"):
            return bool(np.any(np.abs(self.tops[(slice(None), *cells)] - top) < _EPS))

    def fits(self, cells: tuple[slice, slice], bottom: float, top: float) -> bool:
        """Whether a lip spanning ``bottom..top`` fits in every cell of ``cells``."""
        with np.errstate(invalid="ignore"):
            walled = (self.wall_z0[cells] <= bottom + _EPS) & (self.wall_z1[cells] >= top - _EPS)
        rows, cols = np.nonzero(~(self.spare[cells] | walled))
        if not len(rows):
            return True
        # A lip pokes into the next cell: bodies one cell further than their reach meet it.
        n = self.p.reach_cells + 1
        r0 = max(cells[0].start + rows.min() - n, 0)
        c0 = max(cells[1].start + cols.min() - n, 0)
        near = self.supports[
            :, r0 : cells[0].start + rows.max() + n + 1, c0 : cells[1].start + cols.max() + n + 1
        ]
        low, high = self.p.body_z
        with np.errstate(invalid="ignore"):
            in_band = (near + high > bottom + _EPS) & (near + low < top - _EPS)
        return not bool(in_band.any())


def overlap_seams(
    lo: np.ndarray, hi: np.ndarray, rects: np.ndarray, room: LipRoom
) -> tuple[np.ndarray, np.ndarray]:
    """Floor boxes ``lo..hi`` on cell rectangles ``rects``, grown over their coplanar neighbours.

    A side grows by ``SEAM_OVERLAP`` where it meets a floor of the same top (of any layer) and
    the lip fits in every cell past it (see :class:`LipRoom`).

    Args:
        lo: (N, 3) box corners.
        hi: (N, 3) box corners.
        rects: (N, 4) cell rectangles (row0, row1, col0, col1), end-exclusive.
        room: Where lips fit, and which floors they meet.
    """
    lo, hi = lo.copy(), hi.copy()
    h, w = room.spare.shape
    for i, (r0, r1, c0, c1) in enumerate(rects):
        sides = (
            (np.s_[r0:r1, c0 - 1 : c0], c0 > 0, lo, 0, -SEAM_OVERLAP),
            (np.s_[r0:r1, c1 : c1 + 1], c1 < w, hi, 0, SEAM_OVERLAP),
            (np.s_[r0 - 1 : r0, c0:c1], r0 > 0, lo, 1, -SEAM_OVERLAP),
            (np.s_[r1 : r1 + 1, c0:c1], r1 < h, hi, 1, SEAM_OVERLAP),
        )
        for beyond, inside, end, axis, step in sides:
            if inside and room.seam(beyond, hi[i, 2]) and room.fits(beyond, lo[i, 2], hi[i, 2]):
                end[i, axis] += step
    return lo, hi
