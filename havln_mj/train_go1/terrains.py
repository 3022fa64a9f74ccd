"""Training courses: a flight up, a landing, a flight down, on a flat floor, one per level.

Every course climbs along +x from ``x = 0``: ``flight_risers`` risers up (the last onto the
landing), a landing of ``LANDING`` m, as many risers down, then the floor again. Level 0
is flat; stair level ``k`` has risers linear from ``risers[0]`` (level 1) to ``risers[1]``
(the last level); ramp level ``k`` climbs at ``k / (levels - 1) × max_ramp_deg`` over the
same run as the stairs of the middle tread. Each (kind, level, tread) is compiled once, with a
GO1, and shared by every robot on it; so is its height scan (the courses are static).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco

from havln_mj.robot.go1 import add_go1, flat_floor_spec
from havln_mj.robot.go1.constants import TRUNK
from havln_mj.robot.go1.courses import add_box, add_slab
from havln_mj.robot.go1.height_scan import HeightScan
from havln_mj.train_go1.config import EnvConfig

LANDING = 1.2  # metres
WIDTH = 3.0  # metres: wide enough that a robot drifting sideways stays on the course
KINDS = ("stairs", "ramp")


@dataclass
class Course:
    """One compiled course.

    Attributes:
        model: The world with a GO1 (prefix ``go1/``).
        scan: Its height scan (on a data of its own).
        run: Horizontal length of each flight (m).
        rise: Height of the landing (m).
    """

    model: mujoco.MjModel
    scan: HeightScan
    run: float
    rise: float

    @property
    def top_start(self) -> float:
        """A start on the landing, facing down the second flight (x, m)."""
        return self.run + 0.4


def riser(cfg: EnvConfig, level: int) -> float:
    """The riser height of a stair level (0 on level 0)."""
    if level == 0:
        return 0.0
    lo, hi = cfg.risers
    return lo + (hi - lo) * (level - 1) / max(cfg.levels - 2, 1)


def ramp_degrees(cfg: EnvConfig, level: int) -> float:
    """The angle of a ramp level."""
    return cfg.max_ramp_deg * level / (cfg.levels - 1)


def course_spec(
    cfg: EnvConfig, kind: str, level: int, tread: float
) -> tuple[mujoco.MjSpec, float, float]:
    """The spec of a course, its flight's run and its landing's height."""
    spec = flat_floor_spec()
    n = cfg.flight_risers
    if kind == "stairs" or level == 0:
        h = riser(cfg, level) if kind == "stairs" else 0.0
        run = (n - 1) * tread
        if h > 0:
            for k in range(1, n):
                add_box(spec, f"up{k}", (k - 1) * tread, k * tread, WIDTH, k * h)
                x0 = run + LANDING + (n - 1 - k) * tread
                add_box(spec, f"down{k}", x0, x0 + tread, WIDTH, k * h)
            add_box(spec, "landing", run, run + LANDING, WIDTH, n * h)
        return spec, run, n * h
    mid = sorted(cfg.treads)[len(cfg.treads) // 2]
    run = (n - 1) * mid
    a = math.radians(ramp_degrees(cfg, level))
    rise = run * math.tan(a)
    add_slab(spec, "ramp_up", 0.0, run, a, WIDTH)
    add_slab(spec, "ramp_down", 2 * run + LANDING, run, -a, WIDTH)
    add_box(spec, "landing", run, run + LANDING, WIDTH, rise)
    return spec, run, rise


def build_courses(cfg: EnvConfig) -> dict[tuple[str, int, float], Course]:
    """Every course of the configuration, keyed by (kind, level, tread)."""
    out = {}
    for kind in KINDS:
        for level in range(cfg.levels):
            for tread in cfg.treads if kind == "stairs" else (0.0,):
                spec, run, rise = course_spec(cfg, kind, level, tread)
                add_go1(spec)
                model = spec.compile()
                data = mujoco.MjData(model)
                mujoco.mj_forward(model, data)
                scan = HeightScan(model, data, model.body("go1/" + TRUNK).id)
                out[(kind, level, tread)] = Course(model, scan, run, rise)
    return out
