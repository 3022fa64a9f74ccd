"""A MatterSim agent loop that runs on havln_mj with only its import changed.

Rendering is off, so no GL work is done: this is how R2R agents are trained and evaluated on
navigation graphs. The scene is a built-in procedural house by default; with a folder of
Matterport3DSimulator connectivity files, any of the 90 real scans works the same way.

    python examples/mattersim_loop.py
    python examples/mattersim_loop.py --connectivity-dir path/to/connectivity --scene 17DRP5sb8fy
"""

import argparse
import math

import havln_mj as MatterSim  # noqa: N812 - was: import MatterSim


def main() -> None:
    """Parses the command line and runs the example."""
    parser = argparse.ArgumentParser(description="A MatterSim loop with rendering off.")
    parser.add_argument("--scene", default="proc-0", help="proc-<seed> or a Matterport scan id")
    parser.add_argument("--connectivity-dir", help="folder of <scan>_connectivity.json files")
    parser.add_argument("--steps", type=int, default=20, help="actions to take")
    parser.add_argument("--seed", type=int, default=0, help="seed of the start and the walk")
    args = parser.parse_args()

    sim = MatterSim.Simulator()
    if args.connectivity_dir:
        sim.setNavGraphPath(args.connectivity_dir)
    sim.setRenderingEnabled(False)
    sim.setDiscretizedViewingAngles(True)
    sim.setBatchSize(1)
    sim.setSeed(args.seed)
    sim.initialize()
    sim.newRandomEpisode([args.scene])

    for _ in range(args.steps):
        state = sim.getState()[0]
        if len(state.navigableLocations) > 1:
            # Index 0 is "stay"; 1 is the reachable viewpoint nearest the view centre.
            sim.makeAction([1], [0.0], [0.0])
        else:
            sim.makeAction([0], [math.radians(30.0)], [0.0])  # nothing in view: turn right
        state = sim.getState()[0]
        print(
            f"step {state.step:2d}  at {state.location.viewpointId[:8]}  "
            f"heading {math.degrees(state.heading):5.1f}°  view {state.viewIndex:2d}  "
            f"{len(state.navigableLocations) - 1} reachable  t = {state.time:5.1f} s"
        )
    sim.close()


if __name__ == "__main__":
    main()
