"""``python -m havln_mj.eval``: run an agent over a split and score it with the HA-VLN metrics.

Episodes come from an R2R / HA-R2R file or split name (``--dataset``), or are generated in
procedural houses (``--scenes proc-0 proc-1 ...``: R2R-like shortest paths of 4–7 viewpoints
and 5–20 m with three instructions each, people as the simulator places them for ``--seed``).
Every instruction is run through ``havln_mj.Simulator`` (point body or GO1, rendering off,
people placed by HA3D's rule or HA3D's placement file) with the chosen agent:

* ``shortest``: the optimal expert (shortest path, people ignored);
* ``oracle``: HA3D's sub-optimal human-aware expert (re-plans around people within 4.5 m);
* ``oracle-global``: the paper's variant that plans once around every person;
* ``random``: a seeded random walk of at most 30 steps;
* ``module:callable``: your agent, a callable ``(rng) -> Expert`` (see
  :class:`havln_mj.tasks.experts.Expert`);
* a checkpoint file (``.pt``) of a trained VLN-CM or VLN-DT (:mod:`havln_mj.agents.train`);
  the features of scans it has not seen are rendered first, with the evaluation's people.

Writes to ``--out``: ``episodes.json`` (per-instruction metrics), ``submission.json``
(trajectories in the R2R submission format), ``summary.json`` and ``summary.md`` (NE, TCR,
CR, SR per split, the paper's layout, plus the other metrics).
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
from tqdm import tqdm

from havln_mj.cache import atomic_write_bytes, atomic_write_json
from havln_mj.errors import HavlnError, InvalidArgumentError
from havln_mj.scene.ids import expand_scene_ranges
from havln_mj.sim.simulator import Simulator
from havln_mj.tasks.datasets import load_dataset
from havln_mj.tasks.episodes import Episode
from havln_mj.tasks.experts import (
    Expert,
    HumanAwareExpert,
    RandomWalkExpert,
    ShortestPathExpert,
    run_expert,
)
from havln_mj.tasks.metrics import EvalEpisode, Evaluator, MetricConfig
from havln_mj.tasks.procedural import procedural_episodes

AGENTS = ("shortest", "oracle", "oracle-global", "random")
TABLE = (("NE", "ne"), ("TCR", "tcr"), ("CR", "cr"), ("SR", "sr"))


def make_agent(
    name: str, args: argparse.Namespace | None = None
) -> Callable[[np.random.Generator], Expert]:
    """The factory of an agent given by name, ``module:callable`` or checkpoint file.

    Args:
        name: The agent.
        args: The evaluation's arguments (a checkpoint agent renders features with its
            seed, connectivity folder and placements).

    Raises:
        InvalidArgumentError: Unknown name, or a ``module:callable`` that cannot be imported.
        MissingDataError: A checkpoint file that does not exist.
    """
    if name.endswith(".pt"):
        from havln_mj.agents.policy import load_agent  # torch: only for trained agents

        return load_agent(
            name,
            seed=getattr(args, "seed", 0),
            connectivity_dir=getattr(args, "connectivity_dir", None),
            human_placements=getattr(args, "human_placements", None),
        )
    builtin = {
        "shortest": lambda rng: ShortestPathExpert("graph"),
        "oracle": lambda rng: HumanAwareExpert(mode="local"),
        "oracle-global": lambda rng: HumanAwareExpert(mode="global"),
        "random": lambda rng: RandomWalkExpert(rng),
    }
    if name in builtin:
        return builtin[name]
    module, _, attr = name.partition(":")
    if not attr:
        raise InvalidArgumentError(
            f"unknown agent {name!r}; valid: {', '.join(AGENTS)}, 'module:callable' or a "
            "checkpoint file (.pt)"
        )
    try:
        return getattr(importlib.import_module(module), attr)
    except (ImportError, AttributeError) as exc:
        raise InvalidArgumentError(f"cannot load agent {name!r}: {exc}") from None


def _simulator(args: argparse.Namespace) -> Simulator:
    sim = Simulator(
        humans=not args.no_people, human_placements=args.human_placements, body=args.body
    )
    if args.connectivity_dir:
        sim.setNavGraphPath(str(args.connectivity_dir))
    sim.setRenderingEnabled(False)
    sim.setDiscretizedViewingAngles(True)
    sim.setSeed(args.seed)
    sim.initialize()
    return sim


def evaluate_split(args: argparse.Namespace, episodes: list[Episode], split: str) -> dict:
    """Runs the agent over every instruction of ``episodes``; returns the split's report."""
    sim = _simulator(args)
    make = make_agent(args.agent, args)
    rng = np.random.default_rng(args.seed)
    config = MetricConfig(critical=args.critical)
    evaluator = Evaluator(config=config)
    runs, submission, scored = [], [], []
    t0 = time.perf_counter()
    for episode in tqdm(episodes, desc=split, unit="path"):
        for k in range(len(episode.instructions)):
            trajectory = run_expert(sim, episode, make(rng), instruction=k)
            instr_id = f"{episode.path_id}_{k}"
            submission.append({"instr_id": instr_id, "trajectory": trajectory.r2r()})
            steps = [
                [r.viewpoint, r.heading, r.elevation, r.is_crushed] for r in trajectory.records
            ]
            scored.append(EvalEpisode.from_ha_r2r(episode, steps, episode_id=instr_id))
            runs.append({"instr_id": instr_id, "scan": episode.scan, "stopped": trajectory.stopped})
    seconds = time.perf_counter() - t0
    result = evaluator.evaluate(scored, sim.graph)
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
    sim.close()
    return {"summary": summary, "episodes": runs, "submission": submission}


