"""What an evaluation is run with: its protocol, agent, simulator and people.

Shared by ``python -m havln_mj.eval`` (:mod:`havln_mj.eval.run`), its recordings
(:mod:`havln_mj.eval.record`), the benchmark and the Ray evaluation.
"""

from __future__ import annotations

import argparse
import importlib
from collections.abc import Callable, Sequence
from dataclasses import asdict

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.sim.settings import Settings
from havln_mj.sim.simulator import Simulator
from havln_mj.tasks.episodes import Episode
from havln_mj.tasks.experts import (
    Expert,
    HumanAwareExpert,
    RandomWalkExpert,
    ShortestPathExpert,
)
from havln_mj.tasks.metrics import MetricConfig
from havln_mj.tasks.protocol import TaskProtocol, get_protocol

AGENTS = ("shortest", "oracle", "oracle-global", "random")
EXPERTS = ("shortest", "oracle", "oracle-global")  # capped by the protocol's expert step cap

AgentFactory = Callable[[np.random.Generator], Expert]


def protocol_of(args: argparse.Namespace) -> TaskProtocol:
    """The protocol ``args`` names, its metrics changed by ``--critical`` and ``--count``.

    ``--critical ha3d`` is HA3D's whole metric rule
    (:meth:`~havln_mj.tasks.metrics.config.MetricConfig.ha3d`: people
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


def _legged_options(args: argparse.Namespace) -> object | None:
    """The GO1's options from the flags; None for the point body."""
    if args.body != "go1":
        return None
    from havln_mj.sim.legged import LeggedOptions  # the GO1's physics, only when used

    return LeggedOptions(controller=getattr(args, "go1_controller", "trot"))


def evaluation_simulator(args: argparse.Namespace, film_width: int | None = None) -> Simulator:
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
        legged=_legged_options(args),
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


def banner(args: argparse.Namespace, split: str, episodes: Sequence[Episode], people: dict) -> str:
    """What is evaluated, by what rules, with whom (printed before the first instruction)."""
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


def blank_instructions(episodes: Sequence[Episode]) -> list[str]:
    """The ids of blank instructions (HA-R2R val_seen has 13): evaluated, and reported."""
    return [
        f"{e.path_id}_{k}" for e in episodes for k, t in enumerate(e.instructions) if not t.strip()
    ]
