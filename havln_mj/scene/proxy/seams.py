"""Floor boxes that overlap where they meet, so that no foot is caught between two of them.

A legged body's feet are soft spheres: a loaded foot sinks until its centre nears the floor's
top. Where two coplanar boxes meet face to face, MuJoCo's sphere–box contact then takes the
side face of each, and their two opposed pushes clamp the foot (with the friction on them, a
swing cannot lift it): the body trips on a flat floor. Where one box reaches ``SEAM_OVERLAP`` past
the line, the two faces lie apart, inside the other box, and each pushes a foot one way only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from havln_mj.scene.proxy.params import ProxyParams

# metres: keeps a loaded foot off the side face under it (bench_go1_terrain --parts seams), and
# no more, as the strip covered twice stiffens the floor
SEAM_OVERLAP = 0.01
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

    def seams(self, cells: tuple[slice, slice], top: float) -> np.ndarray:
        """Per cell of a row or column of ``cells``: is a floor of ``top`` (any layer) free?"""
        with np.errstate(invalid="ignore"):
            return np.any(np.abs(self.tops[(slice(None), *cells)] - top) < _EPS, axis=0).ravel()

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
    lo: np.ndarray,
    hi: np.ndarray,
    rects: np.ndarray,
    room: LipRoom,
    covered: dict[float, tuple[np.ndarray, np.ndarray]],
) -> tuple[np.ndarray, np.ndarray]:
    """Floor boxes ``lo..hi`` on cell rectangles ``rects``, grown over their coplanar neighbours.

    Of two boxes that meet, one reaches ``SEAM_OVERLAP`` over the other: where a foot stands
    on both, their two contacts make the floor stiffer (the trot falls on a floor covered
    twice), so the strip covered twice is kept to one overlap. A side grows where it meets a
    floor of its top (of any layer), the lip fits in every cell past it (see
    :class:`LipRoom`) and no lip covers that stretch yet; shorter sides first, so that of a
    long side and the short ones across it, the short ones grow, and a side that would cover
    a strip twice only once no other can.

    Args:
        lo: (N, 3) box corners.
        hi: (N, 3) box corners.
        rects: (N, 4) cell rectangles (row0, row1, col0, col1), end-exclusive.
        room: Where lips fit, and which floors they meet.
        covered: Per floor top, the cell edges that lips cover: across x (rows, columns + 1),
            between columns c - 1 and c; across y (rows + 1, columns). Shared by a drawing's
            layers and updated here.
    """
    lo, hi = lo.copy(), hi.copy()
    h, w = room.spare.shape
    keys = np.round(hi[:, 2], 6)
    for key in map(float, np.unique(keys)):
        if key not in covered:
            covered[key] = (np.zeros((h, w + 1), bool), np.zeros((h + 1, w), bool))
    # Per side that meets a floor of its top: (length, box, axis, grows +, cells beyond it,
    # the cell edges it lies on, which of those are seams).
    sides = []
    for i, (r0, r1, c0, c1) in enumerate(rects):
        for length, axis, grows, inside, beyond, edges in (
            (r1 - r0, 0, True, c1 < w, np.s_[r0:r1, c1 : c1 + 1], np.s_[r0:r1, c1]),
            (r1 - r0, 0, False, c0 > 0, np.s_[r0:r1, c0 - 1 : c0], np.s_[r0:r1, c0]),
            (c1 - c0, 1, True, r1 < h, np.s_[r1 : r1 + 1, c0:c1], np.s_[r1, c0:c1]),
            (c1 - c0, 1, False, r0 > 0, np.s_[r0 - 1 : r0, c0:c1], np.s_[r0, c0:c1]),
        ):
            if inside and (seams := room.seams(beyond, hi[i, 2])).any():
                sides.append((length, i, axis, grows, beyond, edges, seams))
    sides.sort(key=lambda side: side[:2])
    waiting = []  # sides that would cover a strip twice: they wait for the rest
    for twice in (False, True):
        for side in waiting if twice else sides:
            _, i, axis, grows, beyond, edges, seams = side
            lipped = covered[float(keys[i])][axis][edges]
            if not np.any(seams & ~lipped):
                continue
            if not twice and np.any(seams & lipped):
                waiting.append(side)
            elif room.fits(beyond, lo[i, 2], hi[i, 2]):
                if grows:
                    hi[i, axis] += SEAM_OVERLAP
                else:
                    lo[i, axis] -= SEAM_OVERLAP
                lipped[:] = True
    return lo, hi
