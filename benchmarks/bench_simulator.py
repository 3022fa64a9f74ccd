"""Speed of the discrete Simulator API: steps/s with rendering off, fps with RGB-D, memory.

* **Rendering off**: random walks on the 90 real connectivity graphs (``--data``), batch 1 and
  batch 8. A step is ``getState()`` + ``makeAction()`` for the whole batch with a random
  navigable index and a random heading change per element (drawn up front, so the timing is
  the simulator's); a new random episode every 30 steps in a random scan. steps/s counts
  batch elements (batch 8 at 1,000 calls/s = 8,000 steps/s), the unit MatterSim quotes.
* **With people**: the same walk, rendering off, in procedural houses ``proc-0``…``proc-4``
  with their people (HA3D's placement rule), so every action runs the 16 Hz collision check;
  and in ``proc-0`` with 30 people.
* **RGB-D**: the same walk in the procedural house ``proc-0`` at 640×480 and 128×128 with
  depth on; fps = rendered frames per second of ``makeAction`` + ``getState``. Then 640×480
  with 4 people in the house, drawn in each style (``pieces``, the default, and ``capsules``).
* **Memory**: resident set size after each part (``/proc/self/statm``) and the peak.

Every rate is also given per CPU second of the timed calls (``*_per_cpu_s``), which holds
steadier than wall time on a shared machine.

``--compare DIR`` measures the package in ``DIR`` (a checkout of another version, e.g. a
``git worktree`` of an older commit) against this one: both in fresh processes, alternating,
``--rounds`` times, and prints the medians of each and their ratios (this one / ``DIR``).

Prints one JSON object. Run: ``python benchmarks/bench_simulator.py [--seconds S]``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np

EPISODE_STEPS = 30
STYLES = ("pieces", "capsules")


def _rss_mb() -> float:
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return round(pages * os.sysconf("SC_PAGE_SIZE") / 2**20, 1)


def _walk(sim, scans: list[str], batch: int, seconds: float, seed: int) -> dict:
    """Random walk for about ``seconds``; returns element-steps per (CPU) second."""
    rng = np.random.default_rng(seed)
    picks = rng.random((4096, batch)).tolist()
    turns = rng.uniform(-math.pi, math.pi, (4096, batch)).tolist()
    zeros = [0.0] * batch
    steps, calls, t_end = 0, 0, time.perf_counter() + seconds
    elapsed = cpu = 0.0
    while time.perf_counter() < t_end:
        sim.newRandomEpisode([scans[int(rng.integers(len(scans)))] for _ in range(batch)])
        t, c = time.perf_counter(), time.process_time()
        for _ in range(EPISODE_STEPS):
            states = sim.getState()
            row, turn = picks[calls % 4096], turns[calls % 4096]
            index = [int(r * len(s.navigableLocations)) for r, s in zip(row, states, strict=True)]
            sim.makeAction(index, turn, zeros)
            calls += 1
        elapsed += time.perf_counter() - t
        cpu += time.process_time() - c
        steps += EPISODE_STEPS * batch
    return {
        "batch": batch,
        "steps": steps,
        "steps_per_s": round(steps / elapsed),
        "steps_per_cpu_s": round(steps / cpu),
    }


def _rendering_off(conn: Path, seconds: float) -> list[dict]:
    import havln_mj as MatterSim  # noqa: N812 - MatterSim code, only the import changed

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


def _people(count: int | None):
    """A crowd factory: HA3D's rule with ``count`` people (placed again until there are)."""
    from havln_mj.humans.crowd import Crowd
    from havln_mj.humans.population import populate
    from havln_mj.scene.scan import load_scan

    def make(scan_id, graph, rng):
        scan, people = load_scan(scan_id), []
        while len(people) < count:
            people += populate(scan, rng, count=count).people
        return Crowd(people[:count])

    return True if count is None else make


def _with_people(seconds: float, scans: list[str], count: int | None) -> dict:
    import havln_mj as MatterSim  # noqa: N812

    sim = MatterSim.Simulator(humans=_people(count))
    sim.setRenderingEnabled(False)
    sim.initialize()
    for scan in scans:  # build the houses and their crowds before timing
        sim.newRandomEpisode([scan])
    people = len(sim.getHumanState()[0])
    _walk(sim, scans, 1, min(1.0, seconds), seed=0)
    row = _walk(sim, scans, 1, seconds, seed=3)
    row["scenes"] = scans
    row["people_in_last_scene"] = people
    row["rss_mb"] = _rss_mb()
    sim.close()
    return row


