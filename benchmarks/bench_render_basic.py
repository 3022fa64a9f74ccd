"""Frames per second of havln_mj's one-pass RGB-D Camera vs mujoco.Renderer's two passes.

The world is a synthetic house: a floor, a ceiling and a grid of rooms walled by ~300 box
geoms, lit by a few lights; the camera stands in a room and turns a little every frame.
fps is 1 / median frame time, where a frame is mj_kinematics + mj_camlight + the render
calls; the methods run round-robin so that other processes sharing the CPUs slow them
alike. ``mujoco.Renderer`` is measured with
the model's default 4× multisampling and with none (``havln_mj`` defaults to none).
Prints one JSON object. Run: ``python benchmarks/bench_render_basic.py [--seconds S]``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time
from collections.abc import Callable

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco
import numpy as np

from havln_mj.frames import camera_quat
from havln_mj.render import gl
from havln_mj.render.camera import Camera

_RESOLUTIONS = ((640, 480), (128, 128))


def build_house(rooms_x: int = 8, rooms_y: int = 8, room: float = 4.0) -> mujoco.MjModel:
    """Returns a model with a floor, a ceiling and a grid of rooms walled by box geoms."""
    spec = mujoco.MjSpec()
    spec.visual.global_.offwidth = 640
    spec.visual.global_.offheight = 480
    world = spec.worldbody
    size_x, size_y = rooms_x * room, rooms_y * room
    box = mujoco.mjtGeom.mjGEOM_BOX
    world.add_geom(
        type=mujoco.mjtGeom.mjGEOM_PLANE, size=[size_x, size_y, 0.1], rgba=[0.6, 0.55, 0.5, 1]
    )
    world.add_geom(type=box, size=[size_x / 2, size_y / 2, 0.05], pos=[size_x / 2, size_y / 2, 2.8])
    rng = np.random.default_rng(0)
    half = room / 2 - 0.5  # Two wall segments per room side leave a 1 m doorway.
    for i in range(rooms_x + 1):
        for j in range(rooms_y):
            for s in (-1, 1):
                y = j * room + room / 2 + s * (half / 2 + 0.5)
                world.add_geom(
                    type=box,
                    size=[0.05, half / 2, 1.35],
                    pos=[i * room, y, 1.35],
                    rgba=[*rng.uniform(0.3, 0.9, 3), 1],
                )
    for j in range(rooms_y + 1):
        for i in range(rooms_x):
            x = i * room + room / 2
            world.add_geom(
                type=box,
                size=[room / 2, 0.05, 1.35],
                pos=[x, j * room, 1.35],
                rgba=[*rng.uniform(0.3, 0.9, 3), 1],
            )
    for i in range(rooms_x):
        for j in range(rooms_y):  # One piece of furniture per room.
            world.add_geom(
                type=box,
                size=[0.4, 0.3, 0.4],
                pos=[i * room + 1.0, j * room + 1.0, 0.4],
                rgba=[*rng.uniform(0.2, 0.8, 3), 1],
            )
    for k in range(3):
        world.add_light(pos=[size_x * (k + 1) / 4, size_y / 2, 2.6], dir=[0, 0, -1])
    body = world.add_body(name="agent", mocap=True, pos=[room / 2, room / 2, 1.5])
    body.add_camera(name="agent_cam")
    return spec.compile()


def _turn(model: mujoco.MjModel, data: mujoco.MjData, k: int) -> None:
    data.mocap_quat[0] = camera_quat(math.radians(7.0 * k))
    mujoco.mj_kinematics(model, data)
    mujoco.mj_camlight(model, data)


def _interleaved_fps(steps: dict[str, Callable[[int], None]], seconds: float) -> dict[str, float]:
    """Returns 1 / median frame time per step, the steps run round-robin.

    Interleaving exposes every method to the same load from other processes, and the median
    ignores frames they stalled.
    """
    for step in steps.values():
        step(0)  # Warm-up (shader compilation, allocations).
    times: dict[str, list[float]] = {label: [] for label in steps}
    start = time.perf_counter()
    k = 0
    while time.perf_counter() - start < seconds * len(steps) or k < 5:
        k += 1
        for label, step in steps.items():
            t = time.perf_counter()
            step(k)
            times[label].append(time.perf_counter() - t)
    return {label: round(1.0 / float(np.median(ts)), 1) for label, ts in times.items()}


def camera_steps(model, data, cam: Camera) -> dict[str, Callable[[int], None]]:
    """Frame functions of havln_mj's Camera: RGB, depth, RGB-D (one pass)."""

    def make(rgb: bool, depth: bool) -> Callable[[int], None]:
        def step(k: int) -> None:
            _turn(model, data, k)
            cam.render(data, rgb=rgb, depth=depth)

        return step

    return {"rgb": make(True, False), "depth": make(False, True), "rgbd": make(True, True)}


