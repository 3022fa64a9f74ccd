"""Quadruped in the loop: the demo run's episodes walked by the GO1 beside the point body.

``python -m havln_mj.run --robot go1`` walks each episode's graph actions (turn toward the
next viewpoint, walk to it) with the physically simulated GO1 and compares them with the
point body, which executes the same actions exactly in ``distance / speed + angle / rate``
seconds. Per action it reports where the robot ended (distance to the viewpoint), how far its
trunk strayed from the straight edge (path deviation), the primitives it ran with their
errors, falls, collisions with people and the physics time. The video shows the GO1's head
camera beside a chase view.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from itertools import pairwise
from pathlib import Path

import cv2
import mujoco
import numpy as np

from havln_mj.errors import HavlnError
from havln_mj.frames import heading_to, wrap_angle
from havln_mj.render.camera import Camera
from havln_mj.robot.point_body import DEFAULT_SPEED, DEFAULT_TURN_RATE
from havln_mj.scene.scan import Scan
from havln_mj.sim.crowd import Crowd
from havln_mj.sim.legged import CHASE_CAMERA, LeggedAgent, LeggedOptions, LeggedWorld
from havln_mj.sim.world import WorldOptions


def _deviation(track: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Horizontal distance of each track point to the segment a–b."""
    ab = b[:2] - a[:2]
    rel = track[:, 1:3] - a[:2]
    t = np.clip(rel @ ab / max(float(ab @ ab), 1e-12), 0.0, 1.0)
    return np.linalg.norm(rel - t[:, None] * ab, axis=1)


def _stats(values: Sequence[float]) -> dict:
    v = np.abs(np.asarray(values, float))
    if not len(v):
        return {"n": 0}
    return {
        "n": len(v),
        "mean": round(float(v.mean()), 4),
        "p95": round(float(np.percentile(v, 95)), 4),
    }


def run_go1(
    scan: Scan,
    crowd: Crowd,
    paths: Sequence[Sequence[str]],
    out: Path,
    *,
    width: int,
    height: int,
    vfov: float,
    fps: float,
    options: LeggedOptions,
    collision: str = "auto",
) -> dict:
    """Walks ``paths`` with the GO1, writes ``go1.mp4`` to ``out`` and returns the report."""
    graph = scan.graph
    world = LeggedWorld(scan, WorldOptions(collision=collision), crowd, options)
    agent = LeggedAgent(world)
    video_path = out / "go1.mp4"
    writer = cv2.VideoWriter(
        str(video_path), cv2.VideoWriter_fourcc(*"mp4v"), fps, (2 * width, height)
    )
    if not writer.isOpened():
        raise HavlnError(f"cannot open an MP4 writer for {video_path}")
    head = Camera(world.model, world.camera, width, height, vfov)
    chase = Camera(world.model, CHASE_CAMERA, width, height, 60.0)
    clock, next_frame, frames = 0.0, 0.0, 0
    episodes = []

    def film(t: float) -> None:
        nonlocal next_frame, frames
        if t + 1e-9 < next_frame:
            return
        next_frame = t + 1.0 / fps
        agent.pose_people(t)
        mujoco.mj_kinematics(world.model, agent.data)
        mujoco.mj_camlight(world.model, agent.data)
        views = [cam.render(agent.data, depth=False).rgb for cam in (head, chase)]
        frame = cv2.cvtColor(np.hstack(views), cv2.COLOR_RGB2BGR)
        cv2.putText(frame, f"GO1  t={t:5.1f}s", (8, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.5,
                    (255, 255, 255), 1, cv2.LINE_AA)  # fmt: skip
        writer.write(frame)
        frames += 1

    try:
        for path in paths:
            start = graph.position(path[0])
            agent.place(start, graph.floor_z(path[0]), heading_to(start, graph.position(path[1])),
                        clock)  # fmt: skip
            steps, heading = [], agent.heading()
            point_time = 0.0
            for a, b in pairwise(path):
                pa, pb = graph.position(a), graph.position(b)
                bearing = heading_to(pa, pb)
                point_time += np.linalg.norm(pb - pa) / DEFAULT_SPEED
                point_time += abs(wrap_angle(bearing - heading)) / DEFAULT_TURN_RATE
                heading = bearing
                target = np.array([pb[0], pb[1], graph.floor_z(b)])
                outcome = agent.go_to(target, None, clock, on_tick=film)
                clock += outcome.duration
                end = agent.position()
                dev = _deviation(outcome.track, pa, pb)
                steps.append(
                    {
                        "to": b,
                        "end_error_m": round(float(np.hypot(*(end[:2] - pb[:2]))), 4),
                        "heading_error_deg": round(
                            math.degrees(wrap_angle(agent.heading() - bearing)), 2
                        ),
                        "path_deviation_m": {
                            "mean": round(float(dev.mean()), 4),
                            "max": round(float(dev.max()), 4),
                        },
                        "seconds": round(outcome.duration, 3),
                        "primitives": [
                            {
                                "kind": r.kind,
                                "target": round(r.target, 4),
                                "error": round(r.error, 4),
                                "seconds": round(r.duration, 3),
                                "timed_out": r.timed_out,
                            }
                            for r in outcome.primitives or []
                        ],
                        "collided_people": list(outcome.contact.people) if outcome.contact else [],
                        "fell": outcome.fell,
                    }
                )
                if outcome.fell:
                    break
            prims = [p for s in steps for p in s["primitives"]]
            episodes.append(
                {
                    "path": list(path),
                    "reached": not steps[-1]["fell"] and len(steps) == len(path) - 1,
                    "final_error_m": steps[-1]["end_error_m"],
                    "go1_seconds": round(sum(s["seconds"] for s in steps), 3),
                    "point_body_seconds": round(point_time, 3),
                    "fell": any(s["fell"] for s in steps),
                    "forward_error_m": _stats(
                        [p["error"] for p in prims if p["kind"] == "forward"]
                    ),
                    "turn_error_deg": _stats(
                        [math.degrees(p["error"]) for p in prims if p["kind"] == "turn"]
                    ),
                    "max_path_deviation_m": max(s["path_deviation_m"]["max"] for s in steps),
                    "human_collisions": len({i for s in steps for i in s["collided_people"]}),
                    "steps": steps,
                }
            )
    finally:
        writer.release()
        head.close()
        chase.close()
    return {
        "video": str(video_path),
        "frames": frames,
        "estimate": options.estimate,
        "collision": world.collision,
        "episodes": episodes,
        "falls": sum(e["fell"] for e in episodes),
    }
