"""Rendering RGB, depth and the human mask to PNG files.

The agent stands next to a person and looks at them. Images come in MatterSim's formats:
``rgb`` is BGR ``uint8`` (what OpenCV writes), ``depth`` is ``uint16`` in 0.25 mm units (a
16-bit PNG, as Matterport3DSimulator's depth), and ``humanMask`` is True where a person is
seen. Rendering is offscreen (EGL or OSMesa); no display or GPU is needed.

    python examples/render_rgbd.py --out renders --width 320 --height 240
"""

import argparse
from pathlib import Path

import cv2
import numpy as np

import havln_mj
from havln_mj.frames import heading_to


def main() -> None:
    """Parses the command line and runs the example."""
    parser = argparse.ArgumentParser(description="Render RGB-D and the human mask.")
    parser.add_argument("--scene", default="proc-0", help="scene id")
    parser.add_argument("--seed", type=int, default=0, help="seed of the people")
    parser.add_argument("--width", type=int, default=320, help="image width, pixels")
    parser.add_argument("--height", type=int, default=240, help="image height, pixels")
    parser.add_argument("--out", type=Path, default=Path("renders"), help="output folder")
    args = parser.parse_args()

    sim = havln_mj.Simulator(humans=True)
    sim.setCameraResolution(args.width, args.height)
    sim.setDepthEnabled(True)
    sim.set_human_mask_enabled(True)
    sim.setSeed(args.seed)
    sim.initialize()
    sim.newRandomEpisode([args.scene])

    # Stand at the viewpoint 1.5-4 m from the first person that is nearest, and face them.
    person = sim.getHumanState()[0][0].position
    graph = sim.graph(args.scene)

    def gap(vp: str) -> float:
        d = np.linalg.norm(graph.position(vp)[:2] - person[:2])
        return d if 1.5 < d < 4.0 else np.inf

    start = min(graph.nodes, key=gap)
    heading = heading_to(graph.position(start), person)
    sim.newEpisode([args.scene], [start], [heading], [-0.2])

    state = sim.getState()[0]
    args.out.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(args.out / "rgb.png"), state.rgb)
    cv2.imwrite(str(args.out / "depth.png"), state.depth)
    cv2.imwrite(str(args.out / "human_mask.png"), state.humanMask.astype(np.uint8) * 255)
    metres = state.depth[..., 0] / 4000.0
    print(f"wrote rgb.png, depth.png and human_mask.png to {args.out}")
    print(
        f"depth {metres[metres > 0].min():.2f}-{metres.max():.2f} m; "
        f"people cover {state.humanMask.mean():.1%} of the image"
    )
    sim.close()


if __name__ == "__main__":
    main()
