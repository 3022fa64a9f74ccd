"""What the package costs a process: import time and memory, per simulator, with rendering on.

Each case runs in a fresh process (``python bench_memory.py --case NAME``) and reports its
resident set size (``/proc/self/statm``) over a baseline taken in the same process after
``import numpy, mujoco`` (what any MuJoCo user pays), and which heavy modules got loaded:

* ``import``: ``import havln_mj`` and its ``Simulator`` (the MatterSim entry point).
* ``rendering_off``: one simulator, rendering off, the 90 real graphs preloaded (``--data``),
  a short random walk; then ``--extra`` more simulators doing the same: the memory each
  extra one adds (graphs are shared in a process).
* ``rendering_on``: one simulator on ``proc-0`` with its people, 640×480 RGB-D, a short walk;
  its resident set split (``/proc/self/smaps``) into anonymous memory (heap: model, GL
  textures, arrays) and file-backed pages (shared libraries), of which the OpenGL driver's
  (Mesa llvmpipe and its LLVM: a fixed cost shared by every process that renders).

Prints one JSON object. Run: ``python benchmarks/bench_memory.py``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HEAVY = ("scipy", "trimesh", "cv2", "coacd", "matplotlib", "networkx", "PIL", "torch")
SHARED_DATA = Path(
    os.environ.get("HAVLN_SHARED_DATA", Path(__file__).resolve().parents[2] / "shared" / "data")
)


def _rss_mb() -> float:
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


GL_DRIVER = ("libLLVM", "_dri.so", "libgallium", "libEGL", "libGL", "libglapi")


def _rss_split_mb() -> dict[str, float]:
    """Resident MB by kind: anonymous, file-backed, and the GL driver's part of the latter."""
    kb = {"anonymous": 0, "file": 0, "gl_driver": 0}
    path = ""
    for line in Path("/proc/self/smaps").read_text().splitlines():
        head = line.split(maxsplit=5)
        if "-" in head[0] and len(head) >= 5:  # a mapping's first line
            path = head[5] if len(head) > 5 else ""
        elif head[0] == "Rss:":
            kind = "file" if path.startswith("/") else "anonymous"
            kb[kind] += int(head[1])
            if kind == "file" and any(name in path for name in GL_DRIVER):
                kb["gl_driver"] += int(head[1])
    return {f"rss_{k}_mb": round(v / 1024, 1) for k, v in kb.items()}


def _walk(sim, scans: list[str], steps: int, seed: int) -> None:
    import numpy as np

    rng = np.random.default_rng(seed)
    batch = len(sim.getState()) if sim._batch and sim._batch.elements else 1
    for k in range(steps):
        if k % 30 == 0:
            sim.newRandomEpisode([scans[int(rng.integers(len(scans)))] for _ in range(batch)])
        states = sim.getState()
        index = [int(rng.integers(len(s.navigableLocations))) for s in states]
        sim.makeAction(index, rng.uniform(-1, 1, batch).tolist(), [0.0] * batch)


def _real_simulator(conn: Path):
    import havln_mj

    sim = havln_mj.Simulator()
    sim.setNavGraphPath(str(conn))
    sim.setRenderingEnabled(False)
    sim.setPreloadingEnabled(True)
    sim.initialize()
    return sim


def case(name: str, data: Path, extra: int) -> dict:
    os.environ.setdefault("MUJOCO_GL", "egl")
    import mujoco  # noqa: F401 - the baseline: what any MuJoCo user has loaded
    import numpy  # noqa: F401

    base = _rss_mb()
    t0 = time.perf_counter()
    import havln_mj

    havln_mj.Simulator  # noqa: B018 - the entry point, resolved lazily
    out = {"import_s": round(time.perf_counter() - t0, 3), "import_mb": round(_rss_mb() - base, 1)}
    if name == "rendering_off":
        conn = data / "mp3d_connectivity"
        scans = (conn / "scans.txt").read_text().split()
        sim = _real_simulator(conn)
        _walk(sim, scans, 3000, 0)
        one = _rss_mb()
        out["one_simulator_mb"] = round(one - base, 1)
        sims = []
        for k in range(extra):
            sims.append(_real_simulator(conn))
            _walk(sims[-1], scans, 3000, k + 1)
        out["extra_simulators"] = extra
        out["each_extra_simulator_mb"] = round((_rss_mb() - one) / max(extra, 1), 2)
    elif name == "rendering_on":
        sim = havln_mj.Simulator(humans=True)
        sim.setCameraResolution(640, 480)
        sim.setDepthEnabled(True)
        sim.initialize()
        _walk(sim, ["proc-0"], 60, 0)
        out["people"] = len(sim.getHumanState()[0])
        out["simulator_rss_mb"] = round(_rss_mb(), 1)
        out["simulator_over_baseline_mb"] = round(_rss_mb() - base, 1)
        out.update(_rss_split_mb())
    out["heavy_modules"] = sorted(m for m in HEAVY if m in sys.modules)
    out["baseline_rss_mb"] = round(base, 1)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=SHARED_DATA)
    ap.add_argument("--extra", type=int, default=4, help="extra simulators, rendering off")
    ap.add_argument("--case", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.case:
        print(json.dumps(case(args.case, args.data, args.extra)))
        return 0
    from common import machine

    result = {"machine": machine()}
    for name in ("import", "rendering_off", "rendering_on"):
        if name == "rendering_off" and not (args.data / "mp3d_connectivity").is_dir():
            result[name] = {"skipped": f"connectivity graphs not found at {args.data}"}
            continue
        cmd = [sys.executable, __file__, "--case", name, "--data", str(args.data)]
        cmd += ["--extra", str(args.extra)]
        done = subprocess.run(cmd, capture_output=True, text=True)
        if done.returncode != 0:
            result[name] = {"failed": done.stderr.strip().splitlines()[-1:]}
        else:
            result[name] = json.loads(done.stdout.strip().splitlines()[-1])
    print(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
