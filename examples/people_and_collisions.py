"""Egocentric actions among people, and HA-VLN's collision signal.

The agent starts next to the viewpoint closest to a person, facing it, and walks with HA-VLN's
egocentric actions (FORWARD when a viewpoint lies ahead, else TURN_RIGHT). After every action the
state says whether the agent came within 1 m of anyone at any moment of that action
(``isCrushed``), who it was (``crushedBy``) and how close it came (``minHumanDistance``).

    python examples/people_and_collisions.py --steps 12
"""

import argparse

import numpy as np

import havln_mj
from havln_mj.frames import heading_to
from havln_mj.sim.egocentric import EgoAction


def main() -> None:
    """Parses the command line and runs the example."""
    parser = argparse.ArgumentParser(description="Egocentric actions among people.")
    parser.add_argument("--scene", default="proc-0", help="scene id")
    parser.add_argument("--steps", type=int, default=12, help="actions to take")
    parser.add_argument("--seed", type=int, default=0, help="seed of the people")
    args = parser.parse_args()

    sim = havln_mj.Simulator(humans=True)
    sim.setRenderingEnabled(False)
    sim.setSeed(args.seed)
    sim.initialize()
    sim.newRandomEpisode([args.scene])
    people = sim.getHumanState()[0]
    for k, person in enumerate(people):
        print(f"person {k}: {person.text} (region {person.region}), at {person.position.round(2)}")

    # The viewpoint closest to anyone, and a neighbour of it to start from, facing it.
    graph = sim.graph(args.scene)

    def gap(vp: str) -> float:
        return min(np.linalg.norm(graph.position(vp)[:2] - p.position[:2]) for p in people)

    near = min((vp for vp in graph.nodes if graph.neighbors(vp)), key=gap)
    start = graph.neighbors(near)[0]
    heading = heading_to(graph.position(start), graph.position(near))
    sim.newEpisode([args.scene], [start], [heading], [0.0])
    print(f"heading for {near[:8]}, {gap(near):.2f} m from a person")

    state = sim.getState()[0]
    print(f"start: {state.minHumanDistance:.2f} m from the nearest person")
    collided = 0
    for _ in range(args.steps):
        ahead = any(abs(loc.rel_heading) < sim.half_hfov for loc in state.navigableLocations[1:])
        action = EgoAction.FORWARD if ahead else EgoAction.TURN_RIGHT
        sim.makeEgoAction([action])
        state = sim.getState()[0]
        collided += state.isCrushed
        print(
            f"{action.name:10s} -> {state.location.viewpointId[:8]}  t = {state.time:5.2f} s  "
            f"nearest person {state.minHumanDistance:5.2f} m  isCrushed {state.isCrushed}  "
            f"by {list(state.crushedBy)}"
        )
    print(f"{collided} of {args.steps} actions came within 1 m of a person")
    sim.close()


if __name__ == "__main__":
    main()
