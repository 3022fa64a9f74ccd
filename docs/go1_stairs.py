"""Renders the GO1 (stair crawl) climbing a stair edge of a real building's graph proxy.

Writes ``go1_stairs.mp4`` (MPEG-4 part 2: this OpenCV build has no H.264 encoder; four
times real speed) and ``go1_stairs.png`` (a strip of frames) next to this script. Needs the
shared connectivity graphs:
``python docs/go1_stairs.py [--data ../shared/data] [--scan 17DRP5sb8fy]``.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import cv2
import mujoco
import numpy as np

from havln_mj.robot.go1 import Go1Body
from havln_mj.scene.proxy.walk import edge_grade
from havln_mj.scene.scan import load_scan
from havln_mj.sim.crowd import NO_CROWD
from havln_mj.sim.legged import CHASE_CAMERA, PREFIX, LeggedAgent, LeggedOptions, LeggedWorld
from havln_mj.sim.world import WorldOptions

HERE = Path(__file__).resolve().parent


def main() -> None:
    """Walks the edge and writes the video and the strip of frames."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=HERE.parents[1] / "shared" / "data")
    ap.add_argument("--scan", default="17DRP5sb8fy")
    ap.add_argument("--fps", type=int, default=25)
    args = ap.parse_args()
    scan = load_scan(args.scan, connectivity_dir=args.data / "mp3d_connectivity")
    g = scan.graph
    # The straight stair edge (floors > 0.3 m apart, no route) of grade nearest 0.5, upwards.
    stairs = [
        (a, b) if g.floor_z(a) < g.floor_z(b) else (b, a)
        for a, b, _ in g.edges()
        if abs(g.floor_z(a) - g.floor_z(b)) > 0.3 and scan.route(a, b) is None
    ]
    src, dst = min(stairs, key=lambda e: abs(edge_grade(g, *e) - 0.5))
    world = LeggedWorld(scan, WorldOptions(collision="boxes"), NO_CROWD, LeggedOptions())
    agent = LeggedAgent(world)
    agent.body = Go1Body(world.model, agent.data, PREFIX, controller="crawl")
    target = np.append(g.position(dst)[:2], g.floor_z(dst))
    start = g.position(src)
    heading = float(np.arctan2(target[0] - start[0], target[1] - start[1]))
    agent.place(start, g.floor_z(src), heading, 0.0)
    renderer = mujoco.Renderer(world.model, 360, 480)
    option = mujoco.MjvOption()
    # The crawl is slow: the video shows it at 4x, frames written as they come.
    every = max(1, round(4 * 20 / args.fps))  # of the 20 Hz ticks
    writer = cv2.VideoWriter(
        str(HERE / "go1_stairs.mp4"), cv2.VideoWriter_fourcc(*"mp4v"), args.fps, (480, 360)
    )
    ticks, keep = [0], []

    def grab(t: float) -> None:
        ticks[0] += 1
        if ticks[0] % every:
            return
        renderer.update_scene(agent.data, CHASE_CAMERA, option)
        frame = renderer.render()
        writer.write(cv2.cvtColor(frame, cv2.COLOR_RGB2BGR))
        keep.append((t, cv2.resize(frame, None, fx=0.5, fy=0.5)))

    out = agent.go_to(target, None, 0.0, on_tick=grab)
    writer.release()
    end = agent.position()
    gap = float(np.hypot(*(end[:2] - target[:2])))
    note = f"{args.scan} {src[:6]}->{dst[:6]}: rise {target[2] - g.floor_z(src):+.2f} m"
    note += f", fell={out.fell}, ended {gap:.2f} m from the viewpoint, {out.duration:.0f} s"
    print(note)
    picks = [keep[k][1] for k in np.linspace(0, len(keep) - 1, 8).astype(int)]
    strip = np.concatenate([np.concatenate(picks[:4], 1), np.concatenate(picks[4:], 1)], 0)
    cv2.putText(strip, note, (8, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1)
    cv2.imwrite(str(HERE / "go1_stairs.png"), cv2.cvtColor(strip, cv2.COLOR_RGB2BGR))


if __name__ == "__main__":
    main()
