"""``eval --record N``: a video and a top-down map of evaluated instructions.

Each recorded instruction is run again in a rendering simulator with the evaluation's
protocol, people, seed, agent and (on HA3D's clock) frame counter, filming the agent's camera
through the frame pipeline. The video marks every action that collided (red border and
text); the map (:func:`havln_mj.render.topdown.draw_topdown`) shows the reference path, the
track walked, the people's tracks and where collisions were counted. ``<instr_id>.json``
beside them says whether the rerun matched the evaluated trajectory step for step (a
rendering simulator walks the same graph, so it does unless the agent draws from another
source than its generator).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from havln_mj.cache import atomic_write_json
from havln_mj.eval.setup import EXPERTS, evaluation_simulator, make_agent, protocol_of
from havln_mj.render.video import SizedOnFirstFrame
from havln_mj.sim.simulator import Simulator
from havln_mj.tasks.episodes import Episode
from havln_mj.tasks.experts import run_expert

FPS = 8.0  # video frames per simulated second
WIDTH = 320  # video width in pixels (the height keeps the evaluation camera's aspect)
MAP_MARGIN = 4.0  # metres of the level shown around the reference path and the walk


class _Film:
    """The frames of one instruction, kept until its collisions are known."""

    def __init__(self, sim: Simulator) -> None:
        self.sim = sim
        self.frames: list[tuple[float, np.ndarray, np.ndarray, np.ndarray]] = []

    def __call__(self, i: int, t: float, views: list, pose: np.ndarray) -> None:
        if self.sim.human_clock.kind == "ha3d":  # people hold the state's pose
            people = self.sim.getHumanPositions()[0]
        else:
            people = self.sim.people(i).positions(np.array([t]))[0]
        self.frames.append((t, views[0].rgb.copy(), np.asarray(pose, float), people))


def _label(rgb: np.ndarray, text: str, collided: bool) -> np.ndarray:
    import cv2

    out = rgb.copy()
    if collided:
        cv2.rectangle(out, (0, 0), (out.shape[1] - 1, out.shape[0] - 1), (230, 30, 30), 6)
    cv2.putText(out, text, (8, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 255), 1)
    return out


def record_episodes(
    args: argparse.Namespace,
    episodes: Sequence[Episode],
    records: Sequence[dict],
    folder: Path,
) -> list[dict]:
    """Films the instructions of ``records`` (evaluated records of ``episodes``) into ``folder``.

    Returns:
        One report per instruction (also written as ``<instr_id>.json``).
    """
    from havln_mj.render.topdown import draw_topdown  # matplotlib: only when recording

    by_path = {e.path_id: e for e in episodes}
    protocol = protocol_of(args)
    make = make_agent(args.agent, args)
    cap = protocol.expert_max_steps if args.agent in EXPERTS else None
    sim = evaluation_simulator(args, film_width=WIDTH)
    reports = []
    try:
        for record in records:
            path_id, _, k = record["instr_id"].rpartition("_")
            episode = by_path[int(path_id)]
            sim.set_rules(frame=record["frames"][0])
            film = _Film(sim)
            sim.set_film(FPS, film)
            trajectory = run_expert(
                sim,
                episode,
                make(np.random.default_rng([args.seed, record["index"]])),
                instruction=int(k),
                max_steps=cap,
                protocol=protocol,
            )
            sim.set_film(None)
            report = _write(folder, record, episode, trajectory, film, sim, draw_topdown)
            report["matches_evaluation"] = _same(trajectory.records, record["steps"])
            atomic_write_json(folder / f"{record['instr_id']}.json", report, indent=1)
            print(f"recorded {record['instr_id']}: {report['video']}", flush=True)
            reports.append(report)
    finally:
        sim.close()
    return reports


def _same(rerun: Sequence, evaluated: Sequence[list]) -> bool:
    """Whether the rerun's states are the evaluated ones (viewpoint, heading, collision)."""
    return len(rerun) == len(evaluated) and all(
        r.viewpoint == vp and r.is_crushed == hit and math.isclose(r.heading, h)
        for r, (vp, h, _, hit) in zip(rerun, evaluated, strict=True)
    )


