"""The collision signal's sampling of a body's track: straight moves, routes, instants."""

from __future__ import annotations

import math

import numpy as np
import pytest

from havln_mj.humans.clip import Clip
from havln_mj.humans.crowd import Crowd, Person
from havln_mj.humans.population import populate
from havln_mj.scene.scan import load_scan
from havln_mj.sim import proximity
from havln_mj.sim.crowd import NEAR_M, Proximity
from havln_mj.sim.proximity import (
    SAMPLE_HZ,
    NearMemo,
    _near,
    batch_proximity,
    knots_proximity,
    sample_knots,
    track_proximity,
)

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


def _direct(crowd, knots, distance=1.0):
    """The signal computed from the crowd's own positions, sample by sample."""
    knots = np.asarray(knots, float).reshape(-1, 4)
    near = _near(crowd, knots[:, 1:], max(NEAR_M, distance))
    if not near:
        return Proximity(False, (), np.inf)
    times, positions = sample_knots(knots)
    return track_proximity(crowd, times, positions, distance, near)


def _people_of_every_kind():
    """People by HA3D's rule in proc-1 (walkers, people sitting down then seated, idlers)
    plus one whose clip does not loop (held at its last frame) and one of a single frame."""
    scan = load_scan("proc-1")
    people = [p for seed in (1, 3) for p in populate(scan, np.random.default_rng(seed)).people]
    spot = scan.graph.position(scan.graph.nodes[0]) - [0.0, 0.0, 1.2]
    root = np.zeros((40, 3))
    root[:, 0] = np.linspace(0.0, 1.5, 40)
    walk_once = Clip(root, 30.0, positions=np.zeros((40, 24, 3)), loop_start=39, name="once")
    still = Clip(root[:1], 30.0, positions=np.zeros((1, 24, 3)), name="still")
    shape = people[0].shape
    people += [
        Person(shape, walk_once, spot, 0.3, "once", start=0.2),
        Person(shape, still, spot + np.array([1.0, 0.0, 0.0]), 0.0, "still"),
    ]
    return scan.graph, Crowd(people)


def _random_action(graph, rng):
    """A point body's knots: an edge walked at 1 m/s then a turn, a wait, or an instant."""
    a, b, _ = graph.edges()[int(rng.integers(graph.num_edges))]
    if rng.random() < 0.5:
        a, b = b, a
    pa, pb = graph.position(a), graph.position(b)
    t0 = float(rng.choice([rng.uniform(0.0, 3.0), rng.uniform(0.0, 300.0)]))
    kind = rng.random()
    if kind < 0.05:
        return ((t0, *pa),)
    if kind < 0.15:
        return ((t0, *pa), (t0 + float(rng.uniform(0.1, 4.0)), *pa))
    move = float(np.linalg.norm(pb - pa))
    turn = float(rng.uniform(0.0, 2.0)) if rng.random() < 0.8 else 0.0
    knots = [(t0, *pa), (t0 + move, *pb)]
    if turn > 0:
        knots.append((t0 + move + turn, *pb))
    return tuple(tuple(float(v) for v in k) for k in knots)


def test_the_tabulated_signal_matches_the_direct_one_on_10000_actions():
    graph, crowd = _people_of_every_kind()
    rng = np.random.default_rng(0)
    actions = [_random_action(graph, rng) for _ in range(10_000)]
    memo = NearMemo()
    batched = []
    for k in range(0, len(actions), 8):  # batches of 8 tracks among the same people
        batched += batch_proximity([(crowd, a) for a in actions[k : k + 8]], 1.0, memo)
    crushed = finite = 0
    for knots, fast in zip(actions, batched, strict=True):
        slow = _direct(crowd, knots)
        assert knots_proximity(crowd, knots) == fast
        assert (fast.crushed, fast.people) == (slow.crushed, slow.people), knots
        if math.isinf(slow.min_distance):
            assert math.isinf(fast.min_distance), knots
        else:
            assert abs(fast.min_distance - slow.min_distance) < 1e-3, knots
            finite += 1
        crushed += slow.crushed
    # The comparison covers many passes near people, collisions included, and far ones.
    assert crushed > 1000 and 3000 < finite < 9000


def _robot_track(graph, rng):
    """A robot's trunk track: a wandering walk of many knots, some ticks standing still."""
    a = graph.position(graph.nodes[int(rng.integers(len(graph.nodes)))])
    t = float(rng.uniform(0.0, 300.0))
    steps = rng.normal(0.0, 0.05, (int(rng.integers(2, 400)), 3)) * [1.0, 1.0, 0.0]
    steps[rng.random(len(steps)) < 0.1] = 0.0
    xyz = a + np.cumsum(steps, axis=0)
    times = t + np.cumsum(rng.choice([0.0, 0.02, 0.1], len(steps)))
    return np.column_stack([times, xyz]).tolist()


@pytest.mark.skipif(proximity._closest is None, reason="the C extension is not built here")
def test_the_compiled_table_read_agrees_with_the_numpy_path(monkeypatch):
    graph, crowd = _people_of_every_kind()
    rng = np.random.default_rng(1)
    actions = [_random_action(graph, rng) for _ in range(10_000)]
    actions += [_robot_track(graph, rng) for _ in range(300)]
    # Long waits (a near miss, a hit): more samples than the numpy path keeps precomputed.
    for node in graph.nodes[1:3]:
        here = graph.position(node)
        actions += [((t0, *here), (t0 + 290.0, *here)) for t0 in (0.5, 10.25)]
    memo = NearMemo()

    def signals():
        single = [knots_proximity(crowd, a, 1.0, memo) for a in actions]
        batched = []
        for k in range(0, len(actions), 8):
            batched += batch_proximity([(crowd, a) for a in actions[k : k + 8]], 1.0, memo)
        return single, batched

    compiled = signals()
    monkeypatch.setattr(proximity, "_closest", None)
    for fast, slow in zip(compiled, signals(), strict=True):
        # Flags bit for bit; distances to rounding (numpy's |x + iy| is not C's hypot).
        assert [(p.crushed, p.people) for p in fast] == [(p.crushed, p.people) for p in slow]
        a = np.array([p.min_distance for p in fast])
        b = np.array([p.min_distance for p in slow])
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=0.0)
    hits = sum(p.crushed for p in compiled[0])
    assert hits > 1000 and np.isfinite([p.min_distance for p in compiled[0]]).sum() > 3000
