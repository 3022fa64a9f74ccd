"""Axis-aligned boxes: the exact geometry of procedural houses, and ray/segment tests on it.

Procedural houses are built from boxes (floors, walls, lintels, ceilings, furniture parts).
The same boxes become MuJoCo box geoms, the visual mesh, and the obstacles that decide the
navigation graph's ``unobstructed`` and ``visible`` flags.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from havln_mj.cache import atomic_write_json
from havln_mj.errors import MalformedDataError, MissingDataError

# Kinds of box; floors and ceilings never block an agent on the same level.
KINDS = ("floor", "ceiling", "wall", "furniture")
_EPS = 1e-9


@dataclass(frozen=True)
class BoxSet:
    """N axis-aligned boxes with their kind, material name and rgba colour."""

    lo: np.ndarray  # (N, 3)
    hi: np.ndarray  # (N, 3)
    kind: tuple[str, ...]
    material: tuple[str, ...]
    rgba: np.ndarray  # (N, 4)

    def __len__(self) -> int:
        return len(self.kind)

    def select(self, mask: np.ndarray) -> BoxSet:
        """The boxes where ``mask`` is true."""
        idx = np.flatnonzero(mask)
        return BoxSet(
            self.lo[idx],
            self.hi[idx],
            tuple(self.kind[i] for i in idx),
            tuple(self.material[i] for i in idx),
            self.rgba[idx],
        )

    def of_kind(self, *kinds: str) -> BoxSet:
        """The boxes whose kind is one of ``kinds``."""
        return self.select(np.array([k in kinds for k in self.kind], dtype=bool))

    def to_json(self) -> dict:
        """The ``boxes.json`` content (millimetre precision)."""
        return {
            "boxes": [
                {
                    "lo": [round(float(v), 4) for v in lo],
                    "hi": [round(float(v), 4) for v in hi],
                    "kind": kind,
                    "material": mat,
                    "rgba": [round(float(v), 4) for v in rgba],
                }
                for lo, hi, kind, mat, rgba in zip(
                    self.lo, self.hi, self.kind, self.material, self.rgba, strict=True
                )
            ]
        }

    def write(self, path: Path) -> None:
        """Writes ``boxes.json`` atomically."""
        atomic_write_json(path, self.to_json(), separators=(",", ":"))

    @classmethod
    def read(cls, path: Path) -> BoxSet:
        """Reads ``boxes.json``, raising MalformedDataError naming the bad entry."""
        if not path.is_file():
            raise MissingDataError(f"boxes file not found: {path}")
        try:
            entries = json.loads(path.read_text(encoding="utf-8"))["boxes"]
            lo = np.array([e["lo"] for e in entries], dtype=float).reshape(-1, 3)
            hi = np.array([e["hi"] for e in entries], dtype=float).reshape(-1, 3)
            kind = tuple(str(e["kind"]) for e in entries)
            material = tuple(str(e["material"]) for e in entries)
            rgba = np.array([e["rgba"] for e in entries], dtype=float).reshape(-1, 4)
        except (json.JSONDecodeError, KeyError, TypeError, ValueError) as exc:
            raise MalformedDataError(f"{path}: not a valid boxes file ({exc!r})") from exc
        bad = [k for k in kind if k not in KINDS]
        if bad:
            raise MalformedDataError(f"{path}: box kind {bad[0]!r} unknown; valid: {KINDS}")
        if np.any(hi < lo) or not np.all(np.isfinite(lo)) or not np.all(np.isfinite(hi)):
            raise MalformedDataError(f"{path}: boxes need finite lo <= hi on every axis")
        return cls(lo, hi, kind, material, rgba)


def interval_gaps(
    lo: float, hi: float, covers: list[tuple[float, float]], shortest: float = 1e-6
) -> list[tuple[float, float]]:
    """The stretches of [lo, hi] that no interval of ``covers`` covers, longer than ``shortest``.

    Along one line: the wall left beside a room's doors, the openings left between walls.
    """
    out, start = [], lo
    for a, b in sorted(covers):
        if a > start:
            out.append((start, min(a, hi)))
        start = max(start, b)
    if hi > start:
        out.append((start, hi))
    return [(a, b) for a, b in out if b - a > shortest]


def segments_hit_boxes(
    p0: np.ndarray, p1: np.ndarray, lo: np.ndarray, hi: np.ndarray, chunk: int = 4096
) -> np.ndarray:
    """For each segment p0[i] -> p1[i], whether it passes through any box (slab method).

    Works in any dimension (2-D footprints or 3-D boxes). Touching a face counts as a hit.

    Args:
        p0: (S, D) segment starts.
        p1: (S, D) segment ends.
        lo: (B, D) box minima.
        hi: (B, D) box maxima.
        chunk: Segments processed per batch (bounds memory at chunk × B × D).

    Returns:
        (S,) bool.
    """
    p0 = np.asarray(p0, dtype=float)
    d = np.asarray(p1, dtype=float) - p0
    out = np.zeros(len(p0), dtype=bool)
    if len(lo) == 0 or len(p0) == 0:
        return out
    for s in range(0, len(p0), chunk):
        o = p0[s : s + chunk, None, :]  # (C, 1, D)
        dd = d[s : s + chunk, None, :]
        parallel = np.abs(dd) < _EPS
        safe = np.where(parallel, 1.0, dd)
        t0 = (lo[None] - o) / safe
        t1 = (hi[None] - o) / safe
        tmin = np.where(parallel, -np.inf, np.minimum(t0, t1))
        tmax = np.where(parallel, np.inf, np.maximum(t0, t1))
        # A segment parallel to a slab must already lie inside it.
        inside = ~parallel | ((o >= lo[None] - _EPS) & (o <= hi[None] + _EPS))
        enter = np.maximum(tmin.max(axis=2), 0.0)
        leave = np.minimum(tmax.min(axis=2), 1.0)
        hit = (enter <= leave + _EPS) & inside.all(axis=2)
        out[s : s + chunk] = hit.any(axis=1)
    return out


def body_sweep_blocked(
    a: np.ndarray,
    b: np.ndarray,
    boxes: BoxSet,
    radius: float,
    z_range: tuple[float, float],
) -> np.ndarray:
    """Whether a vertical body swept from a[i] to b[i] touches any box.

    The body is a vertical column of horizontal radius ``radius`` spanning ``z_range`` above
    the floor. A box blocks the sweep when its z-extent overlaps the column's and its
    footprint, grown by ``radius`` (a conservative square Minkowski sum), meets the 2-D
    segment: one ray cast per pair against the grown footprints.

    Args:
        a: (S, 3) start floor points (x, y, z_floor).
        b: (S, 3) end floor points; must share a floor height with ``a`` within 0.05 m.
        boxes: Obstacles.
        radius: Body radius in metres.
        z_range: (low, high) heights of the body above its floor.

    Returns:
        (S,) bool.
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    out = np.zeros(len(a), dtype=bool)
    floors = np.round(a[:, 2], 2)
    for z in np.unique(floors):
        rows = np.flatnonzero(floors == z)
        zl, zh = z + z_range[0], z + z_range[1]
        near = (boxes.hi[:, 2] > zl) & (boxes.lo[:, 2] < zh)
        lo = boxes.lo[near, :2] - radius
        hi = boxes.hi[near, :2] + radius
        out[rows] = segments_hit_boxes(a[rows, :2], b[rows, :2], lo, hi)
    return out
