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
import importlib
import json
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict
from pathlib import Path

import numpy as np
from tqdm import tqdm

from havln_mj.errors import HavlnError, InvalidArgumentError
from havln_mj.eval.outputs import RECORDINGS, Outputs
from havln_mj.scene.ids import expand_scene_ranges
from havln_mj.sim.settings import Settings
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
from havln_mj.tasks.metrics.config import COUNT_MODES, CRITICAL_MODES
from havln_mj.tasks.procedural import procedural_episodes
from havln_mj.tasks.protocol import PROTOCOL_NAMES, TaskProtocol, get_protocol

AGENTS = ("shortest", "oracle", "oracle-global", "random")
TABLE = (("NE", "ne"), ("TCR", "tcr"), ("CR", "cr"), ("SR", "sr"))
EXPERTS = ("shortest", "oracle", "oracle-global")  # capped by the protocol's expert step cap

AgentFactory = Callable[[np.random.Generator], Expert]


def protocol_of(args: argparse.Namespace) -> TaskProtocol:
    """The protocol ``args`` names, its metrics changed by ``--critical`` and ``--count``.

    ``--critical ha3d`` is HA3D's whole metric rule (:meth:`MetricConfig.ha3d`: people
    labelled Beginning/End, no clipping, raw CR); ``paper`` is ours; ``none`` adjusts nothing.
    """
    protocol = get_protocol(getattr(args, "protocol", "strict"))
    critical = getattr(args, "critical", None)
    if critical is not None:
        base = {"paper": MetricConfig(), "ha3d": MetricConfig.ha3d()}.get(
            critical, MetricConfig(critical="none")
        )
        protocol = protocol.with_metrics(**asdict(base))
    count = getattr(args, "count", None)
    if count is not None:
        protocol = protocol.with_metrics(count=count)
    return protocol


def metric_config(args: argparse.Namespace) -> MetricConfig:
    """How ``args``' evaluation scores episodes."""
    return protocol_of(args).metrics


