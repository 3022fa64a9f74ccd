"""Timed pelvis routes: a looping walk along waypoints, with rounded corners and pivots.

A route is where a walking person's pelvis is over the ground (``xy``), which way the body
faces (``yaw``: about +z, 0 facing +y, unwrapped) and how fast it moves, as a periodic
function of time. Gentle corners are rounded with circular arcs walked slower (the heading
turns at most :data:`MAX_TURN_RATE`); sharp ones (more than :data:`PIVOT_ANGLE`) and the ends
of an open path make the walker slow to a stop, turn on the spot and set off again.
Speeds change with bounded acceleration.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from havln_mj.errors import InvalidArgumentError

PIVOT_ANGLE = math.radians(100.0)
"""Corners sharper than this (radians) are turned on the spot."""
MAX_TURN_RATE = math.radians(90.0)
"""Fastest heading change (rad/s) while walking an arc."""
CORNER_RADIUS = 0.6  # metres, largest arc radius of a rounded corner
ACCEL = 0.8  # m/s², speeding up and slowing down
_DS = 0.01  # metres between route samples


@dataclass(frozen=True)
class Route:
    """A periodic pelvis route sampled at increasing times.

    Attributes:
        times: Sample times ``(M,)`` from 0 to ``period``.
        xy: Ground positions ``(M, 2)``.
        yaw: Body yaw ``(M,)``, unwrapped.
        speed: Ground speed ``(M,)`` in m/s.
        period: Seconds per loop.
    """

    times: np.ndarray
    xy: np.ndarray
    yaw: np.ndarray
    speed: np.ndarray
    period: float

    @property
    def winding(self) -> float:
        """Total heading change over one loop (a multiple of 2π)."""
        return float(self.yaw[-1] - self.yaw[0])

    def at(self, t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Ground position ``(..., 2)``, yaw and speed at times ``t``, looping."""
        t = np.asarray(t, float)
        laps = np.floor(t / self.period)
        local = t - laps * self.period
        xy = np.stack([np.interp(local, self.times, self.xy[:, i]) for i in range(2)], -1)
        yaw = np.interp(local, self.times, self.yaw) + laps * self.winding
        return xy, yaw, np.interp(local, self.times, self.speed)


def yaw_of(direction: np.ndarray) -> np.ndarray:
    """Body yaw facing a ground direction ``(..., 2)`` (0 faces +y, positive turns left)."""
    direction = np.asarray(direction, float)
    return np.arctan2(-direction[..., 0], direction[..., 1])


def loop_route(
    waypoints: np.ndarray,
    speed: float,
    rng: np.random.Generator,
    *,
    closed: bool = True,
    turn_time: float = 1.3,
    fps: float | None = None,
) -> Route:
    """The route of someone walking through ``waypoints`` over and over.

    A closed path is walked round and round; an open one (or any two points) back and forth.
    The route starts just after the first on-the-spot turn, from a standstill, facing the next
    waypoint; a path without such turns starts halfway along its first leg.

    Args:
        waypoints: Ground points ``(K, 2)``, K ≥ 2, in metres.
        speed: Walking speed on straight legs, m/s (0.2–2.5).
        rng: Picks the direction of 180° turns.
        closed: Whether the last waypoint connects back to the first.
        turn_time: Seconds for a 180° turn on the spot (smaller turns take less).
        fps: If given, the period is stretched (by under one frame) to a whole number of frames.

    Raises:
        InvalidArgumentError: Bad waypoints or speed.
    """
    pts = _clean_waypoints(waypoints)
    if not (math.isfinite(speed) and 0.2 <= speed <= 2.5):
        raise InvalidArgumentError(f"walking speed must be in 0.2..2.5 m/s, got {speed!r}")
    if not closed or len(pts) == 2:
        pts = np.concatenate([pts, pts[-2:0:-1]])  # there and back
    n = len(pts)
    seg = np.roll(pts, -1, axis=0) - pts  # segment i runs from point i to i+1
    length = np.linalg.norm(seg, axis=1)
    unit = seg / length[:, None]
    # Corner i joins segment i-1 to segment i; positive turns are to the left.
    u_in = np.roll(unit, 1, axis=0)
    cross = u_in[:, 0] * unit[:, 1] - u_in[:, 1] * unit[:, 0]
    turn = np.arctan2(cross, np.sum(u_in * unit, axis=1))
    reverse = np.abs(np.abs(turn) - math.pi) < 1e-6
    turn[reverse] = np.where(rng.random(int(reverse.sum())) < 0.5, -math.pi, math.pi)
    pivot = np.abs(turn) > PIVOT_ANGLE
    half = np.tan(np.abs(turn) / 2)
    cut = np.where(
        pivot, 0.0, np.minimum(CORNER_RADIUS * half, 0.45 * np.minimum(length, np.roll(length, 1)))
    )
    cut[np.abs(turn) < 1e-4] = 0.0

    # Walk the loop as straight legs, arcs and pivots, starting after a pivot if there is one.
    first = int(np.flatnonzero(pivot)[0]) if pivot.any() else None
    pieces: list[tuple] = []
    yaw = float(yaw_of(unit[first if first is not None else 0]))
    start_seg = first if first is not None else 0
    pos = pts[start_seg] + (0.0 if first is not None else 0.5) * seg[start_seg]
    for k in range(n):
        i = (start_seg + k) % n  # segment being walked
        j = (i + 1) % n  # the corner at its end
        corner_start = pts[j] - cut[j] * unit[i]
        pieces.append(("line", pos, corner_start, yaw))
        if pivot[j]:
            pieces.append(("pivot", pts[j], yaw, turn[j]))
        elif cut[j] > 0:
            pieces.append(("arc", corner_start, unit[i], turn[j], cut[j] / half[j], yaw))
        yaw += turn[j]
        pos = pts[j] + cut[j] * unit[j]
    if first is None:  # back to the middle of the first leg
        pieces.append(("line", pos, pts[0] + 0.5 * seg[0], yaw))
    return _timed(pieces, speed, turn_time, periodic=first is None, fps=fps)


