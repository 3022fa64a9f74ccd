"""Every person's pelvis track, tabulated once, read at many times in one vectorised call.

People are a pure function of simulated time: person k's pelvis at time t is their clip's
root at frame ``f = (t + start_k) · fps_k`` (looping past the last frame from ``loop_start``,
see :mod:`havln_mj.humans.clip`), turned by their heading and placed at their anchor. A
:class:`PelvisTable` does the turning and placing once per crowd, for every frame, and keeps
the world ``x + iy`` of all people in one array along one frame axis (person k's frames at
``base_k + i``). A query is then a few array operations over ``(times × people)`` and a single
``numpy.interp``: the frame arithmetic of :meth:`havln_mj.humans.crowd.Crowd.positions`
without its gathers, rotations and per-coordinate work (the values agree to rounding).

Over the first :data:`UNROLLED_S` simulated seconds (every episode's start, where nearly every
query falls) the loops are also laid out unrolled, cycle after cycle, on an axis of their own:
a query there is one multiply-add and the interpolation, with no wrapping. Where a loop wraps,
its last frame and its ``loop_start`` frame share one axis position, so that just past it the
track goes on from ``loop_start`` as the wrap plays it (a loop whose ends differ jumps there).
The unrolled tracks take ``UNROLLED_S × fps`` positions per person (about 230 kB at 30 fps).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

try:  # numpy's compiled interpolation, without np.interp's argument handling
    from numpy._core.multiarray import interp_complex as _interp_complex
except ImportError:  # numpy < 2
    _interp_complex = np.interp

UNROLLED_S = 320.0
"""Simulated seconds from 0 over which every track is also kept unrolled (read unwrapped)."""
_SAFE_S = 1e-6  # seconds past everyone's entry into their loop before the short path is taken
_SUBSETS = 4096  # sets of people whose constants are kept


class PelvisTable:
    """The horizontal pelvis tracks of a crowd's people.

    Args:
        roots: Each person's clip root positions ``(T_k, 3)`` in their anchor frame.
        fps: Frames per second ``(P,)``.
        loop_start: First looping frame ``(P,)``.
        start: Seconds into the clip at simulated time 0 ``(P,)``.
        yaw: Each anchor's rotation about z ``(P, 3, 3)``.
        anchor: Anchor positions ``(P, 3)``.
    """

    def __init__(
        self,
        roots: list[np.ndarray],
        fps: np.ndarray,
        loop_start: np.ndarray,
        start: np.ndarray,
        yaw: np.ndarray,
        anchor: np.ndarray,
    ) -> None:
        n = len(roots)
        values, base, loop, period, last = [], np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
        offset = 0
        for k, root in enumerate(roots):
            xy = (anchor[k] + root @ yaw[k].T)[:, :2]
            frames = xy[:, 0] + 1j * xy[:, 1]
            last[k] = len(frames) - 1
            loop[k] = loop_start[k]
            period[k] = last[k] - loop[k]
            if period[k] == 0:
                # Past its end a clip without a loop holds its last frame: a loop of one
                # frame onto a copy of it plays exactly that.
                frames = np.append(frames, frames[-1])
                period[k] = 1.0
            base[k] = offset
            offset += len(frames)
            values.append(frames)
        self.size = n
        self.values = np.concatenate(values) if values else np.zeros(0, complex)
        self.axis = np.arange(len(self.values), dtype=float)
        fps = np.asarray(fps, float)
        start_f = np.asarray(start, float) * fps
        self.unrolled_axis, self.unrolled, unrolled_base, first = _unroll(
            values, last, loop, period, start_f + fps * UNROLLED_S
        )
        self._person = (fps, start_f, period, loop, last, base, start_f + unrolled_base)
        # Each person's (fps, where simulated time 0 is on the unrolled axis, the index of
        # their first position there), as Python numbers.
        zero_at = (start_f + unrolled_base).tolist()
        self.unrolled_frames = list(zip(fps.tolist(), zero_at, first, strict=True))
        self._everyone = _Columns(*self._person)
        self._subsets: dict[tuple[int, ...], _Columns] = {}

    def _columns(self, people: Sequence[int] | None) -> _Columns:
        if people is None or len(people) == self.size:
            return self._everyone
        key = tuple(people)
        cols = self._subsets.get(key)
        if cols is None:
            if len(self._subsets) >= _SUBSETS:
                self._subsets.clear()
            index = np.asarray(key, int)
            cols = self._subsets[key] = _Columns(*(a[index] for a in self._person))
        return cols

    def xy(
        self,
        times: np.ndarray,
        earliest: float | None = None,
        people: Sequence[int] | None = None,
        latest: float | None = None,
    ) -> np.ndarray:
        """Pelvis ``x + iy`` of ``people`` (default everyone) at ``times (n,)``: ``(P, n)``.

        ``earliest`` and ``latest`` (optional) are ``times.min()`` and ``times.max()``, when
        the caller knows them (``latest`` within :data:`UNROLLED_S`: the unrolled tracks are
        read).
        """
        c = self._columns(people)
        f = c.fps * times
        if latest is not None and latest <= UNROLLED_S:
            f += c.unrolled_at
            return _interp_complex(f, self.unrolled_axis, self.unrolled)
        if earliest is None:
            earliest = float(times.min()) if len(times) else 0.0
        if earliest >= c.looping_from + _SAFE_S:
            # Everyone is inside their loop: one wrap (of non-negative values), no branch.
            f += c.from_loop
            np.fmod(f, c.period, out=f)
            f += c.loop_at
        else:
            f += c.start_f
            wrapped = np.fmod(f - c.loop, c.period)
            wrapped += c.loop_at
            f += c.base
            f = np.where(f > c.last_at, wrapped, f)
        return _interp_complex(f, self.axis, self.values)


class _Columns:
    """Per-person constants of some people, as columns: queries are (people × times)."""

    __slots__ = (
        "base",
        "fps",
        "from_loop",
        "last_at",
        "loop",
        "loop_at",
        "looping_from",
        "period",
        "start_f",
        "unrolled_at",
    )

    def __init__(self, fps, start_f, period, loop, last, base, unrolled_at) -> None:
        col = lambda a: np.ascontiguousarray(a, float).reshape(-1, 1)  # noqa: E731
        self.fps = col(fps)
        self.start_f, self.period, self.loop = col(start_f), col(period), col(loop)
        self.from_loop = col(start_f - loop)  # frames past loop_start at time 0
        self.loop_at = col(loop + base)  # where each loop begins on the axis
        self.last_at, self.base = col(last + base), col(base)
        self.unrolled_at = col(unrolled_at)  # where simulated time 0 is on the unrolled axis
        # From this simulated time on, each of these people is inside their loop.
        self.looping_from = float(np.max((loop - start_f) / fps, initial=0.0))


def _unroll(
    values: list[np.ndarray],
    last: np.ndarray,
    loop: np.ndarray,
    period: np.ndarray,
    until: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[int]]:
    """Each person's frames played up to frame ``until[k]``, loops unrolled, on one axis.

    Returns:
        ``(axis, values, base, first)``: non-decreasing axis positions (a step of 1, or 0
        where a loop wraps), the ``x + iy`` there, where each person's frame 0 is on the axis
        (people one position apart), and the index of each person's first position.
    """
    axes, out, base, first = [], [], np.zeros(len(values)), []
    offset, index = 0.0, 0
    for k, frames in enumerate(values):
        lk, ok, pk = int(last[k]), int(loop[k]), int(period[k])
        cycles = max(0, math.ceil((until[k] - lk) / pk)) + 1  # one more: rounding
        steps = np.arange(pk + 1, dtype=float)
        # Frames 0..last, then each cycle loop_start..loop_start + period, its first frame at
        # the position of the cycle before's last one.
        axis = np.concatenate(
            [np.arange(lk + 1.0), (lk + np.add.outer(pk * np.arange(cycles), steps)).ravel()]
        )
        out += [frames[: lk + 1], np.tile(frames[ok : ok + pk + 1], cycles)]
        base[k] = offset
        first.append(index)
        axes.append(axis + offset)
        offset += axis[-1] + 1.0
        index += len(axis)
    if not axes:
        return np.zeros(0), np.zeros(0, complex), base, first
    return np.concatenate(axes), np.concatenate(out), base, first