def make_agent(name: str, args: argparse.Namespace | None = None) -> AgentFactory:
    """The factory of an agent given by name, ``module:callable`` or checkpoint file.

    Args:
        name: The agent.
        args: The evaluation's arguments (the protocol shapes the sub-optimal expert; a
            checkpoint agent renders features with its seed, connectivity folder and
            placements).

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
    protocol = protocol_of(args) if args is not None else get_protocol("strict")
    experts = {
        "shortest": lambda: ShortestPathExpert("graph"),
        "oracle": lambda: HumanAwareExpert.for_protocol(protocol, "local"),
        "oracle-global": lambda: HumanAwareExpert.for_protocol(protocol, "global"),
    }
    if name in experts:
        # One expert for every episode (it resets itself): its planners are kept per scan.
        expert = experts[name]()
        return lambda rng: expert
    if name == "random":
        return lambda rng: RandomWalkExpert(rng)
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


def _simulator(args: argparse.Namespace, film_width: int | None = None) -> Simulator:
    """The evaluation's simulator: discretised views, the protocol's rules and camera.

    Rendering is off, unless ``film_width`` asks for RGB frames that wide (the height keeps
    the protocol camera's aspect, which decides the navigable neighbours).
    """
    protocol = protocol_of(args)
    sim = Simulator(
        humans=not args.no_people,
        human_placements=args.human_placements,
        body=args.body,
        collision_rule=protocol.collision_rule,
        human_clock=protocol.human_clock,
        pinned_people=getattr(args, "pinned_people", False),
    )
    if args.connectivity_dir:
        sim.setNavGraphPath(str(args.connectivity_dir))
    default = Settings()
    width, height, vfov = protocol.camera or (default.width, default.height, default.vfov)
    if film_width is not None:
        width, height = film_width, round(film_width * height / width)
        sim.set_color_order("RGB")
    sim.setCameraResolution(width, height)
    sim.setCameraVFOV(vfov)
    sim.setRenderingEnabled(film_width is not None)
    sim.setDiscretizedViewingAngles(True)
    sim.setSeed(args.seed)
    sim.initialize()
    return sim


def people_report(sim: Simulator, episodes: Sequence[Episode]) -> dict:
    """Who the split is evaluated with, checked against the people its episodes name.

    Raises:
        MissingDataError: A real scan with nobody to place (see :mod:`havln_mj.sim.people`).
        InvalidArgumentError: An episode names a person (HA-R2R ``human_viewpoint``) the
            simulator does not place: the placements are not the dataset's.
    """
    scans = sorted({e.scan for e in episodes})
    sources: dict[str, list[str]] = {}
    count = 0
    for scan in scans:
        crowd = sim.crowd(scan)
        count += len(crowd)
        sources.setdefault(sim.people_source(scan), []).append(scan)
        placed = {getattr(p, "viewpoint", "") for p in getattr(crowd, "people", ())}
        for e in episodes:
            named = {h.viewpoint for h in e.humans or ()} if e.scan == scan else set()
            missing = sorted(named - placed)
            if missing and len(crowd):
                raise InvalidArgumentError(
                    f"path {e.path_id} names people at {missing} in scan {scan}, where the "
                    "simulator places nobody: these placements are not the ones the dataset "
                    "was made with (--human-placements)"
                )
    named = sum(len(e.humans or ()) for e in episodes)
    return {
        "count": count,
        "scans": len(scans),
        "named_by_episodes": named,
        "sources": {src: len(s) for src, s in sources.items()},
    }


def _banner(args: argparse.Namespace, split: str, episodes: Sequence[Episode], people: dict) -> str:
    protocol = protocol_of(args)
    n = sum(len(e.instructions) for e in episodes)
    where = "; ".join(f"{src} in {k} scan(s)" for src, k in people["sources"].items())
    lines = [
        f"eval {split}: agent {args.agent}, protocol {protocol.name}, {n} instructions in "
        f"{people['scans']} scan(s)",
        f"people: {people['count']} — {where}",
    ]
    blank = blank_instructions(episodes)
    if blank:
        lines.append(f"note: {len(blank)} blank instruction(s), evaluated as given: {blank}")
    return "\n".join(lines)


def _run_one(
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
    return {
        "instr_id": f"{episode.path_id}_{k}",
        "index": index,
        "scan": episode.scan,
        "stopped": trajectory.stopped,
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
    sim = _simulator(args)
    try:
        people = people_report(sim, episodes)
        print(_banner(args, split, episodes, people), file=sys.stderr, flush=True)
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
                    done = _run_one(sim, episode, k, index, make, args, protocol)
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


def _existing_dir(text: str) -> Path:
    path = Path(text).expanduser()
    if not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is not a folder")
    return path


def _existing_file(text: str) -> Path:
    path = Path(text).expanduser()
    if not path.is_file():
        raise argparse.ArgumentTypeError(f"{text!r} is not a file")
    return path


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    """Parses and checks the command-line arguments, before any work is done."""
    p = argparse.ArgumentParser(prog="python -m havln_mj.eval", description=__doc__.splitlines()[0])
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--dataset", nargs="+", help="R2R/HA-R2R JSON files or split names")
    src.add_argument(
        "--scenes", nargs="+", help="procedural scene ids (proc-<seed>; proc-A:B for a range)"
    )
    p.add_argument("--split", default=None, help="name of the split in the tables")
    p.add_argument("--per-scene", type=int, default=10, help="episodes per procedural scene (≥ 1)")
    p.add_argument(
        "--skip", type=int, default=0, help="leave out each scene's first paths (val_seen; ≥ 0)"
    )
    p.add_argument(
        "--agent",
        default="shortest",
        help=f"{', '.join(AGENTS)}, module:callable or a trained agent's checkpoint (.pt)",
    )
    p.add_argument("--body", choices=("point", "go1"), default="point")
    p.add_argument(
        "--protocol",
        choices=PROTOCOL_NAMES,
        default="strict",
        help="strict (ours, the default) or ha3d (HA3D's code, to compare with the paper)",
    )
    p.add_argument(
        "--critical",
        choices=CRITICAL_MODES,
        default=None,
        help="unavoidable people: paper (crux points, clipped), ha3d (HA3D's whole metric "
        "rule: Beginning/End, unclipped, raw CR) or none (default: the protocol's)",
    )
    p.add_argument(
        "--count",
        choices=COUNT_MODES,
        default=None,
        help="collisions per step (HA3D) or per visited viewpoint (default: step)",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of people and random agents (≥ 0)")
    p.add_argument("--no-people", action="store_true", help="evaluate without people")
    p.add_argument(
        "--pinned-people",
        action="store_true",
        help="people play their motions on the spot where they were placed (HA3D's barely move)",
    )
    p.add_argument("--connectivity-dir", type=_existing_dir, default=None)
    p.add_argument("--human-placements", type=_existing_file, default=None)
    p.add_argument(
        "--data-dir", type=_existing_dir, default=None, help="folder with r2r/ and ha_r2r/"
    )
    p.add_argument("--out", type=Path, default=Path("havln_eval"))
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue the interrupted evaluation in --out (same arguments)",
    )
    p.add_argument(
        "--record",
        type=int,
        default=0,
        metavar="N",
        help="film the first N instructions: a video and a top-down map each (≥ 0)",
    )
    p.add_argument(
        "--threads", type=int, default=None, help="torch threads of a trained agent (≥ 1)"
    )
    args = p.parse_args(argv)
    checks = [
        (args.per_scene >= 1, f"--per-scene must be at least 1, got {args.per_scene}"),
        (args.skip >= 0, f"--skip must be ≥ 0, got {args.skip}"),
        (0 <= args.seed < 2**32, f"--seed must be in [0, 2^32), got {args.seed}"),
        (args.record >= 0, f"--record must be ≥ 0 instructions, got {args.record}"),
        (
            args.threads is None or args.threads >= 1,
            f"--threads must be at least 1, got {args.threads}",
        ),
        (not args.out.is_file(), f"--out {str(args.out)!r} is a file; give a folder"),
        (args.split is None or args.split.strip(), f"--split must be a name, got {args.split!r}"),
        (args.agent.strip(), "--agent must name an agent"),
    ]
    for ok, message in checks:
        if not ok:
            p.error(message)
    if args.critical is None:
        args.critical = get_protocol(args.protocol).metrics.critical
    return args


def settings(args: argparse.Namespace) -> dict:
    """What decides an evaluation's results (``run.json``; ``--resume`` must match it)."""

    def path(p: Path | None) -> str | None:
        return None if p is None else str(Path(p).expanduser().resolve())

    protocol = protocol_of(args)
    return {
        "agent": args.agent,
        "body": args.body,
        "protocol": protocol.name,
        "metrics": asdict(protocol.metrics),
        "seed": args.seed,
        "people": not args.no_people,
        "pinned_people": args.pinned_people,
        "human_placements": path(args.human_placements),
        "connectivity_dir": path(args.connectivity_dir),
        "dataset": [str(d) for d in args.dataset] if args.dataset else None,
        "scenes": args.scenes,
        "per_scene": args.per_scene if args.scenes else None,
        "skip": args.skip if args.scenes else None,
        "split": args.split,
    }


SplitRunner = Callable[[argparse.Namespace, list[Episode], str], dict]


def _splits(args: argparse.Namespace) -> list[tuple[str, list[Episode]]]:
    if args.scenes:
        scenes = expand_scene_ranges(args.scenes)
        episodes = procedural_episodes(scenes, args.per_scene, args.seed, args.skip)
        return [(args.split or "procedural", episodes)]
    splits = []
    for name in args.dataset:
        data = load_dataset(name, connectivity_dir=args.connectivity_dir, data_dir=args.data_dir)
        if not data.episodes:
            raise InvalidArgumentError(f"dataset {data.source} has no episodes")
        _check_instructions(data.source, data.episodes)
        splits.append((args.split or Path(str(name)).stem, list(data.episodes)))
    return splits


def _check_instructions(source: str, episodes: Sequence[Episode]) -> None:
    """Refuses paths without instructions: they would be dropped from the split unseen."""
    ids = [e.path_id for e in episodes if not e.instructions]
    if ids:
        shown = ", ".join(map(str, ids[:5])) + (" ..." if len(ids) > 5 else "")
        raise InvalidArgumentError(
            f"dataset {source}: {len(ids)} path(s) with no instructions (path_id {shown}); "
            "every path needs at least one"
        )


def blank_instructions(episodes: Sequence[Episode]) -> list[str]:
    """The ids of blank instructions (HA-R2R val_seen has 13): evaluated, and reported."""
    return [
        f"{e.path_id}_{k}" for e in episodes for k, t in enumerate(e.instructions) if not t.strip()
    ]


def run_cli(args: argparse.Namespace, evaluate: SplitRunner = evaluate_split) -> int:
    """Loads the splits ``args`` names, evaluates each with ``evaluate`` and writes the files.

    ``evaluate`` is :func:`evaluate_split` here (which writes each instruction as it
    finishes); the Ray command passes its sharded version, whose results are written when
    the split is done.

    Returns:
        The process exit code: 0, 2 on bad input or a failure (with the message on stderr),
        130 when interrupted (finished instructions are kept for ``--resume``).
    """
    out = args.out.expanduser().resolve()
    outputs = None
    try:
        make_agent(args.agent, args)  # fail at once on a bad agent
        outputs = Outputs(out, settings(args), args.resume)
        if args.agent.endswith(".pt") and args.threads:
            import torch  # a trained agent: torch is installed

            torch.set_num_threads(args.threads)
        splits = _splits(args)
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


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the process exit code."""
    return run_cli(parse_args(argv))