def _rgbd(seconds: float, width: int, height: int, people: int, style: str | None) -> dict:
    import havln_mj as MatterSim  # noqa: N812

    sim = MatterSim.Simulator(humans=_people(people) if people else False)
    sim.setCameraResolution(width, height)
    sim.setCameraVFOV(math.radians(60))
    sim.setDepthEnabled(True)
    row = {"scene": "proc-0", "resolution": f"{width}x{height}", "people": people}
    if style is not None:
        from havln_mj.sim.world import WorldOptions

        try:
            sim.set_world_options(WorldOptions(collision="none", people_style=style))
        except TypeError:  # a version without drawing styles draws people one way
            style = "only"
        row["style"] = style
    sim.initialize()
    sim.newRandomEpisode(["proc-0"])  # builds the world and the camera
    _walk(sim, ["proc-0"], 1, min(1.0, seconds), seed=0)
    walk = _walk(sim, ["proc-0"], 1, seconds, seed=2)
    row.update(fps=walk["steps_per_s"], fps_per_cpu_s=walk["steps_per_cpu_s"], rss_mb=_rss_mb())
    sim.close()
    return row


def measure(data: Path, seconds: float) -> dict:
    """Every part of the benchmark, in this process."""
    from common import machine

    conn = data / "mp3d_connectivity"
    procs = [f"proc-{k}" for k in range(5)]
    out = {"machine": machine(), "rendering_off": _rendering_off(conn, seconds)}
    out["rendering_off_with_people"] = _with_people(seconds, procs, None)
    out["rendering_off_30_people"] = _with_people(seconds, procs[:1], 30)
    out["rgbd"] = [_rgbd(seconds, w, h, 0, None) for w, h in ((640, 480), (128, 128))]
    out["rgbd_4_people"] = [_rgbd(seconds, 640, 480, 4, s) for s in STYLES]
    out["peak_rss_mb"] = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)
    return out


def _rates(result: dict) -> dict[str, float]:
    """The rates of one result, flat: ``part[/k]/unit -> value``."""
    flat = {}
    for part, rows in result.items():
        rows = rows if isinstance(rows, list) else [rows]
        for k, row in enumerate(rows):
            if not isinstance(row, dict):
                continue
            name = part if len(rows) == 1 else f"{part}/{row.get('style', row.get('batch', k))}"
            if part == "rgbd":
                name = f"rgbd/{row['resolution']}"
            for unit in ("steps_per_s", "steps_per_cpu_s", "fps", "fps_per_cpu_s"):
                if unit in row:
                    flat[f"{name}/{unit}"] = row[unit]
    return flat


def compare(other: Path, args: argparse.Namespace) -> dict:
    """This package against the one in ``other``, alternating fresh processes."""
    runs: dict[str, list[dict]] = {"before": [], "after": []}
    for r in range(args.rounds):
        for side in ("before", "after") if r % 2 == 0 else ("after", "before"):
            env = dict(os.environ)
            if side == "before":  # its own cache: scans built by another version stay apart
                env["PYTHONPATH"] = str(other)
                env["HAVLN_CACHE"] = str(args.before_cache)
            cmd = [sys.executable, __file__, "--data", str(args.data)]
            cmd += ["--seconds", str(args.seconds)]
            done = subprocess.run(cmd, capture_output=True, text=True, env=env, check=True)
            runs[side].append(json.loads(done.stdout))
    med = {
        side: {k: statistics.median(_rates(r)[k] for r in rows) for k in _rates(rows[0])}
        for side, rows in runs.items()
    }
    ratios = {
        k: round(med["after"][k] / med["before"][k], 3)
        for k in med["after"]
        if med["before"].get(k)
    }
    return {"before": str(other), "rounds": args.rounds, "medians": med, "ratios": ratios}


def main() -> int:
    default = Path(
        os.environ.get("HAVLN_SHARED_DATA", Path(__file__).resolve().parents[2] / "shared" / "data")
    )
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", type=Path, default=default)
    ap.add_argument("--seconds", type=float, default=5.0)
    ap.add_argument("--compare", type=Path, default=None, help="another checkout to measure")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument(
        "--before-cache",
        type=Path,
        default=Path(os.environ.get("HAVLN_CACHE", Path.home() / ".cache" / "havln_mj")).parent
        / "havln_mj-compare",
        help="HAVLN_CACHE of the version compared against",
    )
    args = ap.parse_args()
    if not (args.data / "mp3d_connectivity").is_dir():
        print(f"connectivity graphs not found at {args.data} (set --data)", file=sys.stderr)
        return 1
    if args.compare is not None:
        result = compare(args.compare.resolve(), args)
    else:
        result = measure(args.data, args.seconds)
    print(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
