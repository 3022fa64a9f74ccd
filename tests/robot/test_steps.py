"""Steps in the ground and the hybrid controller's choice of gait (trot or crawl)."""

from __future__ import annotations

import math

import pytest

from havln_mj.robot.go1 import Go1Body
from havln_mj.robot.go1 import constants as const
from havln_mj.robot.go1.courses import START_X, flat_floor_spec, stairs_spec
from havln_mj.robot.go1.steps import largest_step, steepest

FACING_UP = math.pi / 2  # heading of +x, up the course's stair


@pytest.fixture
def stair_body(go1_on):
    """``stair_body(controller)``: a GO1 before 4 risers of 0.17 m, and the course."""

    def make(controller: str = "hybrid") -> tuple[Go1Body, object]:
        spec, course = stairs_spec(riser=0.17, tread=0.28, risers=4)
        return go1_on(spec, controller), course

    return make


def test_steps_skip_walls_and_holes_and_grades_are_rise_over_run() -> None:
    inf = math.inf
    assert largest_step([0.0, 0.01, 0.03, 0.2, 0.2]) == pytest.approx(0.17)
    assert largest_step([0.0, inf, 0.02, -inf, 0.0]) == pytest.approx(0.02)
    assert largest_step([inf, -inf]) == 0.0
    ramp = [0.02 * 0.3 * k for k in range(30)]  # a 0.3 grade sampled every 2 cm
    assert steepest(ramp, 0.02) == pytest.approx(0.3)
    assert steepest([0.0] * 5 + [0.17] * 20, 0.02) == pytest.approx(0.17 / 0.2)


def test_the_hybrid_crawls_where_a_walk_or_turn_meets_a_riser_and_trots_elsewhere(
    stair_body,
) -> None:
    body, _ = stair_body()
    body.reset(START_X, 0.0, 0.0, FACING_UP)
    assert not body.crawl  # level ground all round: it stands as the trot
    assert body.meets_step(1.0) and body.crawls(1.0)  # up to the first riser and over it
    assert not body.meets_step(0.4)  # short of the riser by more than a foot's reach
    assert not body.meets_step(-0.5)  # backwards, away from the stair
    assert not body.meets_step(None)  # a turn in place
    assert body.meets_step(0.8, heading=FACING_UP)
    assert not body.meets_step(0.8, heading=-FACING_UP)
    body.reset(-0.1, 0.0, 0.0, FACING_UP)
    assert body.meets_step(None)  # the front feet sweep over the first riser
    assert body.crawl  # and the hybrid stands there as the crawl
    trot, _ = stair_body("trot")
    trot.reset(-0.1, 0.0, 0.0, FACING_UP)
    assert not trot.crawls(None) and not trot.crawls(1.0)


def test_the_hybrid_walks_level_ground_as_the_trot_does(go1_on) -> None:
    hybrid, trot = go1_on(flat_floor_spec(), "hybrid"), go1_on(flat_floor_spec(), "trot")
    results = []
    for body in (hybrid, trot):
        body.reset(0.0, 0.0, 0.0, 0.3)
        results.append((body.forward(0.5), body.turn(math.pi / 4)))
        assert not body.crawl
    (f_h, t_h), (f_t, t_t) = results
    assert f_h.distance == f_t.distance and t_h.heading_change == t_t.heading_change
    assert f_h.duration < 5.0 and abs(f_h.distance - 0.5) < 0.05


@pytest.mark.slow
def test_the_hybrid_turns_as_the_trot_and_climbs_as_the_crawl(stair_body) -> None:
    body, course = stair_body()
    body.reset(START_X, 0.02, 0.0, -FACING_UP)  # its back to the stair
    turn = body.turn(math.pi)
    assert not body.crawl and not turn.fell and turn.duration < 6.0
    climb = body.forward(course.top_x - body.true_pose().x)
    assert body.crawl
    end = body.true_pose()
    assert not climb.fell and not climb.timed_out
    assert abs(end.x - course.top_x) < 0.3 and abs(end.y) < 0.3
    assert end.z == pytest.approx(course.rise + const.STAND_HEIGHT, abs=0.08)
