"""Experts through HA-R2R episodes, scored with the HA-VLN metrics.

Generates R2R-like episodes in a procedural house (HA-R2R's schema, with our own
instructions), runs the optimal expert and HA3D's human-aware expert through each with the
task step (collisions along every action, the start included), and scores the trajectories:
NE, SR, OSR, SPL, nDTW, and the human-aware TCR, CR and collision-free SR. This is what
``python -m havln_mj.eval`` does for a whole split.

    python examples/expert_metrics.py --episodes 3
"""

import argparse

import havln_mj
from havln_mj.tasks.experts import HumanAwareExpert, ShortestPathExpert, run_expert
from havln_mj.tasks.metrics import EvalEpisode, Evaluator, MetricConfig
from havln_mj.tasks.procedural import procedural_episodes

METRICS = ("ne", "sr", "osr", "spl", "ndtw", "tcr", "cr", "cf_sr", "tl")


def main() -> None:
    """Parses the command line and runs the example."""
    parser = argparse.ArgumentParser(description="Experts scored with the HA-VLN metrics.")
    parser.add_argument("--scene", default="proc-0", help="procedural scene id")
    parser.add_argument("--episodes", type=int, default=3, help="paths to generate")
    parser.add_argument("--seed", type=int, default=0, help="seed of paths and people")
    args = parser.parse_args()

    episodes = procedural_episodes([args.scene], per_scene=args.episodes, seed=args.seed)
    sim = havln_mj.Simulator(humans=True)  # the people the episodes were annotated with
    sim.setRenderingEnabled(False)
    sim.setDiscretizedViewingAngles(True)
    sim.setSeed(args.seed)
    sim.initialize()

    evaluator = Evaluator(config=MetricConfig(critical="paper"))
    print("expert            " + "".join(f"{m:>7s}" for m in METRICS))
    for expert in (ShortestPathExpert(), HumanAwareExpert()):
        scored = []
        for episode in episodes:
            for k in range(len(episode.instructions)):
                trajectory = run_expert(sim, episode, expert, instruction=k)
                steps = [
                    (r.viewpoint, r.heading, r.elevation, r.is_crushed) for r in trajectory.records
                ]
                scored.append(EvalEpisode.from_ha_r2r(episode, steps, f"{episode.path_id}_{k}"))
        summary = evaluator.evaluate(scored, sim.graph).summary
        print(f"{expert.name:18s}" + "".join(f"{summary[m]:7.2f}" for m in METRICS))
    print(f"{len(scored)} instructions each; NE and TL in metres, TCR in collisions per episode")
    sim.close()


if __name__ == "__main__":
    main()
