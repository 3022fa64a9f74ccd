"""The collision signal's sampling of an action: straight moves and routes."""

from __future__ import annotations

import numpy as np
import pytest

from havln_mj.sim.crowd import SAMPLE_HZ, action_samples, proximity


class _Standing:
    """People standing still at fixed points."""

    def __init__(self, points):
        self.points = np.asarray(points, float)

    def __len__(self):
        return len(self.points)

    def positions(self, times, people=None):
        points = self.points if people is None else self.points[people]
        return np.broadcast_to(points, (len(times), *points.shape)).copy()

    def footprint(self):
        return self.points[:, :2], np.zeros(len(self.points))


# An L-shaped route: 3 m east, then 4 m north (7 m), walked in 7 s, then a 1 s turn.
_ROUTE = np.array([[0.0, 0.0, 1.5], [3.0, 0.0, 1.5], [3.0, 4.0, 1.5]])


def test_a_route_is_walked_at_constant_speed_then_the_turn_stands_still():
    times, positions = action_samples(_ROUTE, 10.0, 7.0, 8.0)
    assert times[0] == 10.0 and times[-1] == pytest.approx(18.0)
    assert np.diff(times).max() <= 1.0 / SAMPLE_HZ + 1e-12
    # Distance walked along the route grows with time at 1 m/s (the first leg has y = 0,
    # the second x = 3).
    walked = np.where(positions[:, 1] > 0, 3.0 + positions[:, 1], positions[:, 0])
    np.testing.assert_allclose(walked, np.minimum(times - 10.0, 7.0), atol=1e-9)
    np.testing.assert_allclose(positions[-1], _ROUTE[-1])
    # Every sample lies on the route.
    on_first = (positions[:, 1] == 0) & (positions[:, 0] <= 3)
    on_second = np.isclose(positions[:, 0], 3.0) & (positions[:, 1] >= 0)
    assert np.all(on_first | on_second)


def test_a_straight_move_is_a_route_of_two_points():
    straight = _ROUTE[[0, 2]]
    times, positions = action_samples(straight, 0.0, 5.0, 5.0)
    np.testing.assert_allclose(
        positions, straight[0] + (times / 5.0)[:, None] * (straight[1] - straight[0])
    )


def test_the_signal_follows_the_route_not_the_line_between_its_ends():
    corner = [[3.0, 0.0, 0.5]]  # 2.4 m from the line from the start to the end
    on_route = proximity(_Standing(corner), _ROUTE, 0.0, 7.0, 7.0)
    assert on_route.crushed and on_route.people == (0,) and on_route.min_distance < 1e-9
    straight = proximity(_Standing(corner), _ROUTE[[0, 2]], 0.0, 5.0, 5.0)
    assert not straight.crushed and straight.min_distance == pytest.approx(2.4, abs=1e-3)
    # People farther than NEAR_M from every leg are not even sampled.
    far = proximity(_Standing([[10.0, -5.0, 0.5]]), _ROUTE, 0.0, 7.0, 7.0)
    assert not far.crushed and far.min_distance == np.inf
