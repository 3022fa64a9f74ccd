"""The GO1 on stairs and ramps: test courses, and the stair edges of real buildings' proxies.

* **Courses** (``havln_mj.robot.go1.courses``): straight stairs of 12 risers (0.15, 0.17,
  0.19 m) on 0.28 m treads, and ramps of 10, 20 and 30° over a 2.5 m run, 1 m wide, each
  walked up and down from 1 m before the flight to 1 m past it (random start offset ±0.1 m
  across and heading ±0.1 rad) as the simulator's graph actions walk: a ``turn`` to face the
  target, then one ``forward`` primitive of the distance to it. A walk succeeds when the
  robot has not fallen and stands on the far landing within 0.3 m of the target. Reports
  success, falls, time-outs, time and the farthest it got (fraction of the flight's
  height). ``--courses stairs`` or ``ramp`` walks one kind only.
* **Floor seams**: ``--floor-primitives`` primitives (forward 0.5 m or turn ±45°) on a flat
  plane and on a flat floor tiled with 10 cm strips of coplanar boxes (the narrowest floor
  boxes the graph proxies draw), meeting face to face ("strips") or each reaching
  ``SEAM_OVERLAP`` over the next as the proxies' boxes do ("overlapping strips"). Reports falls
  and foot side pushes: the 20 Hz ticks on which a foot contact pushes more than 30 N within 60° of
  horizontal (a box's side face, reached by a foot sunk into the floor), and their share.
* **Proxy stairs**: the stair edges (floors more than 0.3 m apart) on the HA-R2R val_seen
  paths, in the graph proxies of their buildings, each walked both ways with
  ``LeggedAgent.go_to`` (through the edge's route when it has one). An edge counts when the
  robot ends within 0.3 m of the viewpoint's floor point, on its floor, without falling.

Prints one JSON object. Run:
``python benchmarks/bench_go1_terrain.py [--walks 100] [--parts courses,seams,proxy]
[--controller crawl] [--risers 12] [--proxy-edges N] [--floor-primitives 1000]``. The crawl
and the hybrid walk the stair courses down backwards (facing up the stair, ``forward`` of
minus the distance).
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import os
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco
import numpy as np
from common import machine

from havln_mj.frames import heading_to, wrap_angle
from havln_mj.robot.go1 import Go1Body, Go1Gains, add_go1, load_gains
from havln_mj.robot.go1.constants import CONTROLLERS
from havln_mj.robot.go1.courses import START_X, add_box, ramp_spec, stairs_spec
from havln_mj.robot.go1.learned import LearnedPolicy, load_policy
from havln_mj.robot.go1.model import flat_floor_spec
from havln_mj.scene.proxy.seams import SEAM_OVERLAP

STAIRS = (0.15, 0.17, 0.19)
RAMPS = (10.0, 20.0, 30.0)
REACHED = 0.3  # metres from the target that count as arrived


def _course(
    kind: str,
    size: float,
    down: bool,
    walks: int,
    seed: int,
    controller: str,
    gains: Go1Gains,
    policy: LearnedPolicy | None,
    risers: int = 12,
) -> dict:
    spec, course = stairs_spec(riser=size, risers=risers) if kind == "stairs" else ramp_spec(size)
    add_go1(spec)
    model = spec.compile()
    data = mujoco.MjData(model)
    robot = Go1Body(model, data, gains=gains, controller=controller, policy=policy)
    rng = np.random.default_rng(seed)
    start_x, goal_x = (course.top_x, START_X) if down else (START_X, course.top_x)
    goal = (goal_x, 0.0)
    start_z, goal_z = (course.rise, 0.0) if down else (0.0, course.rise)
    # The crawl descends backwards, facing up the stair (its knees would strike the noses).
    backwards = down and controller in ("crawl", "hybrid")
    heading = -math.pi / 2 if down and not backwards else math.pi / 2
    ok = falls = timeouts = 0
    seconds, progress = [], []
    steps, wall = 0, 0.0
    for _ in range(walks):
        robot.reset(
            start_x, float(rng.uniform(-0.1, 0.1)), start_z, heading + rng.uniform(-0.1, 0.1)
        )
        best = [0.0]

        def track(_t: float, best=best) -> None:
            p = robot.true_pose()
            climbed = (p.z - const_stand(start_z)) / (goal_z - start_z)
            best[0] = max(best[0], climbed)

        t = time.perf_counter()
        p = robot.true_pose()
        bearing = heading_to((p.x, p.y), goal) + (math.pi if backwards else 0.0)
        aim = robot.turn(wrap_angle(bearing - p.heading), on_tick=track)
        p = robot.true_pose()
        distance = math.hypot(goal[0] - p.x, goal[1] - p.y)
        res = robot.forward(-distance if backwards else distance, on_tick=track)
        wall += time.perf_counter() - t
        steps += aim.steps + res.steps
        p = robot.true_pose()
        arrived = abs(p.x - goal_x) < REACHED and abs(p.y) < course.width / 2
        arrived = arrived and abs(p.z - const_stand(goal_z)) < 0.15
        ok += arrived and not res.fell
        falls += res.fell
        timeouts += res.timed_out and not res.fell
        seconds.append(aim.duration + res.duration)
        progress.append(min(1.0, best[0]))
    unit = "m" if kind == "stairs" else "deg"
    return {
        "course": f"{kind} {size:g} {unit} {'down' if down else 'up'}"
        + (f", {risers} risers" if kind == "stairs" else "")
        + (", backwards" if backwards else ""),
        "walks": walks,
        "success": round(ok / walks, 3),
        "falls": round(falls / walks, 3),
        "timeouts": round(timeouts / walks, 3),
        "mean_progress": round(float(np.mean(progress)), 3),
        "mean_seconds": round(float(np.mean(seconds)), 1),
        "real_time_factor": round(steps * model.opt.timestep / max(wall, 1e-9), 1),
    }


def _floor_seams(kind: str, primitives: int, seed: int, controller: str, gains, policy) -> dict:
    """Random primitives on a plane (``kind`` "plane") or on coplanar 10 cm box strips."""
    spec = flat_floor_spec()
    top = 0.0
    if kind != "plane":
        top = 0.1
        lap = SEAM_OVERLAP if kind == "overlapping strips" else 0.0
        for k in range(-50, 50):  # 10 m of strips along y, their tops at z = top
            add_box(spec, f"strip{k}", 0.1 * k, 0.1 * (k + 1) + lap, 10.0, top)
    add_go1(spec)
    model = spec.compile()
    data = mujoco.MjData(model)
    robot = Go1Body(model, data, gains=gains, controller=controller, policy=policy)
    feet = set(robot.foot_ids)
    pushes = [0]
    ticks = [0]

    def tick(_t: float) -> None:
        ticks[0] += 1
        for k in range(data.ncon):
            c = data.contact[k]
            on_foot = (c.geom1 in feet or c.geom2 in feet) and c.efc_address >= 0
            if on_foot and abs(c.frame[2]) < 0.5 and data.efc_force[c.efc_address] > 30.0:
                pushes[0] += 1
                return

    rng = np.random.default_rng(seed)
    robot.reset(0.0, 0.0, top, 0.0)
    falls = 0
    t = time.perf_counter()
    for _ in range(primitives):
        p = robot.true_pose()
        if math.hypot(p.x, p.y) > 3.0:  # back to the middle of the floor
            robot.reset(0.0, 0.0, top, float(rng.uniform(0, 2 * math.pi)))
        if rng.random() < 0.5:
            res = robot.forward(0.5, on_tick=tick)
        else:
            res = robot.turn(float(rng.choice((-1.0, 1.0))) * math.pi / 4, on_tick=tick)
        if res.fell:
            falls += 1
            robot.reset(0.0, 0.0, top, float(rng.uniform(0, 2 * math.pi)))
    return {
        "floor": kind,
        "primitives": primitives,
        "falls": falls,
        "foot_side_push_ticks": pushes[0],
        "foot_side_push_share": round(pushes[0] / max(ticks[0], 1), 4),
        "wall_seconds": round(time.perf_counter() - t, 1),
    }


def const_stand(floor: float) -> float:
    """Trunk height standing on a floor."""
    return floor + 0.27


def _proxy_stairs(
    data: Path, edges: int, seed: int, controller: str, policy: LearnedPolicy | None
) -> dict:
    """Stair edges on HA-R2R val_seen paths, walked both ways in the graph proxies."""
    from havln_mj.scene.scan import load_scan
    from havln_mj.sim.crowd import NO_CROWD
    from havln_mj.sim.legged import PREFIX, LeggedAgent, LeggedOptions, LeggedWorld
    from havln_mj.sim.world import WorldOptions

    episodes = data / "ha_r2r" / "HA_val_seen.json"
    conn = data / "mp3d_connectivity"
    if not episodes.is_file() or not conn.is_dir():
        return {"skipped": f"needs {episodes} and {conn}"}
    by_scan: dict[str, set] = {}
    for ep in json.loads(episodes.read_text()):
        for a, b in itertools.pairwise(ep["path"]):
            by_scan.setdefault(ep["scan"], set()).add(tuple(sorted((a, b))))
    rng = np.random.default_rng(seed)
    scans = {sid: load_scan(sid, connectivity_dir=conn) for sid in sorted(by_scan)}
    todo = [
        (sid, e)
        for sid, scan in scans.items()
        for e in sorted(by_scan[sid])
        if abs(scan.graph.floor_z(e[0]) - scan.graph.floor_z(e[1])) > 0.3
    ]
    n_edges = len(todo)
    if edges and len(todo) > edges:
        todo = [todo[k] for k in sorted(rng.permutation(len(todo))[:edges])]
    rows = []
    for sid in sorted({sid for sid, _ in todo}):
        scan = scans[sid]
        g = scan.graph
        world = LeggedWorld(scan, WorldOptions(collision="boxes"), NO_CROWD, LeggedOptions())
        agent = LeggedAgent(world)
        agent.body = Go1Body(world.model, agent.data, PREFIX, controller=controller, policy=policy)
        for a, b in (e for s, e in todo if s == sid):
            for src, dst in ((a, b), (b, a)):
                heading = float(rng.uniform(0, 2 * math.pi))
                agent.place(g.position(src), g.floor_z(src), heading, 0.0)
                target = np.append(g.position(dst)[:2], g.floor_z(dst))
                out = agent.go_to(target, None, 0.0)
                end = agent.position()
                gap = float(np.hypot(*(end[:2] - target[:2])))
                on_floor = abs(end[2] - const_stand(target[2])) < 0.2
                rows.append(
                    {
                        "scan": sid,
                        "rise_m": round(float(target[2] - g.floor_z(src)), 2),
                        "routed": scan.route(src, dst) is not None,
                        "walked": bool(gap < REACHED and on_floor and not out.fell),
                        "fell": out.fell,
                        "end_error_m": round(gap, 3),
                        "seconds": round(out.duration, 1),
                    }
                )
    n = max(len(rows), 1)
    return {
        "stair_edges_on_paths": n_edges,
        "stair_edge_walks": len(rows),
        "walked": round(sum(r["walked"] for r in rows) / n, 3),
        "falls": round(sum(r["fell"] for r in rows) / n, 3),
        "up_walked": round(_share([r for r in rows if r["rise_m"] > 0]), 3),
        "down_walked": round(_share([r for r in rows if r["rise_m"] < 0]), 3),
        "mean_seconds": round(float(np.mean([r["seconds"] for r in rows])), 1) if rows else None,
        "rows": rows,
    }


def _share(rows: list[dict]) -> float:
    return sum(r["walked"] for r in rows) / max(len(rows), 1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--walks", type=int, default=100, help="walks per course")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--parts", default="courses,seams,proxy")
    parser.add_argument("--courses", default="stairs,ramp", help="course kinds to walk")
    parser.add_argument("--floor-primitives", type=int, default=1000)
    parser.add_argument("--controller", default="terrain", choices=CONTROLLERS)
    parser.add_argument("--risers", type=int, default=12, help="risers of the stair courses")
    parser.add_argument("--proxy-edges", type=int, default=0, help="0: every stair edge")
    parser.add_argument("--gains", type=Path, default=None, help="gains.json to use")
    parser.add_argument(
        "--policy", type=Path, default=None, help="policy .npz of the learned controller"
    )
    parser.add_argument(
        "--data",
        type=Path,
        default=Path(
            os.environ.get(
                "HAVLN_SHARED_DATA", Path(__file__).resolve().parents[2] / "shared" / "data"
            )
        ),
    )
    args = parser.parse_args()
    parts = set(args.parts.split(","))
    gains = load_gains(args.gains)
    policy = load_policy(args.policy) if args.controller == "learned" else None
    out: dict = {"machine": machine(), "controller": args.controller, "gains": str(args.gains)}
    if policy is not None:
        out["policy"] = str(args.policy or "shipped")
    t = time.perf_counter()
    if "courses" in parts:
        kinds = set(args.courses.split(","))
        if not kinds <= {"stairs", "ramp"}:
            parser.error(f"--courses {args.courses!r}: valid kinds are stairs and ramp")
        cells = [("stairs", r) for r in STAIRS if "stairs" in kinds]
        cells += [("ramp", a) for a in RAMPS if "ramp" in kinds]
        out["courses"] = [
            _course(
                kind,
                size,
                down,
                args.walks,
                args.seed + k,
                args.controller,
                gains,
                policy,
                args.risers,
            )
            for k, (kind, size) in enumerate(cells)
            for down in (False, True)
        ]
    if "seams" in parts:
        out["floor_seams"] = [
            _floor_seams(kind, args.floor_primitives, args.seed, args.controller, gains, policy)
            for kind in ("plane", "strips", "overlapping strips")
        ]
    if "proxy" in parts:
        out["proxy_stairs_val_seen"] = _proxy_stairs(
            args.data, args.proxy_edges, args.seed, args.controller, policy
        )
    out["wall_seconds"] = round(time.perf_counter() - t, 1)
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
