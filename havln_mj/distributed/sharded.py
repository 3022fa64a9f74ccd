"""Evaluation sharded over Ray actors: ``havln_mj eval --workers N [--address ADDR]``.

``--workers`` Ray actors each own a ``Simulator`` built like the single-process one;
``--address`` picks the cluster (default a local Ray; ``auto``: the running cluster;
``ray://host:10001``: Ray Client). The instructions are cut into contiguous shards, run on the
actors, merged back in the original order and scored once in the driver with the same
:class:`~havln_mj.tasks.metrics.evaluator.Evaluator`, so the per-instruction metrics and the
summary equal :func:`havln_mj.eval.run.evaluate_split`'s (only ``seconds`` and
``instructions_per_s`` differ): instruction ``i``'s ``random`` agent draws from its own
generator ``default_rng([seed, i])`` in either.
"""

from __future__ import annotations

import argparse
import itertools
import time

from tqdm import tqdm

from havln_mj.distributed._ray import ensure_ray
from havln_mj.errors import InvalidArgumentError
from havln_mj.eval.run import run_instruction, score_split
from havln_mj.eval.setup import evaluation_simulator, make_agent, people_report, protocol_of
from havln_mj.tasks.episodes import Episode

PIECES_PER_SHARD = 20
"""Pieces each actor's shard is sent in, for the progress bar."""


class ShardRunner:
    """A Ray actor's state: one simulator, running shards of instructions."""

    def __init__(self, args: argparse.Namespace) -> None:
        self._args = args
        self._sim = evaluation_simulator(args)
        self._make = make_agent(args.agent, args)
        self._protocol = protocol_of(args)

    def run(self, items: list[tuple[int, Episode, int]]) -> list[dict]:
        """Runs ``(index, episode, k)`` items; one ``instructions.jsonl`` record per item."""
        return [
            run_instruction(self._sim, episode, k, index, self._make, self._args, self._protocol)
            for index, episode, k in items
        ]

    def close(self) -> None:
        """Closes the simulator."""
        self._sim.close()


def _shards(n: int, workers: int) -> list[range]:
    """``range(n)`` cut into at most ``workers`` contiguous, nearly equal, non-empty pieces."""
    workers = max(1, min(workers, n))
    bounds = [round(i * n / workers) for i in range(workers + 1)]
    return [range(a, b) for a, b in itertools.pairwise(bounds) if b > a]


def _pieces(shard: range, size: int) -> list[range]:
    """``shard`` cut into contiguous pieces of ``size`` (the last one shorter)."""
    return [range(i, min(i + size, shard.stop)) for i in range(shard.start, shard.stop, size)]


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
    if workers > 1 and protocol_of(args).name == "ha3d":
        # HA3D's people run on one frame counter shared by every episode in order: shards on
        # separate actors would each start it afresh and score different people.
        raise InvalidArgumentError(
            "--protocol ha3d needs --workers 1 (HA3D's human clock is shared by all episodes "
            "in order); use the strict protocol to shard"
        )
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
            # Each actor's shard goes in small pieces (queued in order on the actor), so the
            # bar moves as instructions finish on any worker.
            size = max(1, len(items) // (len(shards) * PIECES_PER_SHARD))
            sizes = {
                a.run.remote([items[i] for i in piece]): len(piece)
                for a, shard in zip(actors, shards, strict=True)
                for piece in _pieces(shard, size)
            }
            pending = list(sizes)
            with tqdm(
                total=len(items), desc=f"{split} ({len(actors)} workers)", unit="instr"
            ) as bar:
                while pending:
                    done, pending = ray.wait(pending, num_returns=1)
                    records.extend(ray.get(done[0]))
                    bar.update(sizes[done[0]])
        finally:
            for a in actors:
                ray.kill(a)
    records.sort(key=lambda r: r["index"])
    seconds = time.perf_counter() - t0
    sim = evaluation_simulator(args)  # the driver's graphs and people for scoring
    try:
        report = score_split(args, episodes, split, records, sim, people_report(sim, episodes))
    finally:
        sim.close()
    n = len(records)
    report["summary"].update(
        seconds=round(seconds, 2), instructions_per_s=round(n / seconds, 1) if seconds > 0 else None
    )
    return report
