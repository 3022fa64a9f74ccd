"""Discrete API side by side with the C++ Matterport3DSimulator: same actions, fresh processes.

The peer is the C++ MatterSim from ``shared/peers/mattersim`` (built with its ``build.sh``
into ``--build`` on first use, about a minute; never a dependency of the package). When it
cannot be found or built, the peer's rows are skipped with the reason and ours still run.

Every workload is a fixed plan drawn up front from a seed: episodes (scan, start viewpoint,
heading per batch element) of 30 steps, each step a random fraction ``r`` (navigable index
``int(r · len(navigableLocations))``) and a random heading change per element. A step is
``getState()`` + ``makeAction()`` for the whole batch; ``steps_per_s`` counts batch elements,
the unit MatterSim quotes. Each side runs the plan in a fresh process (graphs loaded and the
plan walked once untimed first, which also records the viewpoints visited), for ``--seconds``
of timed stepping (``newEpisode`` untimed); the sides alternate for ``--rounds`` rounds and the
medians are compared. ``cpu_ratio`` compares steps per CPU second of the stepping loop, which
holds steadier than wall time on a shared machine. ``same_path`` says whether both sides
visited the same viewpoints on the plan's first pass. ``compiled_signal`` says whether ours
ran the collision signal's compiled loop (``havln_mj.sim._closest``, built at install where a C
compiler was at hand) or its numpy path, ``compiled_navigation`` whether it ran the compiled
navigable-location query (``havln_mj.sim._navigable``) or its Python loop.

Workloads (rendering off; camera 640×480, vfov 60°, continuous headings, restricted
navigation, identical on both sides):

* ``real_b1``, ``real_b8``: the 90 real connectivity graphs (``--data``), batch 1 and 8.
* ``real_b8_discrete``: as ``real_b8`` with discretised viewing angles on both sides (each
  turn one 30° step in its direction).
* ``proc_b1``: the procedural houses ``proc-0``…``proc-4``: ours without people, ours with
  their people (``Simulator(humans=True)``, every action runs the collision check), MatterSim.
* ``proc0_30people``: ``proc-0`` alone, ours without people, with 30 people, MatterSim.

``--compare DIR`` also runs every side of ours from the package in ``DIR`` (a checkout of
another version, e.g. a ``git worktree`` of ``main``), as ``<side>@compare``, in the same
alternation, and adds the ratios of each side to its twin (``<side>/<side>@compare``).

Prints one JSON object. Run: ``python benchmarks/bench_peers.py [--seconds S] [--rounds N]``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import zlib
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SHARED = Path(os.environ.get("HAVLN_SHARED", HERE.parents[1] / "shared"))
EPISODE_STEPS = 30
PLAN_EPISODES = 600
CAMERA = (640, 480, math.radians(60))
PROC_SCANS = [f"proc-{k}" for k in range(5)]

# workload -> (graphs, batch, sides); a side is (name, simulator, people)
WORKLOADS = {
    "real_b1": ("real", 1, [("ours", "ours", "none"), ("mattersim", "mattersim", "none")]),
    "real_b8": ("real", 8, [("ours", "ours", "none"), ("mattersim", "mattersim", "none")]),
    "real_b8_discrete": (
        "real",
        8,
        [("ours", "ours", "none"), ("mattersim", "mattersim", "none")],
    ),
    "proc_b1": (
        "proc",
        1,
        [
            ("ours", "ours", "none"),
            ("ours_people", "ours", "default"),
            ("mattersim", "mattersim", "none"),
        ],
    ),
    "proc0_30people": (
        "proc0",
        1,
        [
            ("ours", "ours", "none"),
            ("ours_30people", "ours", "30"),
            ("mattersim", "mattersim", "none"),
        ],
    ),
}


# ---------------------------------------------------------------- the peer


def find_peer(build: Path, peers: Path) -> tuple[Path | None, str]:
    """The folder holding ``MatterSim*.so`` (built on first use), or None and why not."""
    found = sorted(build.glob("Matterport3DSimulator/build/MatterSim*.so"))
    if found:
        return found[0].parent, "found"
    script = peers / "mattersim" / "build.sh"
    if not script.is_file():
        return None, f"no MatterSim build in {build} and no build script at {script}"
    print(f"building the MatterSim peer into {build} (about a minute) ...", file=sys.stderr)
    done = subprocess.run(
        ["bash", str(script), str(build), sys.executable], capture_output=True, text=True
    )
    found = sorted(build.glob("Matterport3DSimulator/build/MatterSim*.so"))
    if done.returncode != 0 or not found:
        tail = (done.stderr or done.stdout).strip().splitlines()[-3:]
        return None, f"building MatterSim failed ({script}): {' | '.join(tail)}"
    return found[0].parent, "built"


# ---------------------------------------------------------------- graphs and plans


def _included(conn_file: Path) -> list[str]:
    return [v["image_id"] for v in json.loads(conn_file.read_text()) if v["included"]]


def graph_folder(kind: str, data: Path, tmp: Path) -> tuple[Path, list[str]]:
    """A MatterSim navigation-graph folder (``scans.txt`` + connectivity files) and its ids."""
    if kind == "real":
        conn = data / "mp3d_connectivity"
        return conn, (conn / "scans.txt").read_text().split()
    from havln_mj.scene.scan import load_scan  # builds the houses on first use

    ids = PROC_SCANS if kind == "proc" else PROC_SCANS[:1]
    folder = tmp / f"graphs-{kind}"
    folder.mkdir(exist_ok=True)
    for scan_id in ids:
        src = load_scan(scan_id).folder / "connectivity.json"
        shutil.copyfile(src, folder / f"{scan_id}_connectivity.json")
    (folder / "scans.txt").write_text("\n".join(ids) + "\n")
    return folder, ids


def make_plan(folder: Path, ids: list[str], batch: int, seed: int, path: Path) -> None:
    """Episodes and actions drawn up front, the same for every side."""
    rng = np.random.default_rng(seed)
    starts = {s: _included(folder / f"{s}_connectivity.json") for s in ids}
    scans = rng.integers(len(ids), size=(PLAN_EPISODES, batch))
    plan = {
        "scans": [[ids[k] for k in row] for row in scans.tolist()],
        "viewpoints": [
            [starts[ids[k]][int(rng.integers(len(starts[ids[k]])))] for k in row]
            for row in scans.tolist()
        ],
        "headings": rng.uniform(0, 2 * math.pi, (PLAN_EPISODES, batch)).tolist(),
        "picks": rng.random((PLAN_EPISODES, EPISODE_STEPS, batch)).tolist(),
        "turns": rng.uniform(-math.pi, math.pi, (PLAN_EPISODES, EPISODE_STEPS, batch)).tolist(),
    }
    path.write_text(json.dumps(plan))


# ---------------------------------------------------------------- the worker


def _thirty_people(scan_id, graph, rng):
    """30 people in a scan: HA3D's rule applied until 30 are placed (spots may repeat)."""
    from havln_mj.humans.crowd import Crowd
    from havln_mj.humans.population import populate
    from havln_mj.scene.scan import load_scan

    scan, people = load_scan(scan_id), []
    while len(people) < 30:
        people += populate(scan, rng, count=30).people
    return Crowd(people[:30])


