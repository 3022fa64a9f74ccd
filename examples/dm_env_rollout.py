"""A ``dm_env`` rollout for dm_control users: the same episodes and rules as the gym envs.

``havln_mj.dmenv.load(action_set, **options)`` returns a ``dm_env.Environment`` over the
same episode core as the gymnasium environments: ``reset()`` gives a ``FIRST`` time step,
STOP (or a fall) a ``LAST`` one with discount 0, the step limit a ``LAST`` one with discount
1. Needs the ``dm`` extra: ``pip install 'havln_mj[dm]'``.

    python examples/dm_env_rollout.py --steps 10
"""

import argparse

import numpy as np

from havln_mj import dmenv


def main() -> None:
    """Parses the command line and runs the example."""
    parser = argparse.ArgumentParser(description="A dm_env rollout.")
    parser.add_argument("--action-set", default="ego", help="graph, ego or robot")
    parser.add_argument("--steps", type=int, default=10, help="random actions before STOP")
    parser.add_argument("--seed", type=int, default=0, help="seed of episodes and actions")
    args = parser.parse_args()

    # Without image fields nothing is rendered: the fastest way to run episodes.
    env = dmenv.load(args.action_set, rgb=False, seed=args.seed, episodes_per_scene=4)
    print("observations:", {k: v.shape for k, v in env.observation_spec().items()})
    print("actions:", env.action_spec())
    rng = np.random.default_rng(args.seed)
    n = env.action_spec().num_values
    timestep = env.reset()
    print(f"{timestep.step_type.name}: {env.info['instruction']}")
    returns = 0.0
    for step in range(args.steps + 1):
        action = 0 if step == args.steps else int(rng.integers(1, n))  # random moves, then STOP
        timestep = env.step(action)
        returns += timestep.reward
        if timestep.last():
            break
    print(
        f"{timestep.step_type.name}: return {returns:.2f}, discount {timestep.discount}, "
        f"goal {env.info['distance']:.1f} m away, success {env.info['success']}"
    )
    env.close()


if __name__ == "__main__":
    main()
