"""A gymnasium rollout: HA-R2R episodes in a procedural house, egocentric actions.

``import havln_mj.gym`` registers ``HAVLN-Graph-v0`` (graph moves), ``HAVLN-Ego-v0``
(egocentric actions) and ``HAVLN-Go1-v0`` (the GO1's forward / turn / stop). Observations are
dicts (RGB, instruction token ids, heading, navigable candidates, the collision flag); the
reward is the sum of the paper's terms, each of which is in ``info``. Needs the ``gym``
extra: ``pip install 'havln_mj[gym]'``.

    python examples/gym_rollout.py --size 64 --episodes 2
"""

import argparse

import gymnasium as gym
import numpy as np

import havln_mj.gym  # noqa: F401 - registers the environments


def main() -> None:
    """Parses the command line and runs the example."""
    parser = argparse.ArgumentParser(description="A gymnasium rollout.")
    parser.add_argument("--env", default="HAVLN-Ego-v0", help="environment id")
    parser.add_argument("--size", type=int, default=96, help="image width and height, pixels")
    parser.add_argument("--episodes", type=int, default=2, help="episodes to run")
    parser.add_argument("--max-steps", type=int, default=15, help="random actions per episode")
    parser.add_argument("--seed", type=int, default=0, help="seed of episodes and actions")
    args = parser.parse_args()

    env = gym.make(args.env, width=args.size, height=args.size, episodes_per_scene=4)
    rng = np.random.default_rng(args.seed)
    vocab = env.unwrapped.vocab  # the instruction's token ids index vocab.tokens
    for episode in range(args.episodes):
        obs, info = env.reset(seed=args.seed + episode)
        print(f"episode {episode} in {info['scan']}: {info['instruction']}")
        words = vocab.decode(obs["instruction"])
        print(f"  {len(words)} tokens of {len(vocab)}; rgb {obs['rgb'].shape}; {sorted(obs)}")
        total, collisions = 0.0, 0
        for step in range(args.max_steps):
            # Random moves, then STOP (action 0 in every action set).
            last = step == args.max_steps - 1
            action = 0 if last else int(rng.integers(1, env.action_space.n))
            obs, reward, terminated, truncated, info = env.step(action)
            total += reward
            collisions += int(obs["collision"])
            if terminated or truncated:
                break
        print(
            f"  {step + 1} steps, return {total:.2f}, {collisions} collisions, "
            f"goal {info['distance']:.1f} m away, success {info['success']}"
        )
    env.close()


if __name__ == "__main__":
    main()
