"""``python -m havln_mj.eval``: run an agent over a split and score it with the HA-VLN metrics.

Episodes come from an R2R / HA-R2R file or split name (``--dataset``), or are generated in
procedural houses (``--scenes proc-0 proc-1 ...``: R2R-like shortest paths of 4–7 viewpoints
and 5–20 m with three instructions each, people as the simulator places them for ``--seed``).
Every instruction is run through ``havln_mj.Simulator`` (point body or GO1, rendering off,
people from HA3D's placement file or placed by HA3D's rule) with the chosen agent:

* ``shortest``: the optimal expert (shortest path, people ignored);
* ``oracle``: HA3D's sub-optimal human-aware expert (re-plans around people within 4.5 m);
* ``oracle-global``: the paper's variant that plans once around every person;
* ``random``: a seeded random walk of at most 30 steps (instruction ``i`` draws from
  ``default_rng([seed, i])``);
* ``module:callable``: your agent, a callable ``(rng) -> Expert`` (see
  :class:`havln_mj.tasks.experts.Expert`);
* a checkpoint file (``.pt``) of a trained VLN-CM or VLN-DT (:mod:`havln_mj.agents.train`);
  the features of scans it has not seen are rendered first, with the evaluation's people.

``--protocol`` chooses the rules (:mod:`havln_mj.tasks.protocol`): ``strict`` (ours: the
collision signal along every action, horizontally; people on each episode's own clock) or
``ha3d`` (HA3D's code: per state, 3-D from the camera, one shared frame counter, the expert
stopping when blocked and capped at 20 steps, HA3D's TCR and CR), to compare with the
HA-VLN paper. ``--critical`` and ``--count`` change the metrics' rules alone.

A real scan needs people to be evaluated with: HA3D's placement file lists the 90 Matterport3D
scans; a scan it does not list needs its ``.house`` file (region labels for HA3D's rule), or
the evaluation stops with an error naming ``--human-placements`` (``--no-people`` evaluates
an empty building on purpose). An HA-R2R episode naming a person the simulator does not
place is an error too: the placements are not the ones the dataset was made with.

Writes to ``--out`` (see :mod:`havln_mj.eval.outputs`): ``run.json`` first,
``instructions.jsonl`` as instructions finish (``--resume`` continues an interrupted
evaluation), then ``episodes.json`` (per-instruction metrics), ``submission.json``
(trajectories in the R2R submission format), ``summary.md`` and ``summary.json`` (NE, TCR,
CR, SR per split in the paper's layout, the other metrics, the protocol and where the people
came from). ``--record N`` films the first N instructions (``recordings/``: a video and a
top-down map each, see :mod:`havln_mj.eval.record`).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict

import numpy as np
from tqdm import tqdm

from havln_mj.errors import HavlnError
from havln_mj.eval.cli import load_splits, parse_args, settings
from havln_mj.eval.outputs import RECORDINGS, Outputs
from havln_mj.eval.setup import (
    EXPERTS,
    AgentFactory,
    banner,
    blank_instructions,
    evaluation_simulator,
    make_agent,
    people_report,
    protocol_of,
)
from havln_mj.scene.navgraph import stair_edges
from havln_mj.sim.simulator import Simulator
from havln_mj.tasks.episodes import Episode
from havln_mj.tasks.experts import run_expert
from havln_mj.tasks.metrics import EvalEpisode, Evaluator
from havln_mj.tasks.protocol import TaskProtocol

__all__ = ["evaluate_split", "make_agent", "parse_args", "run_cli", "score_split"]


TABLE = (("NE", "ne"), ("TCR", "tcr"), ("CR", "cr"), ("SR", "sr"))


def run_instruction(
    sim: Simulator,
    episode: Episode,
    k: int,
    index: int,
    make: AgentFactory,
    args: argparse.Namespace,
    protocol: TaskProtocol,
) -> dict:
    """Runs instruction ``k`` of ``episode``; the record ``instructions.jsonl`` keeps."""
    frame0, t0 = sim.human_clock_frame, time.perf_counter()
    cap = protocol.expert_max_steps if args.agent in EXPERTS else None
    trajectory = run_expert(
        sim,
        episode,
        make(np.random.default_rng([args.seed, index])),
        instruction=k,
        max_steps=cap,
        protocol=protocol,
    )
    end = trajectory.records[-1]
    stairs = stair_edges(sim.graph(episode.scan), episode.path)
    return {
        "instr_id": f"{episode.path_id}_{k}",
        "index": index,
        "scan": episode.scan,
        "stopped": trajectory.stopped,
        "terrain": "stairs" if stairs else "flat",
        "stair_edges": [list(e) for e in stairs],
        "fell": end.fell,
        "true_distance": round(float(end.distance), 4),
        "sim_seconds": round(float(end.time), 3),
        "steps": [[r.viewpoint, r.heading, r.elevation, r.is_crushed] for r in trajectory.records],
        "r2r": trajectory.r2r(),
        "frames": [frame0, sim.human_clock_frame],
        "seconds": round(time.perf_counter() - t0, 6),
    }


def evaluate_split(
    args: argparse.Namespace,
    episodes: list[Episode],
    split: str,
    outputs: Outputs | None = None,
) -> dict:
    """Runs the agent over every instruction of ``episodes``; returns the split's report.

    Args:
        args: The evaluation's arguments.
        episodes: The split's episodes.
        split: The split's name in the report.
        outputs: Where finished instructions are written as they come (and which are
            already done, when resuming); None keeps everything in memory.
    """
    protocol = protocol_of(args)
    sim = evaluation_simulator(args)
    try:
        people = people_report(sim, episodes)
        print(banner(args, split, episodes, people), file=sys.stderr, flush=True)
        make = make_agent(args.agent, args)
        records = []
        index, resume_frame = 0, None
        for episode in tqdm(episodes, desc=split, unit="path"):
            for k in range(len(episode.instructions)):
                done = outputs.done.get((split, f"{episode.path_id}_{k}")) if outputs else None
                if done is not None:
                    resume_frame = done["frames"][1]
                else:
                    if resume_frame is not None:  # where HA3D's counter was when it stopped
                        sim.set_rules(frame=resume_frame)
                        resume_frame = None
                    done = run_instruction(sim, episode, k, index, make, args, protocol)
                    done["split"] = split
                    if outputs is not None:
                        outputs.add(done)
                records.append(done)
                index += 1
        report = score_split(args, episodes, split, records, sim, people)
    finally:
        sim.close()
    return report


def score_split(
    args: argparse.Namespace,
    episodes: Sequence[Episode],
    split: str,
    records: Sequence[dict],
    sim: Simulator,
    people: dict | None = None,
) -> dict:
    """Scores the split's instruction records (in episode order) with the protocol's metrics."""
    protocol = protocol_of(args)
    items = [(e, k) for e in episodes for k in range(len(e.instructions))]
    scored = [
        EvalEpisode.from_ha_r2r(e, r["steps"], episode_id=r["instr_id"])
        for (e, _), r in zip(items, records, strict=True)
    ]
    result = Evaluator(config=protocol.metrics).evaluate(scored, sim.graph)
    runs = []
    for r, metrics in zip(records, result.per_episode, strict=True):
        runs.append({"instr_id": r["instr_id"], "scan": r["scan"], "stopped": r["stopped"]})
        runs[-1].update(metrics)
    seconds = sum(r["seconds"] for r in records)
    summary = dict(result.summary)
    summary["by_terrain"] = terrain_report(records, protocol.metrics.success_distance)
    summary.update(
        split=split,
        agent=args.agent,
        body=args.body,
        protocol=protocol.name,
        critical=protocol.metrics.critical,
        metrics=asdict(protocol.metrics),
        collision_rule=asdict(sim.collision_rule),
        human_clock=asdict(sim.human_clock),
        expert_max_steps=protocol.expert_max_steps if args.agent in EXPERTS else None,
        people=people,
        pinned_people=bool(getattr(args, "pinned_people", False)),
        blank_instructions=blank_instructions(episodes),
        instructions=len(runs),
        seconds=round(seconds, 2),
        instructions_per_s=round(len(runs) / seconds, 1) if seconds > 0 else None,
    )
    submission = [{"instr_id": r["instr_id"], "trajectory": r["r2r"]} for r in records]
    return {"summary": summary, "episodes": runs, "submission": submission, "records": records}


def terrain_report(records: Sequence[dict], success_distance: float) -> dict:
    """Success, falls and time for flat episodes and for those whose path has a stair edge.

    Measured from where the body truly ended (the task step's distance, from the robot's
    true pose with the GO1), so a robot that stalled or fell on a stair counts as it is: a
    fall is a fall and is never left out.
    """
    out = {}
    for terrain in ("flat", "stairs"):
        rows = [r for r in records if r.get("terrain") == terrain]
        if not rows:
            continue
        n = len(rows)
        out[terrain] = {
            "instructions": n,
            "success_rate": sum(
                r["stopped"] and r["true_distance"] < success_distance for r in rows
            )
            / n,
            "falls": sum(bool(r["fell"]) for r in rows),
            "mean_distance_m": sum(r["true_distance"] for r in rows) / n,
            "mean_sim_seconds": sum(r["sim_seconds"] for r in rows) / n,
        }
    return out


def markdown_table(summaries: Sequence[dict]) -> str:
    """The paper's layout: one row per agent, NE / TCR / CR / SR per split."""
    splits = [s["split"] for s in summaries]
    head = "| agent | " + " | ".join(f"{sp} NE | TCR | CR | SR" for sp in splits) + " |"
    rule = "|---|" + "---|---|---|---|" * len(splits)
    cells = []
    for s in summaries:
        cells += [f"{s[key]:.2f}" if s.get(key) is not None else "–" for _, key in TABLE]
    first = summaries[0]
    name = f"{first['agent']} ({first.get('protocol', 'strict')})"
    return "\n".join([head, rule, f"| {name} | " + " | ".join(cells) + " |"])