def _simulator(which: str, people: str, graphs: Path, batch: int, discrete: bool = False):
    if which == "mattersim":
        import MatterSim  # the peer, on PYTHONPATH in this process only

        sim = MatterSim.Simulator()
        sim.setPreloadingEnabled(False)
    else:
        import havln_mj

        humans = {"none": False, "default": True, "30": _thirty_people}[people]
        sim = havln_mj.Simulator(humans=humans)
        sim.setPreloadingEnabled(True)
    sim.setNavGraphPath(str(graphs))
    sim.setRenderingEnabled(False)
    sim.setBatchSize(batch)
    sim.setCameraResolution(CAMERA[0], CAMERA[1])
    sim.setCameraVFOV(CAMERA[2])
    sim.setDiscretizedViewingAngles(discrete)
    sim.initialize()
    return sim


def _episode(sim, plan: dict, e: int, zeros: list[float], visited: list | None) -> tuple:
    """Walks episode ``e`` of the plan; returns (wall s, cpu s) of its steps."""
    sim.newEpisode(plan["scans"][e], plan["viewpoints"][e], plan["headings"][e], zeros)
    picks, turns = plan["picks"][e], plan["turns"][e]
    w0, c0 = time.perf_counter(), time.process_time()
    for s in range(EPISODE_STEPS):
        states = sim.getState()
        index = [int(r * len(st.navigableLocations)) for r, st in zip(picks[s], states)]  # noqa: B905
        sim.makeAction(index, turns[s], zeros)
        if visited is not None:
            visited.extend(st.location.viewpointId for st in sim.getState())
    return time.perf_counter() - w0, time.process_time() - c0