def renderer_steps(model, data, renderer: mujoco.Renderer) -> dict[str, Callable[[int], None]]:
    """Frame functions of mujoco.Renderer: RGB, depth, RGB then depth (two passes)."""
    renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
    renderer.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = False

    def rgb_step(k: int) -> None:
        _turn(model, data, k)
        renderer.disable_depth_rendering()
        renderer.update_scene(data, "agent_cam")
        renderer.render()

    def depth_step(k: int) -> None:
        _turn(model, data, k)
        renderer.enable_depth_rendering()
        renderer.update_scene(data, "agent_cam")
        renderer.render()

    def rgbd_step(k: int) -> None:
        _turn(model, data, k)
        renderer.update_scene(data, "agent_cam")
        renderer.disable_depth_rendering()
        renderer.render()
        renderer.enable_depth_rendering()
        renderer.render()

    return {"rgb": rgb_step, "depth": depth_step, "rgbd": rgbd_step}


def make_renderer(model, width: int, height: int, samples: int) -> mujoco.Renderer:
    """Returns a mujoco.Renderer whose offscreen buffer has ``samples`` multisamples."""
    old = model.vis.quality.offsamples
    model.vis.quality.offsamples = samples  # Read when the Renderer makes its MjrContext.
    try:
        return mujoco.Renderer(model, height=height, width=width)
    finally:
        model.vis.quality.offsamples = old


def bench_resolution(model, data, width: int, height: int, seconds: float) -> dict:
    """Returns fps of every method at one resolution."""
    cam = Camera(model, width=width, height=height)
    plain = make_renderer(model, width, height, samples=0)
    msaa = make_renderer(model, width, height, samples=4)
    methods = {
        "havln_camera_msaa0": camera_steps(model, data, cam),
        "mujoco_renderer_msaa0": renderer_steps(model, data, plain),
        "mujoco_renderer_msaa4": renderer_steps(model, data, msaa),
    }
    steps = {(method, mode): step for method, fns in methods.items() for mode, step in fns.items()}
    try:
        fps = _interleaved_fps(steps, seconds)
    finally:
        cam.close()
        plain.close()
        msaa.close()
    out: dict = {method: {} for method in methods}
    for (method, mode), value in fps.items():
        out[method][mode] = value
    ours = out["havln_camera_msaa0"]["rgbd"]
    out["rgbd_speedup_vs_renderer_msaa0"] = round(ours / out["mujoco_renderer_msaa0"]["rgbd"], 2)
    out["rgbd_speedup_vs_renderer_default_msaa4"] = round(
        ours / out["mujoco_renderer_msaa4"]["rgbd"], 2
    )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=1.0, help="seconds per measurement")
    args = parser.parse_args()

    model = build_house()
    data = mujoco.MjData(model)
    result: dict[str, object] = {
        "world": {"ngeom": int(model.ngeom), "nlight": int(model.nlight)},
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version()},
        "mujoco": mujoco.__version__,
    }
    for width, height in _RESOLUTIONS:
        result[f"{width}x{height}"] = bench_resolution(model, data, width, height, args.seconds)
    result["gl"] = _gl_info(model)
    result["gl_released_after_close"] = gl.active_session() is None
    print(json.dumps(result, indent=2))


def _gl_info(model: mujoco.MjModel) -> dict[str, str]:
    """Returns the backend and GL renderer string (informational)."""
    with Camera(model, width=8, height=8) as cam:
        from OpenGL import GL

        renderer = GL.glGetString(GL.GL_RENDERER)
        return {
            "backend": cam.gl_session.backend,
            "renderer": renderer.decode() if renderer else "unknown",
        }


if __name__ == "__main__":
    main()
