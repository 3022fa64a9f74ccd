"""How many fragments a frame rasterises per pixel: the depth complexity of the houses.

Each procedural house is walked with rendering on (640×480 RGB-D by default, its people
drawn), and OpenGL's statistics queries count, per frame, the fragment-shader invocations
(every fragment rasterised, hidden or not) and the samples that pass the depth test. Both are
reported per pixel: 1.0 would mean each pixel is drawn once. On a CPU renderer (Mesa
llvmpipe) a frame's time grows with the first. Rooms that walls hide from the camera are
already left out (:mod:`havln_mj.render.culling`): this counts what is drawn after that.
Also the frame rate of the same walk (queries included) and the GL renderer measured.

Prints one JSON object. Run:
``python benchmarks/bench_overdraw.py [--scenes proc-0 proc-1] [--steps 200] [--no-people]``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import time

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np
from common import machine

_FRAGMENT_INVOCATIONS = 0x82F4  # GL_FRAGMENT_SHADER_INVOCATIONS (ARB_pipeline_statistics_query)
_SAMPLES_PASSED = 0x8914  # GL_SAMPLES_PASSED


def _scene(scene: str, steps: int, size: tuple[int, int], people: bool, seed: int) -> dict:
    from OpenGL import GL  # PyOpenGL, which MuJoCo's EGL backend already loads

    import havln_mj

    sim = havln_mj.Simulator(humans=people)
    sim.setCameraResolution(*size)
    sim.setCameraVFOV(math.radians(60))
    sim.setDepthEnabled(True)
    sim.initialize()
    rng = np.random.default_rng(seed)
    sim.newRandomEpisode([scene])

    def step() -> None:
        state = sim.getState()[0]
        index = int(rng.integers(len(state.navigableLocations)))
        sim.makeAction([index], [float(rng.uniform(-1.0, 1.0))], [0.0])

    step()  # makes the camera: its GL context is current on this thread from here on
    renderer = GL.glGetString(GL.GL_RENDERER).decode()
    queries = GL.glGenQueries(2)
    fragments, passed = [], []
    t, cpu = time.perf_counter(), time.process_time()
    for k in range(steps):
        if k % 30 == 29:
            sim.newRandomEpisode([scene])
        GL.glBeginQuery(_FRAGMENT_INVOCATIONS, int(queries[0]))
        GL.glBeginQuery(_SAMPLES_PASSED, int(queries[1]))
        step()
        GL.glEndQuery(_FRAGMENT_INVOCATIONS)
        GL.glEndQuery(_SAMPLES_PASSED)
        fragments.append(GL.glGetQueryObjectuiv(int(queries[0]), GL.GL_QUERY_RESULT))
        passed.append(GL.glGetQueryObjectuiv(int(queries[1]), GL.GL_QUERY_RESULT))
    wall, cpu = time.perf_counter() - t, time.process_time() - cpu
    GL.glDeleteQueries(2, queries)
    people_count = len(sim.getHumanState()[0]) if people else 0
    sim.close()
    pixels = size[0] * size[1]
    return {
        "scene": scene,
        "people": people_count,
        "renderer": renderer,
        "frames": steps,
        "fragments_per_pixel": round(statistics.mean(fragments) / pixels, 2),
        "fragments_per_pixel_max": round(max(fragments) / pixels, 2),
        "depth_passed_per_pixel": round(statistics.mean(passed) / pixels, 2),
        "fps": round(steps / wall, 1),
        "fps_per_cpu_s": round(steps / cpu, 1),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--scenes", nargs="+", default=[f"proc-{k}" for k in range(5)])
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--size", type=int, nargs=2, default=(640, 480), metavar=("W", "H"))
    parser.add_argument("--no-people", action="store_true")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    rows = [
        _scene(scene, args.steps, tuple(args.size), not args.no_people, args.seed)
        for scene in args.scenes
    ]
    out = {"machine": machine(), "resolution": "{}x{}".format(*args.size), "scenes": rows}
    out["fragments_per_pixel_mean"] = round(
        statistics.mean(r["fragments_per_pixel"] for r in rows), 2
    )
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