def worker(args: argparse.Namespace) -> None:
    plan = json.loads(Path(args.plan).read_text())
    batch = len(plan["scans"][0])
    t0 = time.perf_counter()
    sim = _simulator(args.worker, args.people, Path(args.graphs), batch, args.discrete)
    zeros = [0.0] * batch
    visited: list[str] = []
    for e in range(PLAN_EPISODES):  # untimed pass: loads everything, records the path
        _episode(sim, plan, e, zeros, visited)
    setup = time.perf_counter() - t0
    extra = {}
    if args.worker == "ours":
        from havln_mj.sim import navigation, proximity

        extra["compiled_signal"] = getattr(proximity, "_closest", None) is not None
        extra["compiled_navigation"] = getattr(navigation, "_window", None) is not None
    steps, wall, cpu, e = 0, 0.0, 0.0, 0
    while wall < args.seconds:
        w, c = _episode(sim, plan, e % PLAN_EPISODES, zeros, None)
        wall, cpu, steps, e = wall + w, cpu + c, steps + EPISODE_STEPS * batch, e + 1
    print(
        json.dumps(
            {
                "steps": steps,
                "steps_per_s": steps / wall,
                "steps_per_cpu_s": steps / cpu,
                "setup_s": setup,
                "path_crc": zlib.crc32("\n".join(visited).encode()),
                "rss_mb": int(Path("/proc/self/statm").read_text().split()[1])
                * os.sysconf("SC_PAGE_SIZE")
                / 2**20,
                **extra,
            }
        )
    )


# ---------------------------------------------------------------- the driver


