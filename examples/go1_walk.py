"""The simulated Unitree GO1 walking a path, with the state telling where it really is.

``Simulator(body="go1")`` executes the same MatterSim actions with a physically simulated
quadruped: a graph move turns toward the viewpoint, trots there and turns back to MatterSim's
heading, and lasts its physics time. The state is truthful: ``arrived`` says whether the
robot reached the viewpoint (``location`` stays the last one it stood at when it did not),
``pose`` is the trunk's true pose, ``fell``/``diverged`` end an episode. Then the real
robot's own actions: ``makeRobotAction(["forward"])`` walks 0.5 m, ``"turn_left"`` turns 45°.

    python examples/go1_walk.py --edges 3
"""

import argparse
import math

import havln_mj


def report(what: str, state: havln_mj.SimState) -> None:
    """Prints what the state says of the body after ``what``."""
    x, y, _, heading = state.pose
    print(
        f"{what:16s} arrived {state.arrived!s:5}  at {state.location.viewpointId[:8]}  "
        f"pose ({x:5.2f}, {y:5.2f}) {math.degrees(heading):5.1f}°  t = {state.time:5.2f} s  "
        f"fell {state.fell}"
    )


def main() -> None:
    """Parses the command line and runs the example."""
    parser = argparse.ArgumentParser(description="The GO1 walking a shortest path.")
    parser.add_argument("--scene", default="proc-0", help="scene id")
    parser.add_argument("--edges", type=int, default=3, help="edges of the path to walk")
    parser.add_argument("--seed", type=int, default=0, help="seed of the start")
    args = parser.parse_args()

    sim = havln_mj.Simulator(body="go1")
    sim.setRenderingEnabled(False)
    sim.setRestrictedNavigation(False)  # every neighbour is navigable, whatever the view
    sim.setSeed(args.seed)
    sim.initialize()
    sim.newRandomEpisode([args.scene])
    state = sim.getState()[0]
    report("start", state)

    # The farthest viewpoint that is at most --edges moves away, by the shortest path.
    graph, start = sim.graph(args.scene), state.location.viewpointId
    paths = [graph.shortest_path(start, vp) for vp in graph.nodes]
    path = max((p for p in paths if len(p) <= args.edges + 1), key=len)
    robot = ("turn_left", "forward", "forward")
    moves = [(f"to {vp[:8]}", vp) for vp in path[1:]] + [(name, None) for name in robot]
    for move, target in moves:
        if target:  # a graph move to a navigable viewpoint
            ids = [loc.viewpointId for loc in state.navigableLocations]
            sim.makeAction([ids.index(target)], [0.0], [0.0])
        else:  # one of the real robot's own actions
            sim.makeRobotAction([move])
        state = sim.getState()[0]
        report(move, state)
        if state.fell or state.diverged:
            print("the GO1 is down: its episode is over")
            break
    print(f"geodesic distance back to the start: {sim.getGeodesicDistance([start])[0]:.2f} m")
    sim.close()


if __name__ == "__main__":
    main()
