"""The simulator's collision rules (strict | HA3D's) and human clocks (continuous | HA3D's)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from havln_mj.errors import InvalidArgumentError
from havln_mj.humans.body import BodyShape
from havln_mj.humans.crowd import Crowd, Person
from havln_mj.humans.motion import idle
from havln_mj.scene.scan import load_scan
from havln_mj.sim.crowd import HA3D_TRACK_HEIGHT, ha3d_points, state_proximity
from havln_mj.sim.rules import CollisionRule, HumanClock
from havln_mj.sim.simulator import Simulator

SCAN = "proc-0"


@pytest.fixture(scope="module")
def graph():
    return load_scan(SCAN).graph


def _standing_at(points):
    """A crowd factory: one idling person with their floor point at each of ``points``."""

    def make(scan_id, graph, rng):
        people = [
            Person(BodyShape(1.7), idle(1.7, rng), np.asarray(p, float), 0.0, "idle")
            for p in points
        ]
        return Crowd(people)

    return make


def _sim(humans, **kw):
    sim = Simulator(humans=humans, **kw)
    sim.setRenderingEnabled(False)
    sim.setDiscretizedViewingAngles(True)
    return sim


def _floor(graph, vp, dx=0.0, dy=0.0):
    p = graph.position(vp)
    return np.array([p[0] + dx, p[1] + dy, graph.floor_z(vp)])


def _straight_edge(graph, length=2.5):
    """Two neighbours at least ``length`` apart on one floor."""
    for a, b in itertools.permutations(graph.nodes, 2):
        level = abs(graph.floor_z(a) - graph.floor_z(b)) < 0.05
        long = np.hypot(*(graph.position(a) - graph.position(b))[:2]) >= length
        if b in graph.neighbors(a) and level and long:
            return a, b
    pytest.skip("no long edge in this scene")


def test_rules_and_clocks_check_their_values():
    assert CollisionRule.strict() == CollisionRule("action", "horizontal", 1.0)
    assert CollisionRule.ha3d() == CollisionRule("state", "camera_3d", 1.0)
    with pytest.raises(InvalidArgumentError, match="check"):
        CollisionRule("sometimes")
    with pytest.raises(InvalidArgumentError, match="horizontally"):
        CollisionRule("action", "camera_3d")
    with pytest.raises(InvalidArgumentError, match="threshold"):
        CollisionRule.ha3d(threshold=-1.0)
    with pytest.raises(InvalidArgumentError, match="even"):
        HumanClock("ha3d", step_frames=31)
    with pytest.raises(InvalidArgumentError, match="unknown"):
        Simulator(collision_rule="lenient")
    # HA3D's clock poses people only in states, and its people do not react.
    with pytest.raises(InvalidArgumentError, match="per-state"):
        Simulator(human_clock="ha3d")
    with pytest.raises(InvalidArgumentError, match="react"):
        Simulator(collision_rule="ha3d", human_clock="ha3d", reactions=True)
    with pytest.raises(InvalidArgumentError, match="frame"):
        Simulator(collision_rule="ha3d").set_rules(human_clock="ha3d", frame=120)


def test_ha3d_clock_counts_frames_as_ha3d_does(graph):
    # +16 at a start (getState(16)), +32 per action in two halves (makeAction, getState),
    # each half restarting the counter at 0 once it reaches 120; shared across episodes.
    sim = _sim(_standing_at([]), collision_rule="ha3d", human_clock="ha3d")
    vp = graph.nodes[0]
    sim.newEpisode([SCAN], [vp], [0.0], [0.0])
    frames = [sim.human_clock_frame]
    for _ in range(5):
        sim.makeAction([0], [0.5], [0.0])
        frames.append(sim.human_clock_frame)
    sim.newEpisode([SCAN], [vp], [0.0], [0.0])  # not reset by a new episode
    frames.append(sim.human_clock_frame)
    assert frames == [16, 48, 80, 112, 16, 48, 64]
    assert sim.getState()[0].time == 0.0  # the episode's own time is unchanged


def test_ha3d_people_are_posed_at_the_shared_clock(graph):
    sim = _sim(_standing_at([_floor(graph, graph.nodes[0])]), collision_rule="ha3d")
    sim.set_rules(human_clock="ha3d", frame=40)
    sim.newEpisode([SCAN], [graph.nodes[0]], [0.0], [0.0])
    crowd = sim.people()
    expected = crowd.positions(np.array([56 / 20.0]))[0]  # frame 40 + 16, at 20 frames/s
    assert np.allclose(sim.getHumanPositions()[0], expected)
    points = sim.collision_points()[0]
    assert np.allclose(points[:, :2], expected[:, :2])
    assert np.allclose(points[:, 2], _floor(graph, graph.nodes[0])[2] + HA3D_TRACK_HEIGHT)


def test_start_state_collides_under_both_rules(graph):
    vp = graph.nodes[0]
    person = _floor(graph, vp, dx=0.3)
    for rule, clock in (("strict", "continuous"), ("ha3d", "ha3d")):
        sim = _sim(_standing_at([person]), collision_rule=rule, human_clock=clock)
        sim.newEpisode([SCAN], [vp], [0.0], [0.0])
        state = sim.getState()[0]
        assert state.isCrushed == 1 and state.crushedBy == (0,), rule


def test_ha3d_checks_states_only_strict_checks_the_whole_action(graph):
    # A person standing beside the middle of an edge: passing them collides under the strict
    # rule (checked along the move) but not HA3D's (checked only where the move ends).
    a, b = _straight_edge(graph)
    mid = (graph.position(a) + graph.position(b)) / 2
    person = np.array([mid[0], mid[1], graph.floor_z(a)])
    results = {}
    for rule, clock in (("strict", "continuous"), ("ha3d", "ha3d")):
        sim = _sim(_standing_at([person]), collision_rule=rule, human_clock=clock)
        sim.setDiscretizedViewingAngles(False)
        sim.setRestrictedNavigation(False)
        sim.newEpisode([SCAN], [a], [0.0], [0.0])
        start = sim.getState()[0]
        k = [v.viewpointId for v in start.navigableLocations].index(b)
        sim.makeAction([k], [0.0], [0.0])
        results[rule] = (start.isCrushed, sim.getState()[0].isCrushed)
    assert results == {"strict": (0, 1), "ha3d": (0, 0)}


def test_ha3d_distance_is_3d_from_the_camera(graph):
    # A person on a floor 3 m below the agent, right under it: horizontally on top of the
    # agent (strict collides), 3-D far away (HA3D does not).
    vp = graph.nodes[0]
    below = _floor(graph, vp) - np.array([0.0, 0.0, 3.0])
    hits = {}
    for rule in ("strict", "ha3d"):
        sim = _sim(_standing_at([below]), collision_rule=rule)
        sim.newEpisode([SCAN], [vp], [0.0], [0.0])
        hits[rule] = sim.getState()[0].isCrushed
    assert hits == {"strict": 1, "ha3d": 0}
    # The signal itself: 3-D from the camera to the tracked point, threshold inclusive.
    crowd = _standing_at([_floor(graph, vp)])(SCAN, graph, np.random.default_rng(0))
    points = ha3d_points(crowd, crowd.positions(np.array([0.0]))[0])
    camera = points[0] + np.array([0.6, 0.0, 0.8])  # 1.0 m away in 3-D
    assert state_proximity(points, camera, 1.0).crushed
    assert math.isclose(state_proximity(points, camera, 1.0).min_distance, 1.0)
    assert not state_proximity(points, camera + np.array([0.01, 0.0, 0.0]), 1.0).crushed