def _run_side(
    side: tuple, plan: Path, graphs: Path, peer: Path | None, seconds: float, discrete: bool
) -> dict:
    _, which, people, package = side
    env = dict(os.environ)
    if which == "mattersim":
        env["PYTHONPATH"] = str(peer)
    elif package is not None:  # another version of ours
        env["PYTHONPATH"] = str(package)
    cmd = [sys.executable, __file__, "--worker", which, "--people", people]
    cmd += ["--plan", str(plan), "--graphs", str(graphs), "--seconds", str(seconds)]
    if discrete:
        cmd.append("--discrete")
    done = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=plan.parent)
    if done.returncode != 0:
        raise RuntimeError(f"{side[0]} worker failed:\n{done.stderr[-2000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def run_workload(name: str, args, tmp: Path, peer: Path | None) -> dict:
    kind, batch, sides = WORKLOADS[name]
    if peer is None:
        sides = [s for s in sides if s[1] != "mattersim"]
    sides = [(*s, None) for s in sides]
    if args.compare is not None:
        sides += [(f"{s[0]}@compare", s[1], s[2], args.compare) for s in sides if s[1] == "ours"]
    graphs, ids = graph_folder(kind, args.data, tmp)
    plan = tmp / f"plan-{name}.json"
    make_plan(graphs, ids, batch, args.seed, plan)
    runs: dict[str, list[dict]] = {s[0]: [] for s in sides}
    for r in range(args.rounds):
        order = sides if r % 2 == 0 else sides[::-1]
        for side in order:
            run = _run_side(side, plan, graphs, peer, args.seconds, name.endswith("_discrete"))
            runs[side[0]].append(run)
    out: dict = {"batch": batch, "scans": len(ids), "rounds": args.rounds}
    for side, rows in runs.items():
        out[side] = {
            "steps_per_s": round(statistics.median(r["steps_per_s"] for r in rows)),
            "steps_per_cpu_s": round(statistics.median(r["steps_per_cpu_s"] for r in rows)),
            "runs_steps_per_s": [round(r["steps_per_s"]) for r in rows],
            "setup_s": round(statistics.median(r["setup_s"] for r in rows), 2),
            "rss_mb": round(max(r["rss_mb"] for r in rows), 1),
        }
        for key in ("compiled_signal", "compiled_navigation"):  # ours: compiled code ran
            if key in rows[0]:
                out[side][key] = rows[0][key]
    crcs = {side: rows[0]["path_crc"] for side, rows in runs.items()}
    out["same_path"] = len(set(crcs.values())) == 1
    ratios = {}
    for a, b in (
        ("ours", "mattersim"),
        ("ours_people", "mattersim"),
        ("ours_people", "ours"),
        ("ours_30people", "ours"),
    ):
        for suffix in ("", "@compare"):
            a_, b_ = a + suffix, b if b == "mattersim" else b + suffix
            if a_ in out and b_ in out:
                ratios[f"{a_}/{b_}"] = round(out[a_]["steps_per_s"] / out[b_]["steps_per_s"], 3)
                ratios[f"{a_}/{b_}_cpu"] = round(
                    out[a_]["steps_per_cpu_s"] / out[b_]["steps_per_cpu_s"], 3
                )
    for side in runs:
        twin = f"{side}@compare"
        if twin in out:
            ratios[f"{side}/{twin}_cpu"] = round(
                out[side]["steps_per_cpu_s"] / out[twin]["steps_per_cpu_s"], 3
            )
    out["ratios"] = ratios
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    data = Path(os.environ.get("HAVLN_SHARED_DATA", SHARED / "data"))
    ap.add_argument("--data", type=Path, default=data)
    ap.add_argument("--peers", type=Path, default=SHARED / "peers")
    ap.add_argument("--build", type=Path, default=None, help="where the peer is (built)")
    ap.add_argument("--seconds", type=float, default=3.0, help="timed seconds per run")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workloads", nargs="+", default=list(WORKLOADS), choices=list(WORKLOADS))
    ap.add_argument("--compare", type=Path, default=None, help="another checkout of ours to run")
    # worker mode (one side in a fresh process)
    ap.add_argument("--worker", choices=["ours", "mattersim"], help=argparse.SUPPRESS)
    ap.add_argument("--people", default="none", help=argparse.SUPPRESS)
    ap.add_argument("--plan", help=argparse.SUPPRESS)
    ap.add_argument("--graphs", help=argparse.SUPPRESS)
    ap.add_argument("--discrete", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        worker(args)
        return 0
    if not (args.data / "mp3d_connectivity").is_dir() and any(
        WORKLOADS[w][0] == "real" for w in args.workloads
    ):
        print(f"connectivity graphs not found at {args.data} (set --data)", file=sys.stderr)
        return 1
    from common import machine

    cache = Path(os.environ.get("HAVLN_CACHE", Path.home() / ".cache" / "havln_mj"))
    build = args.build or cache / "peers"
    peer, how = find_peer(build, args.peers)
    if peer is None:
        print(f"MatterSim peer skipped: {how}", file=sys.stderr)
    result: dict = {
        "machine": machine(),
        "peer": {"mattersim": str(peer) if peer else None, "status": how},
        "seconds": args.seconds,
        "compare": str(args.compare) if args.compare else None,
        "workloads": {},
    }
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.workloads:
            result["workloads"][name] = run_workload(name, args, Path(tmp), peer)
    print(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