SplitRunner = Callable[[argparse.Namespace, list[Episode], str], dict]


def run_cli(args: argparse.Namespace, evaluate: SplitRunner = evaluate_split) -> int:
    """Loads the splits ``args`` names, evaluates each with ``evaluate`` and writes the files.

    ``evaluate`` is :func:`evaluate_split` here (which writes each instruction as it
    finishes); the Ray command passes its sharded version, whose results are written when
    the split is done.

    Returns:
        0 when done; 2 on bad input or a failure (with the message on stderr); 130 when
        interrupted (finished instructions are kept for ``--resume``).
    """
    out = args.out.expanduser().resolve()
    outputs = None
    try:
        make_agent(args.agent, args)  # fail at once on a bad agent
        outputs = Outputs(out, settings(args), args.resume)
        if args.agent.endswith(".pt") and args.threads:
            import torch  # a trained agent: torch is installed

            torch.set_num_threads(args.threads)
        splits = load_splits(args)
        outputs.begin()
        reports = []
        for split, episodes in splits:
            if evaluate is evaluate_split:
                reports.append(evaluate_split(args, episodes, split, outputs))
            else:
                reports.append(evaluate(args, episodes, split))
                for record in reports[-1].get("records", ()):
                    outputs.add({**record, "split": split})
        summaries = [r["summary"] for r in reports]
        table = markdown_table(summaries)
        outputs.finish(
            [e for r in reports for e in r["episodes"]],
            [s for r in reports for s in r["submission"]],
            summaries,
            table,
        )
        if args.record:
            from havln_mj.eval.record import record_episodes  # rendering: only when asked

            for (_, episodes), report in zip(splits, reports, strict=True):
                record_episodes(args, episodes, report["records"][: args.record], out / RECORDINGS)
    except HavlnError as exc:
        print(f"error: {exc}", file=sys.stderr)
        if outputs is not None and outputs.done:
            print(f"finished instructions are kept in {out}: rerun with --resume", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        kept = len(outputs.done) if outputs is not None else 0
        print(
            f"interrupted: {kept} finished instructions kept in {out}; rerun with --resume",
            file=sys.stderr,
        )
        return 130
    finally:
        if outputs is not None:
            outputs.close()
    print(table)
    print(json.dumps(summaries, indent=1))
    return 0
