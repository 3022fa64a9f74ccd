"""Env steps/s of ``HAVLN-Graph-v0``: 1 env, ``AsyncVectorEnv`` (spawn) and Ray actors.

Two modes: rendering off (``rgb=False``) and RGB at 128×128. Actions are random valid moves
(a random non-empty candidate row, STOP with probability 0.05), drawn by whoever steps the
env; episodes reset automatically. Every setup is warmed up (simulators built, first reset)
before it is timed for ``--seconds``.

* ``single``: one env stepped in this process (also per CPU second: steadier on a shared
  machine; ``--single-only`` times this setup alone).
* ``async_vector``: ``gymnasium.vector.AsyncVectorEnv`` with ``--workers`` spawned workers,
  stepped in lockstep (steps/s counts every sub-env's step).
* ``ray``: ``--workers`` Ray actors, each owning an env and stepping it ``--chunk`` steps
  per remote call, all actors at once (local Ray with ``--workers`` CPUs).

``efficiency`` = workers' steps/s / (workers × single steps/s). Prints one JSON object.
Run: ``python benchmarks/bench_vector.py [--seconds S] [--workers N]``.
"""

from __future__ import annotations

import argparse
import json
import os
import time

os.environ.setdefault("MUJOCO_GL", "egl")

import gymnasium as gym
import numpy as np
from common import machine

ENV_ID = "HAVLN-Graph-v0"
MODES = {"render_off": {"rgb": False}, "rgb_128": {"rgb": True, "width": 128, "height": 128}}


def make_env(kwargs: dict) -> gym.Env:
    """The benchmarked env (registering the HA-VLN envs in whichever process calls it)."""
    import havln_mj.gym  # noqa: F401 - registers the envs

    return gym.make(ENV_ID, **kwargs)


def pick(mask: np.ndarray, rng: np.random.Generator) -> int:
    """A random valid action of one env from its ``candidate_mask``."""
    rows = np.flatnonzero(mask[1:]) + 1
    if len(rows) == 0 or rng.random() < 0.05:
        return 0
    return int(rng.choice(rows))


class Stepper:
    """One env stepped with random valid actions (the single and Ray setups)."""

    def __init__(self, kwargs: dict, seed: int) -> None:
        self.env = make_env(kwargs)
        self.rng = np.random.default_rng(seed)
        self.obs, _ = self.env.reset(seed=seed)

    def steps(self, n: int) -> int:
        for _ in range(n):
            obs, _, terminated, truncated, _ = self.env.step(
                pick(self.obs["candidate_mask"], self.rng)
            )
            self.obs = self.env.reset()[0] if terminated or truncated else obs
        return n


def bench_single(kwargs: dict, seconds: float) -> tuple[float, float]:
    """Steps per second and per CPU second of one env in this process."""
    s = Stepper(kwargs, 0)
    s.steps(20)
    n, t0, c0 = 0, time.perf_counter(), time.process_time()
    while time.perf_counter() - t0 < seconds:
        n += s.steps(10)
    return n / (time.perf_counter() - t0), n / (time.process_time() - c0)


def bench_async(kwargs: dict, seconds: float, workers: int) -> float:
    from functools import partial

    envs = gym.vector.AsyncVectorEnv(
        [partial(make_env, kwargs) for _ in range(workers)], context="spawn"
    )
    rng = np.random.default_rng(0)
    try:
        obs, _ = envs.reset(seed=list(range(workers)))

        def step(obs):
            actions = np.array([pick(m, rng) for m in obs["candidate_mask"]])
            return envs.step(actions)[0]

        for _ in range(20):
            obs = step(obs)
        n, t0 = 0, time.perf_counter()
        while time.perf_counter() - t0 < seconds:
            obs = step(obs)
            n += workers
        return n / (time.perf_counter() - t0)
    finally:
        envs.close()


def bench_ray(kwargs: dict, seconds: float, workers: int, chunk: int) -> float:
    import ray

    actor_cls = ray.remote(num_cpus=1)(Stepper)
    actors = [actor_cls.remote(kwargs, i) for i in range(workers)]
    try:
        ray.get([a.steps.remote(20) for a in actors])
        n, t0 = 0, time.perf_counter()
        while time.perf_counter() - t0 < seconds:
            n += sum(ray.get([a.steps.remote(chunk) for a in actors]))
        return n / (time.perf_counter() - t0)
    finally:
        for a in actors:
            ray.kill(a)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=5.0, help="timed seconds per setup")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--chunk", type=int, default=50, help="steps per Ray remote call")
    p.add_argument("--single-only", action="store_true", help="time the single env only")
    args = p.parse_args()

    results: dict = {}
    if args.single_only:
        for mode, kwargs in MODES.items():
            single, per_cpu = bench_single(kwargs, args.seconds)
            results[mode] = {
                "single_steps_per_s": round(single, 1),
                "single_steps_per_cpu_s": round(per_cpu, 1),
            }
    else:
        import ray

        ray.init(num_cpus=args.workers, include_dashboard=False, log_to_driver=False)
        try:
            for mode, kwargs in MODES.items():
                single, per_cpu = bench_single(kwargs, args.seconds)
                vec = bench_async(kwargs, args.seconds, args.workers)
                dist = bench_ray(kwargs, args.seconds, args.workers, args.chunk)
                scale = args.workers * single
                results[mode] = {
                    "single_steps_per_s": round(single, 1),
                    "single_steps_per_cpu_s": round(per_cpu, 1),
                    "async_vector_steps_per_s": round(vec, 1),
                    "ray_steps_per_s": round(dist, 1),
                    "async_vector_efficiency": round(vec / scale, 3),
                    "ray_efficiency": round(dist / scale, 3),
                }
        finally:
            ray.shutdown()
    print(
        json.dumps(
            {
                "benchmark": "vector",
                "env": ENV_ID,
                "workers": args.workers,
                "seconds": args.seconds,
                "ray_chunk": args.chunk,
                "machine": machine(),
                "results": results,
            },
            indent=1,
        )
    )


if __name__ == "__main__":
    main()