def _clean_waypoints(waypoints: np.ndarray) -> np.ndarray:
    pts = np.asarray(waypoints, float)
    if pts.ndim != 2 or pts.shape[1] != 2 or not np.isfinite(pts).all():
        raise InvalidArgumentError(
            f"waypoints must be a finite (K, 2) array of ground points, got shape {pts.shape}"
        )
    keep = [0]
    for i in range(1, len(pts)):
        if np.linalg.norm(pts[i] - pts[keep[-1]]) > 0.05:
            keep.append(i)
    pts = pts[keep]
    if len(pts) > 2 and np.linalg.norm(pts[-1] - pts[0]) <= 0.05:
        pts = pts[:-1]
    if len(pts) < 2:
        raise InvalidArgumentError(
            "waypoints must hold at least two points more than 5 cm apart, got "
            f"{np.round(np.asarray(waypoints, float), 3).tolist()}"
        )
    return pts


def _sample_piece(piece: tuple) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions, yaws and curvatures along a line or arc, every ~1 cm, both ends included."""
    kind = piece[0]
    if kind == "line":
        _, a, b, yaw = piece
        m = max(2, math.ceil(np.linalg.norm(b - a) / _DS) + 1)
        f = np.linspace(0.0, 1.0, m)
        return a + f[:, None] * (b - a), np.full(m, yaw), np.zeros(m)
    _, a, u_in, turn, radius, yaw = piece
    m = max(2, math.ceil(abs(turn) * radius / _DS) + 1)
    f = np.linspace(0.0, 1.0, m)
    sgn = math.copysign(1.0, turn)
    alpha0 = math.atan2(u_in[1], u_in[0])
    alpha = alpha0 + turn * f
    centre = a - sgn * radius * np.array([math.sin(alpha0), -math.cos(alpha0)])
    xy = centre + sgn * radius * np.stack([np.sin(alpha), -np.cos(alpha)], -1)
    return xy, yaw + turn * f, np.full(m, 1.0 / radius)


def _speed_profile(ds: np.ndarray, limit: np.ndarray, stop_ends: bool) -> np.ndarray:
    """Fastest speeds under ``limit`` with |acceleration| ≤ ACCEL (stopping at the ends)."""
    v = limit.copy()
    if stop_ends:
        v[0] = v[-1] = 0.0
    for idx in (range(1, len(v)), range(len(v) - 2, -1, -1)):
        step = -1 if idx.step < 0 else 1
        for i in idx:
            v[i] = min(v[i], math.sqrt(v[i - step] ** 2 + 2 * ACCEL * ds[min(i, i - step)]))
    return v


def _timed(pieces: list[tuple], speed: float, turn_time: float, periodic: bool, fps):
    """Times the pieces: moves follow the speed profile, pivots take their turn time."""
    chunks: list[tuple[np.ndarray, ...]] = []
    t = 0.0

    def add(tt: np.ndarray, xy: np.ndarray, yw: np.ndarray, v: np.ndarray) -> None:
        k = 1 if chunks else 0  # a chunk's first sample repeats the previous one's last
        chunks.append((tt[k:], xy[k:], yw[k:], v[k:]))

    def add_move(move: list[tuple]) -> None:
        nonlocal t
        parts = [_sample_piece(p) for p in move]
        xy, yw, kappa = (
            np.concatenate([p[c][(k > 0) :] for k, p in enumerate(parts)]) for c in range(3)
        )
        ds = np.linalg.norm(np.diff(xy, axis=0), axis=1)
        limit = np.minimum(speed, MAX_TURN_RATE / np.maximum(kappa, 1e-9))
        if periodic:  # the loop's end runs into its start: profile three laps, keep the middle
            m = len(ds)
            v3 = _speed_profile(np.tile(ds, 3), np.tile(limit[:-1], 3), stop_ends=False)
            v = np.append(v3[m : 2 * m], v3[m])
        else:
            v = _speed_profile(ds, limit, stop_ends=True)
        dt = 2 * ds / np.maximum(v[:-1] + v[1:], 1e-9)
        tt = t + np.concatenate([[0.0], np.cumsum(dt)])
        add(tt, xy, yw, v)
        t = float(tt[-1])

    move: list[tuple] = []
    for piece in pieces:
        if piece[0] != "pivot":
            move.append(piece)
            continue
        add_move(move)
        move = []
        _, at, yaw0, turn = piece
        duration = turn_time * (0.35 + 0.65 * abs(turn) / math.pi)
        f = np.linspace(0.0, 1.0, max(3, math.ceil(duration * 60)))
        smooth = f**3 * (10 - 15 * f + 6 * f**2)
        add(t + duration * f, np.tile(at, (len(f), 1)), yaw0 + turn * smooth, 0 * f)
        t += duration
    if move:
        add_move(move)
    times, xy, yaw, v = (np.concatenate([c[i] for c in chunks]) for i in range(4))
    period = float(times[-1])
    scale = max(1, round(period * fps)) / fps / period if fps is not None else 1.0
    return Route(times * scale, xy, yaw, v / scale, period * scale)
