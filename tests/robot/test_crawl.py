"""The stair crawl: stance forces, support targets, safe footholds, and real climbs."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from havln_mj.errors import InvalidArgumentError
from havln_mj.robot.go1 import constants as const
from havln_mj.robot.go1 import load_gains
from havln_mj.robot.go1.courses import START_X, stairs_spec
from havln_mj.robot.go1.gains import CrawlGains
from havln_mj.robot.go1.stance_forces import F_MIN, distribute, support_margin, support_target

WEIGHT = np.array([0.0, 0.0, const.TOTAL_MASS * 9.81])
FEET = {
    0: np.array([0.19, -0.13, 0.0]),
    1: np.array([0.19, 0.13, 0.0]),
    2: np.array([-0.19, -0.13, 0.0]),
    3: np.array([-0.19, 0.13, 0.0]),
}


@pytest.fixture
def crawler(go1_on):
    """A crawling GO1 before 4 risers of 0.17 m, and the course."""
    spec, course = stairs_spec(riser=0.17, tread=0.28, risers=4)
    return go1_on(spec, "crawl"), course


def test_stance_forces_carry_the_weight_without_a_moment_within_friction() -> None:
    com = np.array([0.02, 0.01, 0.27])
    forces = distribute(WEIGHT, np.zeros(3), com, FEET, mu=0.5)
    total = sum(forces.values())
    moment = sum(np.cross(FEET[leg] - com, f) for leg, f in forces.items())
    np.testing.assert_allclose(total, WEIGHT, atol=0.5)
    np.testing.assert_allclose(moment, 0.0, atol=0.1)
    for f in forces.values():
        assert f[2] >= F_MIN and math.hypot(f[0], f[1]) <= 0.5 * f[2] + 1e-9
    # The feet nearer the centre of mass carry more of it.
    assert forces[1][2] > forces[2][2]


def test_a_foot_asked_to_pull_pushes_the_least_and_never_pulls() -> None:
    three = {leg: FEET[leg] for leg in (0, 1, 2)}
    com = np.array([-0.15, 0.12, 0.27])  # outside the triangle, beyond the missing foot
    forces = distribute(WEIGHT, np.zeros(3), com, three, mu=0.5)
    # The front right foot, farthest from the centre of mass, would have to pull.
    assert forces[0][2] == pytest.approx(F_MIN)
    assert forces[1][2] > F_MIN and forces[2][2] > F_MIN
    for f in forces.values():
        assert math.hypot(f[0], f[1]) <= 0.5 * f[2] + 1e-9


def test_the_support_target_lies_inside_the_triangle_ahead_of_its_centroid() -> None:
    triangle = np.array([FEET[0], FEET[1], FEET[2]])
    target = support_target(triangle, np.array([0.3, 0.0, 0.0]), margin=0.05)
    assert support_margin(target, triangle) >= 0.05
    assert target[0] > triangle.mean(axis=0)[0]
    assert support_margin(np.array([1.0, 0.0, 0.0]), triangle) < 0


def test_footholds_keep_off_the_noses_and_the_risers(crawler) -> None:
    body, _ = crawler
    g = body.gains.crawl
    walk = np.array([1.0, 0.0, 0.0])
    for x in np.arange(-0.2, 0.8, 0.01):
        s, ground = body.gait.safe_spot(np.array([x, 0.0, 0.0]), walk, 1.0)
        spot = x + s
        tread = math.floor(spot / 0.28)  # -1 is the floor before the first riser
        lo = (tread * 0.28 + g.drop_gap) if tread >= 0 else -math.inf
        hi = (tread + 1) * 0.28 - g.face_gap
        assert lo - 1e-6 <= spot <= hi + 1e-6, (x, spot)
        assert ground == pytest.approx(0.17 * min(max(tread + 1, 0), 4), abs=0.01)
        assert abs(s) <= 0.3


def test_crawl_gains_are_checked_and_read_from_the_gains_file(tmp_path: Path) -> None:
    with pytest.raises(InvalidArgumentError, match="control_decimation"):
        CrawlGains(control_decimation=0)
    with pytest.raises(InvalidArgumentError, match="stride"):
        CrawlGains(stride=-0.1)
    path = tmp_path / "gains.json"
    path.write_text(json.dumps({"crawl": {"stride": 0.12}}))
    assert load_gains(path).crawl.stride == 0.12


@pytest.mark.slow
@pytest.mark.parametrize("down", [False, True], ids=["up", "down backwards"])
def test_the_crawl_climbs_and_descends_four_risers_of_017(crawler, down: bool) -> None:
    body, course = crawler
    start, goal = (course.top_x, START_X) if down else (START_X, course.top_x)
    # Facing up the stair both ways: it descends walking backwards.
    body.reset(start, 0.03, course.rise if down else 0.0, math.pi / 2 + 0.05)
    res = body.forward(goal - body.true_pose().x)
    end = body.true_pose()
    floor = 0.0 if down else course.rise
    assert not res.fell and not res.timed_out
    assert abs(end.x - goal) < 0.3 and abs(end.y) < 0.3
    assert end.z == pytest.approx(floor + const.STAND_HEIGHT, abs=0.08)
    assert body.true_pose().heading == pytest.approx(math.pi / 2 + 0.05, abs=0.2)
