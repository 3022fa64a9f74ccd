"""The collision signal's sampling of a body's track: straight moves, routes, instants."""

from __future__ import annotations

import numpy as np
import pytest

from havln_mj.sim.crowd import SAMPLE_HZ, knots_proximity, sample_knots

# An L-shaped route: 3 m east, then 4 m north (7 m), walked from t = 10 s in 7 s, then a 1 s
# turn in place.
_KNOTS = np.array(
    [[10.0, 0.0, 0.0, 1.5], [13.0, 3.0, 0.0, 1.5], [17.0, 3.0, 4.0, 1.5], [18.0, 3.0, 4.0, 1.5]]
)


def test_a_route_is_walked_at_constant_speed_then_the_turn_stands_still(standing):
    times, positions = sample_knots(_KNOTS)
    assert times[0] == 10.0 and times[-1] == pytest.approx(18.0)
    assert np.diff(times).max() <= 1.0 / SAMPLE_HZ + 1e-12
    assert set(_KNOTS[:, 0]) <= set(times)  # every corner is a sample
    walked = np.where(positions[:, 1] > 0, 3.0 + positions[:, 1], positions[:, 0])
    np.testing.assert_allclose(walked, np.minimum(times - 10.0, 7.0), atol=1e-9)
    np.testing.assert_allclose(positions[-1], _KNOTS[-1, 1:])
    on_first = (positions[:, 1] == 0) & (positions[:, 0] <= 3)
    on_second = np.isclose(positions[:, 0], 3.0) & (positions[:, 1] >= 0)
    assert np.all(on_first | on_second)


def test_a_straight_move_is_a_track_of_two_knots(standing):
    straight = np.array([[0.0, 0.0, 0.0, 1.5], [5.0, 3.0, 4.0, 1.5]])
    times, positions = sample_knots(straight)
    np.testing.assert_allclose(
        positions, straight[0, 1:] + (times / 5.0)[:, None] * (straight[1, 1:] - straight[0, 1:])
    )


def test_an_instant_is_one_sample(standing):
    times, positions = sample_knots(np.array([[4.0, 1.0, 2.0, 3.0]]))
    assert times.tolist() == [4.0] and positions.tolist() == [[1.0, 2.0, 3.0]]
    hit = knots_proximity(standing([[1.5, 2.0, 0.5]]), [[4.0, 1.0, 2.0, 3.0]])
    assert hit.crushed and hit.min_distance == pytest.approx(0.5)


def test_the_signal_follows_the_route_not_the_line_between_its_ends(standing):
    corner = [[3.0, 0.0, 0.5]]  # 2.4 m from the line from the start to the end
    on_route = knots_proximity(standing(corner), _KNOTS)
    assert on_route.crushed and on_route.people == (0,) and on_route.min_distance < 1e-9
    straight = knots_proximity(standing(corner), _KNOTS[[0, 2]])
    assert not straight.crushed and straight.min_distance == pytest.approx(2.4, abs=1e-3)
    # People farther than NEAR_M from every leg are not even sampled.
    far = knots_proximity(standing([[10.0, -5.0, 0.5]]), _KNOTS)
    assert not far.crushed and far.min_distance == np.inf
