"""Where the ground has steps: what chooses between the trot and the crawl.

The hybrid controller trots over level ground and crawls where a walk or a turn meets a step
(a riser, a stair's nose, a ledge). Both checks read the height scan, as the robot's depth
camera would see the ground: along a walk, three lines (the centre and each side's feet) are
sampled every ``SAMPLE`` metres from behind the hind feet to beyond the front feet at the
end; the largest rise or drop between neighbouring samples is the walk's step, the steepest
rise over ``GRADE_WINDOW`` its grade. Under a turn the feet sweep a disc around the trunk;
its ground is sampled on rings.
"""

from __future__ import annotations

import itertools
import math

from havln_mj.robot.go1 import constants as const
from havln_mj.robot.go1.gains import CrawlGains
from havln_mj.robot.go1.height_scan import HeightScan

SAMPLE = 0.02  # metres between ground samples along a line
REACH = const.HIP_X + 0.15  # metres a foot stands ahead of (or behind) the trunk at most
SIDE = const.HIP_Y + const.ABDUCTION  # metres a foot stands beside the centre line
_RINGS = (0.1, 0.2, 0.3, REACH)  # radii (m) of the rings sampled under a turn
_RING_SAMPLES = 48
GRADE_WINDOW = 0.2  # metres over which a walk's slope is measured


def largest_step(heights: list[float]) -> float:
    """The largest rise or drop between neighbouring finite samples (0 when none).

    Non-finite samples (a wall: ``inf``; no ground within reach: ``-inf``) are skipped: the
    step across them is measured between the finite samples on either side.
    """
    finite = [h for h in heights if math.isfinite(h)]
    return max((abs(b - a) for a, b in itertools.pairwise(finite)), default=0.0)


def steepest(heights: list[float], spacing: float, window: float = GRADE_WINDOW) -> float:
    """The steepest grade (rise over run) between finite samples ``window`` metres apart."""
    k = max(1, round(window / spacing))
    pairs = zip(heights, heights[k:], strict=False)
    grades = [abs(b - a) for a, b in pairs if math.isfinite(a) and math.isfinite(b)]
    return max(grades, default=0.0) / (k * spacing)


def step_along(
    scan: HeightScan, x: float, y: float, yaw: float, distance: float, top: float
) -> tuple[float, float]:
    """The largest step and the steepest grade a walk of ``distance`` (m) meets.

    A negative ``distance`` walks backwards.

    Args:
        scan: The robot's height scan.
        x: Trunk x at the start (m).
        y: Trunk y at the start (m).
        yaw: Trunk yaw (rad, counter-clockwise from +x).
        distance: Walk along the yaw (m).
        top: Trunk height (m): the scan's reference for what is ground.
    """
    c, s = math.cos(yaw), math.sin(yaw)
    lo, hi = min(0.0, distance) - REACH, max(0.0, distance) + REACH
    n = max(1, math.ceil((hi - lo) / SAMPLE))
    step = grade = 0.0
    for side in (-SIDE, 0.0, SIDE):
        line = []
        for k in range(n + 1):
            t = lo + (hi - lo) * k / n
            line.append(scan.height(x + c * t - s * side, y + s * t + c * side, top))
        step = max(step, largest_step(line))
        grade = max(grade, steepest(line, (hi - lo) / n))
    return step, grade


def step_around(scan: HeightScan, x: float, y: float, top: float) -> float:
    """The largest step on the ground a turn in place at (x, y) sweeps its feet over.

    The ground at the trunk and on rings out to a foot's reach; each ring's samples and
    each ray out from the trunk are compared neighbour to neighbour.
    """
    centre = scan.height(x, y, top)
    rays = []
    for k in range(_RING_SAMPLES):
        a = 2.0 * math.pi * k / _RING_SAMPLES
        c, s = math.cos(a), math.sin(a)
        rays.append([centre] + [scan.height(x + r * c, y + r * s, top) for r in _RINGS])
    rings = [[ray[i] for ray in rays] for i in range(1, len(_RINGS) + 1)]
    return max(largest_step(line) for line in rays + [ring + ring[:1] for ring in rings])


def meets_step(
    scan: HeightScan,
    gains: CrawlGains,
    x: float,
    y: float,
    z: float,
    yaw: float,
    distance: float | None,
) -> bool:
    """Whether a walk or turn from a trunk at (x, y, z) meets a step or a slope.

    A step higher than ``gains.trot_step``, a slope steeper than ``gains.trot_grade``; the
    walk is ``distance`` m along ``yaw`` (negative: backwards), or None for a turn in place.
    """
    if distance is None:
        return step_around(scan, x, y, z) > gains.trot_step
    step, grade = step_along(scan, x, y, yaw, distance, z)
    return step > gains.trot_step or grade > gains.trot_grade
