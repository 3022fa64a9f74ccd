"""GO1 navigation primitives: accuracy, falls, odometry drift and speed.

* **Flat floor, ground truth**: ``--primitives`` primitives (forward 0.5 m or turn ±45°, drawn
  at random), episodes of 10 from a random start heading (and after any fall), undisturbed
  and again with 40 N × 0.1 s side pushes (``xfrc_applied`` on the trunk, random side, at a
  random time in the first 1.2 s of the primitive). Errors: distance and heading error
  (mean, p95), lateral drift, duration (physics s), falls, time-outs.
* **Odometry**: the same primitives closed on gyro + leg odometry; reports the true errors and
  the estimate's drift per primitive and over each 10-primitive episode.
* **Speed**: controller time per 2 ms physics step (primitive wall time minus bare
  ``mj_step`` time for the same steps), and the real-time factor of the robot walking in the
  procedural house ``proc-0`` (collision boxes) with 4 mocap capsule "people" moved every tick.
* **Cruise**: walking speed over the middle 1.5 m of 3 m forward primitives.
* **Graph walks**: what a graph action asks of the robot on a flat floor: episodes of 4 turns
  to a bearing drawn in (−π, π] each followed by a walk of 0.5–4.5 m, from a random start
  heading. Falls (turns and walks), distance error, mean speed of a walk. ``--forward-accel``
  changes how fast a walk may speed up (``Go1Gains.forward_accel``; 1e9: at once).
* **Stairs**: climbing edges of a real building's graph proxy (``--stairs-scan``), walked both
  ways; with ``--stairs-flights`` the edges walked along a flight drawn for them.

``--controller`` picks the gait (``trot``, ``terrain`` or ``learned``, see ``Go1Body``) for
every part and ``--v-max`` the primitives' cruise cap. Stairs and ramp courses:
``bench_go1_terrain.py``.

Prints one JSON object. Run: ``python benchmarks/bench_go1.py [--primitives N]``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco
import numpy as np
from common import machine

from havln_mj.robot.go1 import Go1Body, Go1Gains, add_go1, flat_floor_spec, load_gains

EPISODE = 10
TURN = math.pi / 4
PUSH_N, PUSH_S = 40.0, 0.1


def _stats(values: list[float], scale: float = 1.0, digits: int = 4) -> dict:
    if not values:
        return {"n": 0}
    a = np.abs(np.asarray(values)) * scale
    return {
        "n": len(a),
        "mean": round(float(a.mean()), digits),
        "p95": round(float(np.percentile(a, 95)), digits),
        "max": round(float(a.max()), digits),
    }


CONTROLLER = ["trot"]  # the controller every part drives (--controller)
GAINS: list[Go1Gains] = []  # the gains every part uses (--v-max changes the cruise cap)


def _flat_robot(estimate: str) -> tuple[mujoco.MjModel, mujoco.MjData, Go1Body]:
    spec = flat_floor_spec()
    add_go1(spec)
    model = spec.compile()
    data = mujoco.MjData(model)
    robot = Go1Body(model, data, estimate=estimate, gains=GAINS[0], controller=CONTROLLER[0])
    return model, data, robot


def _cruise(walks: int, seed: int) -> dict:
    """Walking speed over the middle 1.5 m of 3 m forward primitives on a flat floor."""
    _, _, robot = _flat_robot("truth")
    rng = np.random.default_rng(seed)
    speeds, errors = [], []
    for _ in range(walks):
        robot.reset(0.0, 0.0, 0.0, float(rng.uniform(0, 2 * math.pi)), settle=0.3)
        p0 = robot.true_pose()
        track: list[tuple[float, float]] = []

        def tick(t: float, p0=p0, track=track) -> None:
            p = robot.true_pose()
            track.append((t, math.hypot(p.x - p0.x, p.y - p0.y)))

        res = robot.forward(3.0, on_tick=tick)
        tr = np.array(track)
        mid = (tr[:, 1] > 0.75) & (tr[:, 1] < 2.25)
        if not res.fell and mid.sum() > 3:
            speeds.append(float(np.polyfit(tr[mid, 0], tr[mid, 1], 1)[0]))
            errors.append(res.error)
    return {
        "walks": walks,
        "cruise_m_per_s": _stats(speeds, digits=3),
        "distance_error_3m_m": _stats(errors),
        "forward_v_max": GAINS[0].forward_v_max,
    }


def _graph_walks(episodes: int, seed: int) -> dict:
    """Turns to random bearings and walks of 0.5–4.5 m on a flat floor, 4 of each per episode."""
    _, _, robot = _flat_robot("truth")
    rng = np.random.default_rng(seed)
    falls = {"forward": 0, "turn": 0}
    errors, speeds, walks = [], [], 0
    for _ in range(episodes):
        robot.reset(0.0, 0.0, 0.0, float(rng.uniform(0, 2 * math.pi)), settle=0.5)
        for _ in range(4):
            turn = robot.turn(float(rng.uniform(-math.pi, math.pi)))
            if turn.fell:
                falls["turn"] += 1
                break
            distance = float(rng.uniform(0.5, 4.5))
            walk = robot.forward(distance)
            walks += 1
            if walk.fell:
                falls["forward"] += 1
                break
            errors.append(walk.error)
            speeds.append(walk.distance / walk.duration)
    return {
        "episodes": episodes,
        "walks": walks,
        "falls": falls,
        "walks_per_fall": round(walks / max(1, sum(falls.values())), 1),
        "distance_error_m": _stats(errors),
        "mean_speed_m_per_s": _stats(speeds, digits=3),
        "forward_accel": GAINS[0].forward_accel,
    }


def _run_flat(n: int, estimate: str, push: bool, seed: int) -> dict:
    model, data, robot = _flat_robot(estimate)
    rng = np.random.default_rng(seed)
    fwd: dict[str, list[float]] = {k: [] for k in ("err", "lat", "dh", "dur", "est_err")}
    trn: dict[str, list[float]] = {k: [] for k in ("err", "drift", "dur", "est_err")}
    episode_drift: list[float] = []
    episode_yaw: list[float] = []
    falls = {"forward": 0, "turn": 0}
    timeouts = 0
    steps = 0
    wall = 0.0
    pushes = 0
    for i in range(n):
        if i % EPISODE == 0 or robot.fallen:
            if i and not robot.fallen and estimate == "odometry":
                est, true = robot.pose(), robot.true_pose()
                episode_drift.append(math.hypot(est.x - true.x, est.y - true.y))
                episode_yaw.append(
                    math.degrees(abs(math.remainder(est.yaw - true.yaw, 2 * math.pi)))
                )
            robot.reset(0.0, 0.0, 0.0, float(rng.uniform(0, 2 * math.pi)), settle=0.5)
        kind = "forward" if rng.random() < 0.5 else "turn"
        theta = TURN if rng.random() < 0.5 else -TURN
        on_tick = None
        if push:
            t_push = data.time + float(rng.uniform(0.05, 1.2))
            side = 1.0 if rng.random() < 0.5 else -1.0
            state = {"on": False, "done": False}

            def on_tick(t: float, t_push=t_push, side=side, state=state) -> None:
                if not state["done"] and not state["on"] and t >= t_push - 1e-9:
                    yaw = robot.true_pose().yaw
                    force = PUSH_N * side * np.array([-math.sin(yaw), math.cos(yaw), 0.0])
                    data.xfrc_applied[robot.trunk_id, :3] = force
                    state["on"], state["t"] = True, t
                elif state["on"] and t >= state["t"] + PUSH_S - 1e-9:
                    data.xfrc_applied[robot.trunk_id, :3] = 0.0
                    state["on"], state["done"] = False, True

        t = time.perf_counter()
        res = (
            robot.forward(0.5, on_tick=on_tick)
            if kind == "forward"
            else robot.turn(theta, on_tick=on_tick)
        )
        wall += time.perf_counter() - t
        data.xfrc_applied[:] = 0.0
        if push and state["done"]:
            pushes += 1
        steps += res.steps
        timeouts += res.timed_out
        if res.fell:
            falls[kind] += 1
            continue
        if kind == "forward":
            fwd["err"].append(res.error)
            fwd["lat"].append(res.lateral)
            fwd["dh"].append(res.heading_change)
            fwd["dur"].append(res.duration)
            fwd["est_err"].append(res.est_distance - res.distance)
        else:
            trn["err"].append(res.error)
            trn["drift"].append(math.hypot(res.distance, res.lateral))
            trn["dur"].append(res.duration)
            trn["est_err"].append(res.est_heading_change - res.heading_change)
    out = {
        "primitives": n,
        "forward_0.5m": {
            "distance_error_m": _stats(fwd["err"]),
            "signed_mean_error_m": round(float(np.mean(fwd["err"])), 4) if fwd["err"] else None,
            "lateral_m": _stats(fwd["lat"]),
            "heading_change_deg": _stats(fwd["dh"], 180 / math.pi, 2),
            "duration_s": _stats(fwd["dur"], digits=2),
        },
        "turn_45deg": {
            "heading_error_deg": _stats(trn["err"], 180 / math.pi, 2),
            "signed_mean_error_deg": round(math.degrees(float(np.mean(trn["err"]))), 2)
            if trn["err"]
            else None,
            "drift_m": _stats(trn["drift"]),
            "duration_s": _stats(trn["dur"], digits=2),
        },
        "falls": falls,
        "fall_rate": round((falls["forward"] + falls["turn"]) / n, 4),
        "timeouts": timeouts,
        "physics_steps": steps,
        "real_time_factor": round(steps * model.opt.timestep / wall, 1),
    }
    if push:
        out["pushes_applied"] = pushes
    if estimate == "odometry":
        out["odometry_error_per_primitive"] = {
            "forward_distance_m": _stats(fwd["est_err"]),
            "turn_heading_deg": _stats(trn["est_err"], 180 / math.pi, 2),
        }
        out["odometry_drift_per_10_primitives"] = {
            "position_m": _stats(episode_drift),
            "yaw_deg": _stats(episode_yaw, digits=2),
        }
    return out


def _controller_time(seed: int) -> dict:
    """Wall time per physics step of the whole primitive loop vs bare mj_step."""
    model, data, robot = _flat_robot("truth")
    rng = np.random.default_rng(seed)
    robot.reset(0.0, 0.0, 0.0, 0.0, settle=0.2)
    steps, t = 0, time.perf_counter()
    for k in range(20):
        res = robot.forward(0.5) if k % 2 == 0 else robot.turn(float(rng.choice([TURN, -TURN])))
        steps += res.steps
    total = (time.perf_counter() - t) / steps
    robot.reset(0.0, 0.0, 0.0, 0.0, settle=0.2)
    robot.gait.start()
    t = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(model, data)
    physics = (time.perf_counter() - t) / steps
    return {
        "total_us_per_step": round(total * 1e6, 1),
        "mj_step_us": round(physics * 1e6, 1),
        "controller_us_per_step": round((total - physics) * 1e6, 1),
    }


def _house(seconds: float, seed: int, physical: bool) -> dict:
    """The GO1 walking random graph edges of proc-0 among 4 of its people.

    As the simulator runs it: people posed every controller tick when solid, the 1 m
    collision signal computed for every action.
    """
    from havln_mj.humans.population import populate
    from havln_mj.scene.scan import load_scan
    from havln_mj.sim.legged import LeggedAgent, LeggedOptions, LeggedWorld
    from havln_mj.sim.world import WorldOptions

    scan = load_scan("proc-0")
    g = scan.graph
    rng = np.random.default_rng(seed)
    crowd = populate(scan, rng, count=4)
    world = LeggedWorld(
        scan, WorldOptions(collision="boxes"), crowd, LeggedOptions(physical_humans=physical)
    )
    agent = LeggedAgent(world)
    agent.body = Go1Body(world.model, agent.data, "go1/", gains=GAINS[0], controller=CONTROLLER[0])
    vp = g.nodes[int(rng.integers(g.num_nodes))]
    agent.place(g.position(vp), g.floor_z(vp), float(rng.uniform(0, 2 * math.pi)), 0.0)
    clock, wall, actions, falls, hits = 0.0, time.perf_counter(), 0, 0, 0
    while clock < seconds:
        nxt = g.neighbors(vp)
        nxt = [n for n in nxt if abs(g.floor_z(n) - g.floor_z(vp)) < 0.3] or [vp]
        vp = nxt[int(rng.integers(len(nxt)))]
        target = np.append(g.position(vp)[:2], g.floor_z(vp))
        out = agent.go_to(target, None, clock)
        clock += out.duration
        actions += 1
        hits += bool(out.contact and out.contact.crushed)
        if out.fell:
            falls += 1
            agent.place(g.position(vp), g.floor_z(vp), 0.0, clock)
    wall = time.perf_counter() - wall
    return {
        "scene": "proc-0",
        "people": len(crowd),
        "solid_people": physical,
        "graph_actions": actions,
        "physics_seconds": round(clock, 1),
        "falls": falls,
        "actions_within_1m_of_a_person": hits,
        "real_time_factor": round(clock / wall, 1),
    }


def _stairs(data: Path, scan_id: str, edges: int, seed: int, flights: bool = False) -> dict:
    """The GO1 walking the climbing edges (|Δfloor| > 0.3 m) of a real building's graph proxy.

    With ``flights``, the edges walked along a flight drawn for them instead. Each row says
    how the scan serves the edge (its stored routes): ``straight``, ``by route`` (walked
    through the route's viewpoints), ``by flight``, or ``mesh`` in a real mesh.
    """
    from havln_mj.scene.scan import load_scan
    from havln_mj.sim.crowd import NO_CROWD
    from havln_mj.sim.legged import LeggedAgent, LeggedOptions, LeggedWorld
    from havln_mj.sim.world import WorldOptions

    conn = data / "mp3d_connectivity"
    if not conn.is_dir():
        return {"skipped": f"no connectivity graphs at {conn}"}
    scan = load_scan(scan_id, connectivity_dir=conn)
    g = scan.graph
    climbs = [(a, b) for a, b, _ in g.edges() if abs(g.floor_z(a) - g.floor_z(b)) > 0.3]
    flown = {e for e, via in scan.routes.items() if not all(isinstance(s, str) for s in via)}
    if flights:
        climbs = sorted(flown)
    rng = np.random.default_rng(seed)
    picks = [climbs[int(k)] for k in rng.permutation(len(climbs))[:edges]]
    world = LeggedWorld(scan, WorldOptions(collision="boxes"), NO_CROWD, LeggedOptions())
    agent = LeggedAgent(world)
    agent.body = Go1Body(world.model, agent.data, "go1/", gains=GAINS[0], controller=CONTROLLER[0])
    rows = []
    for a, b in picks:
        for src, dst in ((a, b), (b, a)):
            agent.place(g.position(src), g.floor_z(src), 0.0, 0.0)
            target = np.append(g.position(dst)[:2], g.floor_z(dst))
            out = agent.go_to(target, None, 0.0)
            end = agent.position()
            drawn = "mesh"
            if (a, b) in flown:
                drawn = "by flight"
            elif scan.route(a, b) is not None:
                drawn = "by route"
            elif scan.kind == "graph proxy":
                drawn = "straight"
            rows.append(
                {
                    "proxy_edge": drawn,
                    "rise_m": round(g.floor_z(dst) - g.floor_z(src), 2),
                    "run_m": round(float(np.hypot(*(target[:2] - g.position(src)[:2]))), 2),
                    "end_error_m": round(float(np.hypot(*(end[:2] - target[:2]))), 3),
                    "fell": out.fell,
                    "seconds": round(out.duration, 1),
                }
            )
    reached = [r for r in rows if not r["fell"] and r["end_error_m"] < 0.3]
    return {
        "scene": scan_id,
        "kind": scan.kind,
        ("edges_by_flight" if flights else "climbing_edges_in_graph"): len(climbs),
        "walks": len(rows),
        "reached_within_0.3m": len(reached),
        "falls": sum(r["fell"] for r in rows),
        "rows": rows,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--primitives", type=int, default=1000)
    parser.add_argument("--odometry-primitives", type=int, default=None)
    parser.add_argument("--house-seconds", type=float, default=60.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--parts", default="flat,push,odometry,speed,cruise,graph,house,stairs")
    parser.add_argument("--graph-episodes", type=int, default=100)
    parser.add_argument("--controller", default="trot", choices=("trot", "terrain", "learned"))
    parser.add_argument("--v-max", type=float, default=None, help="forward cruise cap (m/s)")
    parser.add_argument(
        "--forward-accel", type=float, default=None, help="fastest a walk speeds up (m/s²)"
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
    parser.add_argument("--stairs-scan", default="17DRP5sb8fy")
    parser.add_argument("--stairs-edges", type=int, default=10)
    parser.add_argument(
        "--stairs-flights", action="store_true", help="walk the edges flown, not any climbing"
    )
    args = parser.parse_args()
    parts = set(args.parts.split(","))
    n_odo = args.odometry_primitives or max(10, args.primitives // 5)
    CONTROLLER[0] = args.controller
    gains = load_gains()
    if args.v_max:
        gains = gains.with_(forward_v_max=args.v_max)
    if args.forward_accel:
        gains = gains.with_(forward_accel=args.forward_accel)
    GAINS.append(gains)
    out: dict = {"machine": machine(), "controller": args.controller}
    t = time.perf_counter()
    if "flat" in parts:
        out["flat_truth"] = _run_flat(args.primitives, "truth", False, args.seed)
    if "push" in parts:
        out["flat_truth_pushed"] = _run_flat(args.primitives, "truth", True, args.seed + 1)
    if "odometry" in parts:
        out["flat_odometry"] = _run_flat(n_odo, "odometry", False, args.seed + 2)
    if "speed" in parts:
        out["controller_time"] = _controller_time(args.seed + 3)
    if "cruise" in parts:
        out["flat_cruise"] = _cruise(10, args.seed + 6)
    if "graph" in parts:
        out["flat_graph_walks"] = _graph_walks(args.graph_episodes, args.seed + 7)
    if "house" in parts:
        out["house_4_people"] = [
            _house(args.house_seconds, args.seed + 4, physical) for physical in (False, True)
        ]
    if "stairs" in parts:
        out["stairs_proxy"] = _stairs(
            args.data, args.stairs_scan, args.stairs_edges, args.seed + 5, args.stairs_flights
        )
    out["wall_seconds"] = round(time.perf_counter() - t, 1)
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
