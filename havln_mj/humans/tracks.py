"""Every person's pelvis track, tabulated once, read at many times in one vectorised call.

People are a pure function of simulated time: person k's pelvis at time t is their clip's
root at frame ``f = (t + start_k) · fps_k`` (looping past the last frame from ``loop_start``,
see :mod:`havln_mj.humans.clip`), turned by their heading and placed at their anchor. A
:class:`PelvisTable` does the turning and placing once per crowd, for every frame, and keeps
the world ``x + iy`` of all people in one array along one frame axis (person k's frames at
``base_k + i``). A query is then a few array operations over ``(times × people)`` and a single
``numpy.interp``: the frame arithmetic of :meth:`havln_mj.humans.crowd.Crowd.positions`
without its gathers, rotations and per-coordinate work (the values agree to rounding).
"""

from __future__ import annotations

import numpy as np

_SAFE_S = 1e-6  # seconds past everyone's entry into their loop before the short path is taken


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
        start_f = np.asarray(start, float) * fps  # start, in frames
        # From this simulated time on, every person is inside their loop.
        self.looping_from = float(np.max((loop - start_f) / fps, initial=0.0))
        # Per-person constants as columns: queries are (people × times), each row in order.
        col = lambda a: np.ascontiguousarray(a, float).reshape(-1, 1)  # noqa: E731
        self._fps = fps
        self._start_f, self._period, self._loop = col(start_f), col(period), col(loop)
        self._from_loop = col(start_f - loop)  # frames past loop_start at time 0
        self._loop_at = col(loop + base)  # where each loop begins on the axis
        self._last_at, self._base = col(last + base), col(base)

    def xy(self, times: np.ndarray, earliest: float | None = None) -> np.ndarray:
        """Everyone's pelvis ``x + iy`` at ``times (n,)``: complex ``(P, n)``.

        ``earliest`` (optional) is ``times.min()``, when the caller knows it.
        """
        f = np.multiply.outer(self._fps, times)
        if earliest is None:
            earliest = float(times.min()) if len(times) else 0.0
        if earliest >= self.looping_from + _SAFE_S:
            # Everyone is inside their loop: one wrap (of non-negative values), no branch.
            f += self._from_loop
            np.fmod(f, self._period, out=f)
            f += self._loop_at
        else:
            f += self._start_f
            wrapped = np.fmod(f - self._loop, self._period)
            wrapped += self._loop_at
            f += self._base
            f = np.where(f > self._last_at, wrapped, f)
        return np.interp(f, self.axis, self.values)