def markdown_table(summaries: Sequence[dict]) -> str:
    """The paper's layout: one row per agent, NE / TCR / CR / SR per split."""
    splits = [s["split"] for s in summaries]
    head = "| agent | " + " | ".join(f"{sp} NE | TCR | CR | SR" for sp in splits) + " |"
    rule = "|---|" + "---|---|---|---|" * len(splits)
    cells = []
    for s in summaries:
        cells += [f"{s[key]:.2f}" if s.get(key) is not None else "–" for _, key in TABLE]
    return "\n".join([head, rule, f"| {summaries[0]['agent']} | " + " | ".join(cells) + " |"])


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    """Parses command-line arguments."""
    p = argparse.ArgumentParser(prog="python -m havln_mj.eval", description=__doc__.splitlines()[0])
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--dataset", nargs="+", help="R2R/HA-R2R JSON files or split names")
    src.add_argument(
        "--scenes", nargs="+", help="procedural scene ids (proc-<seed>; proc-A:B for a range)"
    )
    p.add_argument("--split", default=None, help="name of the split in the tables")
    p.add_argument("--per-scene", type=int, default=10, help="episodes per procedural scene")
    p.add_argument(
        "--skip", type=int, default=0, help="leave out each scene's first paths (val_seen)"
    )
    p.add_argument(
        "--agent",
        default="shortest",
        help=f"{', '.join(AGENTS)}, module:callable or a trained agent's checkpoint (.pt)",
    )
    p.add_argument("--body", choices=("point", "go1"), default="point")
    p.add_argument("--critical", choices=("paper", "ha3d", "none"), default="paper")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--no-people", action="store_true", help="evaluate without people")
    p.add_argument("--connectivity-dir", type=Path, default=None)
    p.add_argument("--human-placements", type=Path, default=None)
    p.add_argument("--data-dir", type=Path, default=None, help="folder with r2r/ and ha_r2r/")
    p.add_argument("--out", type=Path, default=Path("havln_eval"))
    p.add_argument(
        "--threads", type=int, default=None, help="torch threads of a trained agent (1: busy CPU)"
    )
    return p.parse_args(argv)


SplitRunner = Callable[[argparse.Namespace, list[Episode], str], dict]


def run_cli(args: argparse.Namespace, evaluate: SplitRunner = evaluate_split) -> int:
    """Loads the splits ``args`` names, evaluates each with ``evaluate`` and writes the files.

    ``evaluate`` is :func:`evaluate_split` here; the Ray command passes its sharded version.

    Returns:
        The process exit code (2 on bad input, with the message on stderr).
    """
    if args.agent.endswith(".pt") and args.threads:
        import torch  # a trained agent: torch is installed

        torch.set_num_threads(args.threads)
    try:
        make_agent(args.agent, args)  # fail at once on a bad agent
        splits: list[tuple[str, list[Episode]]] = []
        if args.scenes:
            scenes = expand_scene_ranges(args.scenes)
            episodes = procedural_episodes(scenes, args.per_scene, args.seed, args.skip)
            splits.append((args.split or "procedural", episodes))
        else:
            for name in args.dataset:
                data = load_dataset(
                    name, connectivity_dir=args.connectivity_dir, data_dir=args.data_dir
                )
                splits.append((args.split or Path(str(name)).stem, list(data.episodes)))
        out = args.out.expanduser().resolve()
        out.mkdir(parents=True, exist_ok=True)
        reports = [evaluate(args, episodes, split) for split, episodes in splits]
    except HavlnError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    summaries = [r["summary"] for r in reports]
    atomic_write_json(out / "episodes.json", [e for r in reports for e in r["episodes"]])
    atomic_write_json(out / "submission.json", [s for r in reports for s in r["submission"]])
    atomic_write_json(out / "summary.json", summaries, indent=1)
    table = markdown_table(summaries)
    atomic_write_bytes(out / "summary.md", (table + "\n").encode())
    print(table)
    print(json.dumps(summaries, indent=1))
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the process exit code."""
    return run_cli(parse_args(argv))
