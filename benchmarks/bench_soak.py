"""Memory soak: resident memory stays flat over a long run with people and rendered frames.

* **Steps**: 100,000 steps (``getState`` + ``makeAction`` with a random navigable index and
  heading change; a new random episode every 30 steps) with rendering off in the procedural
  houses ``proc-0``…``proc-4`` with their people, so every action runs the 16 Hz collision
  check against the crowd.
* **Frames**: the same walk for 5,000 steps with rendering on (RGB-D and the human mask, people
  drawn) in ``proc-0``: a frame per step and per new episode (``frames_rendered``).

Each part warms up first (tables, crowds, the world and its camera are made once), then reads
the resident set size (``/proc/self/statm``, after a garbage collection) every tenth of the
way. ``growth_mb`` is the last reading minus the first, ``spread_mb`` the largest minus the
smallest; ``flat`` says whether both stay within ``--tolerance-mb`` (default 5).

Prints one JSON object. Run: ``python benchmarks/bench_soak.py [--steps N] [--frames N]``.
"""

from __future__ import annotations

import argparse
import gc
import json
import math
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np
from common import machine

from havln_mj.sim.simulator import Simulator

EPISODE_STEPS = 30
READINGS = 10


def _rss_mb() -> float:
    gc.collect()
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


def _walk(sim: Simulator, scans: list[str], steps: int, rng: np.random.Generator) -> None:
    """``steps`` random steps, a new random episode every :data:`EPISODE_STEPS`."""
    for k in range(steps):
        if k % EPISODE_STEPS == 0:
            sim.newRandomEpisode([scans[int(rng.integers(len(scans)))]])
        state = sim.getState()[0]
        index = int(rng.random() * len(state.navigableLocations))
        sim.makeAction([index], [float(rng.uniform(-math.pi, math.pi))], [0.0])


def _soak(sim: Simulator, scans: list[str], total: int, warmup: int, tolerance: float) -> dict:
    rng = np.random.default_rng(0)
    _walk(sim, scans, warmup, rng)
    frames0 = sim.timing()["frames"]
    readings = [_rss_mb()]
    t = time.perf_counter()
    chunk = total // READINGS
    for _ in range(READINGS):
        _walk(sim, scans, chunk, rng)
        readings.append(_rss_mb())
    seconds = time.perf_counter() - t
    growth, spread = readings[-1] - readings[0], max(readings) - min(readings)
    return {
        "steps": chunk * READINGS,
        "warmup_steps": warmup,
        "seconds": round(seconds, 1),
        "steps_per_s": round(chunk * READINGS / seconds),
        "frames_rendered": sim.timing()["frames"] - frames0,
        "rss_mb": [round(r, 1) for r in readings],
        "growth_mb": round(growth, 2),
        "spread_mb": round(spread, 2),
        "flat": abs(growth) <= tolerance and spread <= tolerance,
    }


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=100_000)
    ap.add_argument("--frames", type=int, default=5_000)
    ap.add_argument("--size", type=int, nargs=2, default=(128, 128), metavar=("W", "H"))
    ap.add_argument("--tolerance-mb", type=float, default=5.0)
    args = ap.parse_args()
    if min(args.steps, args.frames) < READINGS:
        ap.error(f"--steps and --frames must be at least {READINGS}")

    scans = [f"proc-{k}" for k in range(5)]
    sim = Simulator(humans=True)
    sim.setRenderingEnabled(False)
    sim.initialize()
    steps = _soak(sim, scans, args.steps, 10_000, args.tolerance_mb)
    steps["scenes"] = scans
    steps["people"] = {s: len(sim.crowd(s)) for s in scans}
    sim.close()

    sim = Simulator(humans=True)
    sim.setCameraResolution(*args.size)
    sim.setDepthEnabled(True)
    sim.set_human_mask_enabled(True)
    sim.initialize()
    frames = _soak(sim, ["proc-0"], args.frames, 500, args.tolerance_mb)
    frames["size"] = list(args.size)
    frames["people"] = len(sim.crowd("proc-0"))
    sim.close()

    print(
        json.dumps(
            {
                "machine": machine(),
                "tolerance_mb": args.tolerance_mb,
                "steps_with_people": steps,
                "rendered_frames": frames,
                "flat": steps["flat"] and frames["flat"],
            },
            indent=1,
        )
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
