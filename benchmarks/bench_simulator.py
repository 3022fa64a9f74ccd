"""Speed of the discrete Simulator API: steps/s with rendering off, fps with RGB-D, memory.

* **Rendering off**: random walks on the 90 real connectivity graphs (``--data``), batch 1 and
  batch 8. A step is ``getState()`` + ``makeAction()`` for the whole batch with a random
  navigable index and a random heading change per element (drawn up front, so the timing is
  the simulator's); a new random episode every 30 steps in a random scan. steps/s counts
  batch elements (batch 8 at 1,000 calls/s = 8,000 steps/s), the unit MatterSim quotes.
* **With people**: the same walk, rendering off, in procedural houses ``proc-0``…``proc-4``
  with their people (HA3D's placement rule), so every action runs the 16 Hz collision check.
* **RGB-D**: the same walk in the procedural house ``proc-0`` at 640×480 and 128×128 with
  depth on; fps = rendered frames per second of ``makeAction`` + ``getState``.
* **Memory**: resident set size after each part (``/proc/self/statm``) and the peak.

Prints one JSON object. Run: ``python benchmarks/bench_simulator.py [--seconds S]``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import sys
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np
from common import machine

import havln_mj as MatterSim  # noqa: N812 - MatterSim code, only the import changed

EPISODE_STEPS = 30


def _rss_mb() -> float:
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return round(pages * os.sysconf("SC_PAGE_SIZE") / 2**20, 1)


def _walk(sim, scans: list[str], batch: int, seconds: float, seed: int) -> dict:
    """Random walk for about ``seconds``; returns element-steps per second."""
    rng = np.random.default_rng(seed)
    picks = rng.random((4096, batch)).tolist()
    turns = rng.uniform(-math.pi, math.pi, (4096, batch)).tolist()
    zeros = [0.0] * batch
    steps, calls, t_end = 0, 0, time.perf_counter() + seconds
    elapsed = 0.0
    while time.perf_counter() < t_end:
        sim.newRandomEpisode([scans[int(rng.integers(len(scans)))] for _ in range(batch)])
        t = time.perf_counter()
        for _ in range(EPISODE_STEPS):
            states = sim.getState()
            row, turn = picks[calls % 4096], turns[calls % 4096]
            index = [int(r * len(s.navigableLocations)) for r, s in zip(row, states, strict=True)]
            sim.makeAction(index, turn, zeros)
            calls += 1
        elapsed += time.perf_counter() - t
        steps += EPISODE_STEPS * batch
    return {"batch": batch, "steps": steps, "steps_per_s": round(steps / elapsed)}


def _rendering_off(conn: Path, seconds: float) -> list[dict]:
    scans = (conn / "scans.txt").read_text().split()
    rows = []
    for batch in (1, 8):
        sim = MatterSim.Simulator()
        sim.setNavGraphPath(str(conn))
        sim.setRenderingEnabled(False)
        sim.setBatchSize(batch)
        sim.setPreloadingEnabled(True)  # load the 90 graphs before timing
        t = time.perf_counter()
        sim.initialize()
        preload = time.perf_counter() - t
        _walk(sim, scans, batch, min(1.0, seconds), seed=0)  # warm every table a little
        row = _walk(sim, scans, batch, seconds, seed=1)
        row["preload_s"] = round(preload, 2)
        row["rss_mb"] = _rss_mb()
        rows.append(row)
        sim.close()
    return rows


def _with_people(seconds: float) -> dict:
    scans = [f"proc-{k}" for k in range(5)]
    sim = MatterSim.Simulator(humans=True)
    sim.setRenderingEnabled(False)
    sim.initialize()
    for scan in scans:  # build the houses and their crowds before timing
        sim.newRandomEpisode([scan])
    people = len(sim.getHumanState()[0])
    row = _walk(sim, scans, 1, seconds, seed=3)
    row["scenes"] = scans
    row["people_in_last_scene"] = people
    row["rss_mb"] = _rss_mb()
    sim.close()
    return row


def _rendering(seconds: float) -> list[dict]:
    rows = []
    for width, height in ((640, 480), (128, 128)):
        sim = MatterSim.Simulator()
        sim.setCameraResolution(width, height)
        sim.setCameraVFOV(math.radians(60))
        sim.setDepthEnabled(True)
        sim.initialize()
        sim.newRandomEpisode(["proc-0"])  # builds the world and the camera
        row = _walk(sim, ["proc-0"], 1, seconds, seed=2)
        rows.append(
            {
                "scene": "proc-0",
                "resolution": f"{width}x{height}",
                "fps": row["steps_per_s"],
                "rss_mb": _rss_mb(),
            }
        )
        sim.close()
    return rows


def main() -> int:
    default = Path(
        os.environ.get("HAVLN_SHARED_DATA", Path(__file__).resolve().parents[2] / "shared" / "data")
    )
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", type=Path, default=default)
    ap.add_argument("--seconds", type=float, default=5.0)
    args = ap.parse_args()
    conn = args.data / "mp3d_connectivity"
    if not conn.is_dir():
        print(f"connectivity graphs not found at {conn} (set --data)", file=sys.stderr)
        return 1
    off = _rendering_off(conn, args.seconds)
    people = _with_people(args.seconds)
    rgbd = _rendering(args.seconds)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(
        json.dumps(
            {
                "machine": machine(),
                "rendering_off": off,
                "rendering_off_with_people": people,
                "rgbd": rgbd,
                "peak_rss_mb": round(peak, 1),
            },
            indent=1,
        )
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
