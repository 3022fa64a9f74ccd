"""Filming a walk with ``Simulator.set_film``: frames during actions, not only after them.

``set_film(fps, callback, cameras)`` draws frames at ``fps`` per simulated second while each
action runs, with the people and the body as they were at that moment, and hands them to
``callback(element, t, views, pose)``. Here they go into an H.264 MP4 that browsers play.
With ``--body go1`` the GO1's chase camera is filmed beside its head camera.

    python examples/film_walk.py --out walk.mp4 --width 320 --height 240
"""

import argparse
from pathlib import Path

import numpy as np

import havln_mj
from havln_mj.render.video import VideoWriter


def main() -> None:
    """Parses the command line and runs the example."""
    parser = argparse.ArgumentParser(description="Film a walk along a shortest path.")
    parser.add_argument("--scene", default="proc-0", help="scene id")
    parser.add_argument("--body", default="point", choices=["point", "go1"], help="agent body")
    parser.add_argument("--edges", type=int, default=3, help="edges of the path to walk")
    parser.add_argument("--fps", type=float, default=10.0, help="frames per simulated second")
    parser.add_argument("--width", type=int, default=320, help="image width, pixels")
    parser.add_argument("--height", type=int, default=240, help="image height, pixels")
    parser.add_argument("--seed", type=int, default=0, help="seed of the start and the people")
    parser.add_argument("--out", type=Path, default=Path("walk.mp4"), help="the .mp4 to write")
    args = parser.parse_args()

    sim = havln_mj.Simulator(humans=True, body=args.body)
    sim.setCameraResolution(args.width, args.height)
    sim.setRestrictedNavigation(False)
    sim.setSeed(args.seed)
    sim.initialize()
    cameras = ("go1/chase",) if args.body == "go1" else ()
    size = (args.width * (1 + len(cameras)), args.height)
    track = []
    with VideoWriter(args.out, args.fps, size) as video:

        def frame(element: int, t: float, views: list, pose: np.ndarray) -> None:
            video.write(np.hstack([view.rgb for view in views]))  # RGB frames
            track.append((float(pose[0]), float(pose[1])))

        sim.set_film(args.fps, frame, cameras)
        sim.newRandomEpisode([args.scene])
        start = sim.getState()[0].location.viewpointId
        graph = sim.graph(args.scene)
        paths = [graph.shortest_path(start, vp) for vp in graph.nodes]
        for target in max((p for p in paths if len(p) <= args.edges + 1), key=len)[1:]:
            ids = [loc.viewpointId for loc in sim.getState()[0].navigableLocations]
            sim.makeAction([ids.index(target)], [0.0], [0.0])
        sim.set_film(None)
    state = sim.getState()[0]
    print(f"wrote {args.out}: {len(track)} frames over {state.time:.1f} simulated seconds")
    (x0, y0), (x1, y1) = track[0], track[-1]
    print(f"walked from ({x0:.2f}, {y0:.2f}) to ({x1:.2f}, {y1:.2f}); arrived {state.arrived}")
    sim.close()


if __name__ == "__main__":
    main()
