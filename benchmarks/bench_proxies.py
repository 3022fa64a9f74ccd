"""Graph proxies of all real navigation graphs: build time, geometry, walkability, physics.

Prints one JSON object:

* a row per scan: build time, floor/stair/wall box counts, layers, and its edges walked
  straight, walked by a route (``by_flight`` of them along a flight drawn for the edge), and
  unwalkable (by cause; ``crossing`` marks edges whose straight corridor provably cannot
  coexist with a drawn edge's);
* stairs: the edges climbing more than ``stair_rise`` walked straight or along a flight, how
  many are cut into treads and risers (the rest stay ramps), the risers and treads their
  walks cross (``walk.stair_steps``);
* totals, with the unwalkable edges by cause and by proof: ``steep`` edges climb more than
  ``max_grade`` end to end (no straight walk exists whatever is drawn), ``crossing`` ones
  cannot be drawn straight beside another edge, the rest are faults of the drawing;
* physics in the proxy with the most boxes (or ``--physics-scans``), with MuJoCo's own
  timers: a GO1-sized free body (0.65 × 0.28 × 0.3 m, 12 kg, 2 ms steps, never asleep)
  standing, and the GO1 (``robots/go1``) standing and walking random flat edges.

Run: ``python benchmarks/bench_proxies.py [--data ../shared/data] [--scans ID ...]
[--physics-scans ID ...]``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

import mujoco
import numpy as np
from common import machine

_LEDGE = 0.08  # metres: a smaller rise is a ledge, not a stair's riser


def main() -> int:
    default = Path(
        os.environ.get("HAVLN_SHARED_DATA", Path(__file__).resolve().parents[2] / "shared" / "data")
    )
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", type=Path, default=default)
    ap.add_argument("--scans", nargs="*", default=None)
    ap.add_argument("--steps", type=int, default=5000)
    ap.add_argument("--walk-seconds", type=float, default=120.0)
    ap.add_argument(
        "--physics-scans", nargs="*", default=None, help="default: the proxy with most boxes"
    )
    args = ap.parse_args()
    conn = args.data / "mp3d_connectivity"
    if not conn.is_dir():
        print(
            f"connectivity graphs not found at {conn} (set HAVLN_SHARED_DATA or --data)",
            file=sys.stderr,
        )
        return 1

    from havln_mj.scene.navgraph import NavGraph
    from havln_mj.scene.proxy.build import ProxyParams, build_proxy
    from havln_mj.scene.proxy.routes import route_floor_points
    from havln_mj.scene.proxy.walk import edge_grade, stair_steps

    params = ProxyParams()
    scans = args.scans or (conn / "scans.txt").read_text().split()
    rows, largest = [], None
    stair_rows: list = []
    causes: Counter = Counter()
    for scan in scans:
        graph = NavGraph.from_file(conn / f"{scan}_connectivity.json")
        t = time.perf_counter()
        proxy = build_proxy(graph, params)
        seconds = time.perf_counter() - t
        mats = proxy.boxes.material
        unwalkable: Counter = Counter()
        for a, b in proxy.unwalkable:
            if edge_grade(graph, a, b) > params.max_grade:
                proof = "steep"
            elif (a, b) in proxy.crossing:
                proof = "crossing"
            else:
                proof = "drawing"
            unwalkable[f"{proof}:{proxy.faults[(a, b)]}"] += 1
        causes.update(unwalkable)
        # Stairs: edges climbing more than stair_rise, walked straight or along a flight.
        risers, treads, stairs, cut = [], [], 0, 0
        for a, b, _ in graph.edges():
            if abs(graph.floor_z(a) - graph.floor_z(b)) <= params.stair_rise:
                continue
            via = proxy.routes.get((a, b))
            if via is not None and all(isinstance(s, str) for s in via):
                continue  # walked through other viewpoints: their edges count
            if (a, b) in proxy.unwalkable:
                continue
            path = route_floor_points(graph, via or (a, b))
            r, _ = stair_steps(path, proxy.boxes, params)
            big, t = stair_steps(path, proxy.boxes, params, least=_LEDGE)
            stairs += 1
            cut += len(big) > 0
            risers += np.abs(r).tolist()
            treads += t.tolist()
        stair_rows.append((stairs, cut, risers, treads))
        rows.append(
            {
                "scan": scan,
                "viewpoints": graph.num_nodes,
                "edges": graph.num_edges,
                "build_s": round(seconds, 3),
                "boxes": len(proxy.boxes),
                "floor_boxes": mats.count("floor"),
                "stair_boxes": mats.count("stairs"),
                "wall_boxes": mats.count("wall"),
                "layers": len(proxy.free),
                "straight": graph.num_edges - len(proxy.faults),
                "by_route": len(proxy.routes),
                "by_flight": len(proxy.flights),
                "unwalkable_edges": len(proxy.unwalkable),
                "unwalkable_by_cause": dict(sorted(unwalkable.items())),
            }
        )
        if largest is None or len(proxy.boxes) > largest[1]:
            largest = (scan, len(proxy.boxes))
    total_edges = sum(r["edges"] for r in rows)
    bad = sum(r["unwalkable_edges"] for r in rows)
    physics = [
        _physics(conn, scan, args.steps, args.walk_seconds)
        for scan in (args.physics_scans or [largest[0]])
    ]
    print(
        json.dumps(
            {
                "machine": machine(),
                "scans": len(rows),
                "edges": total_edges,
                "straight": sum(r["straight"] for r in rows),
                "by_route": sum(r["by_route"] for r in rows),
                "by_flight": sum(r["by_flight"] for r in rows),
                "unwalkable_edges": bad,
                "unwalkable_fraction": round(bad / total_edges, 4),
                "unwalkable_by_cause": dict(sorted(causes.items())),
                "scans_with_unwalkable": sum(r["unwalkable_edges"] > 0 for r in rows),
                "stairs": _stair_stats(stair_rows),
                "build_s": {
                    "mean": round(float(np.mean([r["build_s"] for r in rows])), 3),
                    "max": max(r["build_s"] for r in rows),
                    "total": round(sum(r["build_s"] for r in rows), 1),
                },
                "boxes": {
                    "mean": round(float(np.mean([r["boxes"] for r in rows]))),
                    "max": max(r["boxes"] for r in rows),
                },
                "physics": physics,
                "rows": rows,
            },
            indent=1,
        )
    )
    return 0


def _stair_stats(stair_rows: list) -> dict:
    """Stair edges cut into treads and risers (else left ramps), and their proportions.

    Rises and drops of 3 cm or more count; treads run between those of ``_LEDGE`` or more
    (smaller ledges are where a stair's floor blends into others around it).
    """
    risers = np.array([x for _, _, r, _ in stair_rows for x in r])
    treads = np.array([x for _, _, _, t in stair_rows for x in t])
    return {
        "stair_edges": sum(s for s, _, _, _ in stair_rows),
        "cut_into_treads": sum(c for _, c, _, _ in stair_rows),
        "risers_and_ledges": len(risers),
        "ledges_under_ledge_m": int(np.sum(risers < _LEDGE)),
        "riser_max_m": round(float(risers.max()), 3) if len(risers) else None,
        "risers_over_0.19": int(np.sum(risers > 0.19 + 1e-9)),
        "tread_p5_m": round(float(np.percentile(treads, 5)), 3) if len(treads) else None,
        "tread_median_m": round(float(np.median(treads)), 3) if len(treads) else None,
        "treads_under_0.25": round(float(np.mean(treads < 0.25)), 3) if len(treads) else None,
    }


def _timers(data: mujoco.MjData) -> dict:
    """Mean microseconds per call of MuJoCo's step, collision and constraint timers."""
    out = {}
    for name in ("STEP", "POS_KINEMATICS", "COL_BROAD", "COL_NARROW", "CONSTRAINT"):
        t = data.timer[getattr(mujoco.mjtTimer, f"mjTIMER_{name}")]
        out[name.lower()] = round(t.duration / max(t.number, 1) * 1e6, 1)
    return out


def _reset_timers(data: mujoco.MjData) -> None:
    for t in data.timer:
        t.duration, t.number = 0.0, 0


def _physics(conn: Path, scan_id: str, steps: int, walk_seconds: float) -> dict:
    """Real-time factors of a GO1-sized free box and of the GO1 in a proxy."""
    os.environ.setdefault("HAVLN_CACHE", tempfile.mkdtemp(prefix="havln_bench_"))
    from havln_mj.scene.scan import load_scan
    from havln_mj.sim.crowd import NO_CROWD
    from havln_mj.sim.legged import LeggedAgent, LeggedOptions, LeggedWorld
    from havln_mj.sim.world import WorldOptions, world_spec

    scan = load_scan(scan_id, connectivity_dir=conn)
    g = scan.graph
    spec, _, n_collision = world_spec(scan)
    vp = g.nodes[len(g.nodes) // 2]
    x, y, _ = g.position(vp)
    body = spec.worldbody.add_body(name="go1_proxy", pos=(x, y, g.floor_z(vp) + 0.2))
    body.sleep = mujoco.mjtSleepPolicy.mjSLEEP_NEVER  # a walking robot is never at rest
    body.add_freejoint()
    body.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX, size=(0.325, 0.14, 0.15), mass=12.0, name="go1_trunk"
    )
    spec.option.timestep = 0.002
    model = spec.compile()
    data = mujoco.MjData(model)
    for _ in range(500):  # settle on the floor
        mujoco.mj_step(model, data)
    _reset_timers(data)
    t = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(model, data)
    seconds = time.perf_counter() - t
    out = {
        "scan": scan_id,
        "collision_geoms": n_collision,
        "free_box": {
            "steps_per_s": round(steps / seconds),
            "x_real_time": round(steps * model.opt.timestep / seconds, 1),
            "body_height_above_floor_m": round(float(data.qpos[2] - g.floor_z(vp)), 3),
            "contacts": int(data.ncon),
            "timers_us": _timers(data),
        },
    }
    world = LeggedWorld(scan, WorldOptions(collision="boxes"), NO_CROWD, LeggedOptions())
    agent = LeggedAgent(world)
    agent.place(g.position(vp), g.floor_z(vp), 0.0, 0.0)
    _reset_timers(agent.data)
    t = time.perf_counter()
    stand = agent.run([("stand", 10.0)], 0.0)
    out["go1_standing"] = {
        "x_real_time": round(stand.duration / (time.perf_counter() - t), 1),
        "timers_us": _timers(agent.data),
    }
    rng = np.random.default_rng(0)
    clock, actions, falls, contacts = 0.0, 0, 0, []
    _reset_timers(agent.data)
    t = time.perf_counter()
    while clock < walk_seconds:
        flat = [v for v in g.neighbors(vp) if abs(g.floor_z(v) - g.floor_z(vp)) < 0.3] or [vp]
        vp = flat[int(rng.integers(len(flat)))]
        target = np.append(g.position(vp)[:2], g.floor_z(vp))
        walk = agent.go_to(target, None, clock, on_tick=lambda _t: contacts.append(agent.data.ncon))
        clock += walk.duration
        actions += 1
        if walk.fell:
            falls += 1
            agent.place(g.position(vp), g.floor_z(vp), 0.0, clock)
    out["go1_walking_flat_edges"] = {
        "graph_actions": actions,
        "physics_seconds": round(clock, 1),
        "falls": falls,
        "mean_contacts": round(float(np.mean(contacts)), 1),
        "x_real_time": round(clock / (time.perf_counter() - t), 1),
        "timers_us": _timers(agent.data),
    }
    return out


if __name__ == "__main__":
    sys.exit(main())
