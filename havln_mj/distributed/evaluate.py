"""``python -m havln_mj.distributed.evaluate``: :mod:`havln_mj.eval` sharded over Ray actors.

Takes every argument of ``python -m havln_mj.eval`` plus ``--workers`` (Ray actors, each
owning a ``Simulator`` built like the single-process one) and ``--address`` (None: local Ray;
``auto``: the running cluster; ``ray://host:10001``: Ray Client). The instructions are cut
into contiguous shards, run on the actors, merged back in the original order and scored
once in the driver with the same :class:`havln_mj.tasks.metrics.Evaluator`, so the
per-instruction metrics and the summary equal :func:`havln_mj.eval.run.evaluate_split`'s
(only ``seconds`` and ``instructions_per_s`` differ).

Caveat: ``evaluate_split`` draws every ``random`` agent from one generator in instruction
order, which shards cannot reproduce; here instruction ``i`` gets its own generator
``default_rng([seed, i])``, so ``random`` results are deterministic for any ``--workers`` but
differ from the single-process run. The other built-in agents use no generator and match.
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from collections.abc import Sequence

import numpy as np

from havln_mj.distributed._ray import ensure_ray
from havln_mj.errors import InvalidArgumentError
from havln_mj.eval.run import _simulator, make_agent, run_cli
from havln_mj.eval.run import parse_args as eval_parse_args
from havln_mj.tasks.episodes import Episode
from havln_mj.tasks.experts import run_expert
from havln_mj.tasks.metrics import EvalEpisode, Evaluator, MetricConfig


class ShardRunner:
    """A Ray actor's state: one simulator, running shards of instructions."""

    def __init__(self, args: argparse.Namespace) -> None:
        self._args = args
        self._sim = _simulator(args)
        self._make = make_agent(args.agent, args)

    def run(self, items: list[tuple[int, Episode, int]]) -> list[dict]:
        """Runs ``(index, episode, k)`` items; one EvalEpisode-ready record per item."""
        out = []
        for index, episode, k in items:
            rng = np.random.default_rng([self._args.seed, index])
            trajectory = run_expert(self._sim, episode, self._make(rng), instruction=k)
            out.append(
                {
                    "index": index,
                    "instr_id": f"{episode.path_id}_{k}",
                    "r2r": trajectory.r2r(),
                    "steps": [
                        [r.viewpoint, r.heading, r.elevation, r.is_crushed]
                        for r in trajectory.records
                    ],
                    "stopped": trajectory.stopped,
                }
            )
        return out

    def close(self) -> None:
        """Closes the simulator."""
        self._sim.close()


def _shards(n: int, workers: int) -> list[range]:
    """``range(n)`` cut into at most ``workers`` contiguous, nearly equal, non-empty pieces."""
    workers = max(1, min(workers, n))
    bounds = [round(i * n / workers) for i in range(workers + 1)]
    return [range(a, b) for a, b in itertools.pairwise(bounds) if b > a]


def evaluate_split_ray(
    args: argparse.Namespace,
    episodes: list[Episode],
    split: str,
    workers: int = 2,
    address: str | None = None,
) -> dict:
    """:func:`havln_mj.eval.run.evaluate_split` with the instructions run on Ray actors.

    Args:
        args: The arguments of ``python -m havln_mj.eval`` (see its ``parse_args``).
        episodes: The split's episodes.
        split: The split's name in the report.
        workers: Ray actors (one CPU and one simulator each).
        address: Ray address (None: local; ``"auto"``; ``"ray://host:port"``); ignored when
            Ray is already initialised.

    Returns:
        ``{"summary", "episodes", "submission"}`` as ``evaluate_split`` returns them.
    """
    if workers < 1:
        raise InvalidArgumentError(f"workers must be >= 1, got {workers}")
    make_agent(args.agent)  # fail in the driver on a bad agent
    ray = ensure_ray(address)
    items = [
        (i, episode, k)
        for i, (episode, k) in enumerate(
            (e, k) for e in episodes for k in range(len(e.instructions))
        )
    ]
    t0 = time.perf_counter()
    records: list[dict] = []
    if items:
        actor_cls = ray.remote(num_cpus=1)(ShardRunner)
        shards = _shards(len(items), workers)
        actors = [actor_cls.remote(args) for _ in shards]
        try:
            futures = [
                a.run.remote([items[i] for i in shard])
                for a, shard in zip(actors, shards, strict=True)
            ]
            records = [r for part in ray.get(futures) for r in part]
        finally:
            for a in actors:
                ray.kill(a)
    records.sort(key=lambda r: r["index"])
    seconds = time.perf_counter() - t0

    runs, submission, scored = [], [], []
    for (_, episode, _), rec in zip(items, records, strict=True):
        instr_id = rec["instr_id"]
        submission.append({"instr_id": instr_id, "trajectory": rec["r2r"]})
        scored.append(EvalEpisode.from_ha_r2r(episode, rec["steps"], episode_id=instr_id))
        runs.append({"instr_id": instr_id, "scan": episode.scan, "stopped": rec["stopped"]})
    sim = _simulator(args)  # the driver's graphs for scoring
    try:
        result = Evaluator(config=MetricConfig(critical=args.critical)).evaluate(scored, sim.graph)
    finally:
        sim.close()
    for run, metrics in zip(runs, result.per_episode, strict=True):
        run.update(metrics)
    summary = dict(result.summary)
    summary.update(
        split=split,
        agent=args.agent,
        body=args.body,
        critical=args.critical,
        instructions=len(runs),
        seconds=round(seconds, 2),
        instructions_per_s=round(len(runs) / seconds, 1) if seconds > 0 else None,
    )
    return {"summary": summary, "episodes": runs, "submission": submission}


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    """``python -m havln_mj.eval``'s arguments plus ``--workers`` and ``--address``."""
    extra = argparse.ArgumentParser(prog="python -m havln_mj.distributed.evaluate", add_help=False)
    extra.add_argument("--workers", type=int, default=2, help="Ray actors (default 2)")
    extra.add_argument(
        "--address", default=None, help="Ray address: auto, ray://host:10001 (default: local)"
    )
    argv = list(sys.argv[1:] if argv is None else argv)
    if "-h" in argv or "--help" in argv:
        print(
            __doc__.splitlines()[0] + "\n\nRay options: --workers N (default 2), "
            "--address ADDR (auto, ray://host:10001; default: local Ray)\n"
        )
    known, rest = extra.parse_known_args(argv)
    args = eval_parse_args(rest)
    args.workers, args.address = known.workers, known.address
    return args


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the process exit code (writes what ``havln_mj.eval`` writes)."""
    args = parse_args(argv)

    def sharded(a: argparse.Namespace, episodes: list[Episode], split: str) -> dict:
        return evaluate_split_ray(a, episodes, split, workers=a.workers, address=a.address)

    return run_cli(args, sharded)


if __name__ == "__main__":
    sys.exit(main())
