"""Renders the README's two frames of people, through the Simulator API.

Each frame looks at one person of ``proc-0`` from a viewpoint 2–4.5 m in front of them.
Run: ``python docs/people_frames.py [--seed N] [--out docs]``.
"""

from __future__ import annotations

import argparse
import math
import os
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import cv2
import numpy as np

import havln_mj as MatterSim  # noqa: N812 - MatterSim code, only the import changed
from havln_mj.frames import heading_to
from havln_mj.scene.scan import load_scan


def main() -> None:
    """Writes people_frame_1.png and people_frame_2.png."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent)
    args = ap.parse_args()
    sim = MatterSim.Simulator(humans=True)
    sim.setCameraResolution(640, 480)
    sim.setCameraVFOV(math.radians(60))
    sim.set_human_mask_enabled(True)
    sim.setSeed(args.seed)
    sim.initialize()
    sim.newRandomEpisode(["proc-0"])
    graph = load_scan("proc-0").graph
    shots = []
    for person in sim.getHumanState()[0]:
        forward = np.array([math.sin(person.heading), math.cos(person.heading)])
        best, best_score = None, -math.inf
        for vp in graph.nodes:
            offset = graph.position(vp)[:2] - person.position[:2]
            d = float(np.linalg.norm(offset))
            facing = float(forward @ offset) / max(d, 1e-6)
            same_floor = abs(graph.floor_z(vp) - person.position[2]) < 1.5
            score = facing - abs(d - 3.0) / 3.0
            if 2.0 < d < 4.5 and facing > 0.3 and same_floor and score > best_score:
                best, best_score = vp, score
        if best is None:
            continue
        sim.newEpisode(
            ["proc-0"], [best], [heading_to(graph.position(best), person.position)], [-0.15]
        )
        state = sim.getState()[0]
        shots.append((float(state.humanMask.mean()), person.text, state.rgb))
    for k, (_, text, bgr) in enumerate(sorted(shots, key=lambda s: -s[0])[:2], start=1):
        cv2.imwrite(str(args.out / f"people_frame_{k}.png"), bgr)
        print(f"people_frame_{k}.png: {text}")


if __name__ == "__main__":
    main()