def _write(folder, record, episode, trajectory, film, sim, draw_topdown) -> dict:
    """Writes the video and the map of one filmed instruction; returns its report."""
    instr_id = record["instr_id"]
    ends = [r.time for r in trajectory.records]  # each state's time, the start first
    hit = [bool(r.is_crushed) for r in trajectory.records]
    video = folder / f"{instr_id}.mp4"
    writer = SizedOnFirstFrame(video, FPS)
    collisions, track = [], []
    try:
        for t, rgb, pose, _ in film.frames:
            # The state (action) a frame belongs to: the first whose time is not before it.
            s = min(int(np.searchsorted(ends, t - 1e-9)), len(ends) - 1)
            what = "start" if s == 0 else f"step {s}"
            text = f"{instr_id}  {what}  t={t:5.1f}s" + ("  COLLISION" if hit[s] else "")
            writer.write(_label(rgb, text, hit[s]))
            track.append(pose[:3])
            if hit[s] and abs(t - ends[s]) < 1e-6:
                collisions.append(pose[:3])
    finally:
        writer.close()
    scan = sim.scan(episode.scan)
    walked = np.array(track).reshape(-1, 3)
    points = np.vstack([walked, [scan.graph.position(v) for v in episode.path]])
    lo, hi = points[:, :2].min(axis=0) - MAP_MARGIN, points[:, :2].max(axis=0) + MAP_MARGIN
    graph, regions, mesh = _crop(scan, lo, hi)
    people = np.array([f[3] for f in film.frames]).reshape(len(film.frames), -1, 3)
    shown = ((people[..., :2] >= lo) & (people[..., :2] <= hi)).all(axis=-1).any(axis=0)
    people = people[:, shown]
    draw_topdown(
        folder / f"{instr_id}_map.png",
        graph,
        regions,
        mesh,
        [episode.path],
        level_floor=graph.floor_z(episode.start),
        title=f"{instr_id} in {scan.description}",
        people=people[0] if len(people) and people.shape[1] else None,
        walked=[walked],
        people_tracks=people if len(people) and people.shape[1] else None,
        collisions=np.array(collisions).reshape(-1, 3),
    )
    return {
        "instr_id": instr_id,
        "video": str(video),
        "map": str(folder / f"{instr_id}_map.png"),
        "frames": len(film.frames),
        "steps": len(trajectory.records) - 1,
        "collided_steps": int(sum(hit)),
        "final_viewpoint": trajectory.final_viewpoint,
        "goal": episode.goal,
        "stopped": trajectory.stopped,
    }


def _crop(scan, lo: np.ndarray, hi: np.ndarray) -> tuple:
    """The scan's graph, regions and mesh inside the box ``lo``–``hi`` (x, y), for the map."""
    from dataclasses import replace

    from havln_mj.scene.navgraph import NavGraph
    from havln_mj.scene.regions import Regions

    c = scan.graph.connectivity
    xy = c.positions[:, :2]
    inside = ((xy >= lo) & (xy <= hi)).all(axis=1)
    graph = NavGraph(replace(c, included=c.included & inside))
    regions = scan.regions
    if regions is not None:

        def meets(bbox: np.ndarray) -> bool:
            return bool((bbox[:2] <= hi).all() and (bbox[3:5] >= lo).all())

        regions = Regions(
            regions.levels,
            tuple(
                replace(r, polygon=np.clip(r.polygon, lo, hi))
                for r in regions.regions
                if meets(r.bbox)
            ),
            tuple(o for o in regions.objects if meets(o.bbox)),
        )
    mesh = scan.mesh
    for axis, bound, sign in ((0, lo, 1.0), (0, hi, -1.0), (1, lo, 1.0), (1, hi, -1.0)):
        if mesh is None or mesh.is_empty:
            break
        normal = np.zeros(3)
        normal[axis] = sign
        origin = np.zeros(3)
        origin[axis] = bound[axis]
        mesh = mesh.slice_plane(origin, normal)
    return graph, regions, mesh
