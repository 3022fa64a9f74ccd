"""Each rule of HA3D's protocol on hand-made episodes, beside the strict one."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from havln_mj.errors import InvalidArgumentError
from havln_mj.humans.body import BodyShape
from havln_mj.humans.crowd import Crowd, Person
from havln_mj.humans.motion import idle
from havln_mj.scene.scan import load_scan
from havln_mj.sim.simulator import Simulator
from havln_mj.tasks.episodes import Episode, HumanOnPath
from havln_mj.tasks.experts import (
    STOP,
    WAIT,
    HumanAwareExpert,
    ShortestPathExpert,
    run_expert,
)
from havln_mj.tasks.metrics import EvalEpisode, Evaluator, MetricConfig
from havln_mj.tasks.planning import PathPlanner
from havln_mj.tasks.protocol import HA3D, STRICT, get_protocol
from havln_mj.tasks.step import TaskStep

SCAN = "proc-0"


@pytest.fixture(scope="module")
def graph():
    return load_scan(SCAN).graph


def _standing_at(points):
    def make(scan_id, graph, rng):
        return Crowd(
            [
                Person(BodyShape(1.7), idle(1.7, rng), np.asarray(p, float), 0.0, "idle")
                for p in points
            ]
        )

    return make


def _sim(points):
    sim = Simulator(humans=_standing_at(points))
    sim.setRenderingEnabled(False)
    sim.setDiscretizedViewingAngles(True)
    return sim


def _floor(graph, vp, dx=0.0):
    p = graph.position(vp)
    return np.array([p[0] + dx, p[1], graph.floor_z(vp)])


def _episode(graph, path, humans=(), heading=0.0):
    people = tuple(HumanOnPath(vp, rel, "room:someone") for vp, rel in humans)
    return Episode(7, SCAN, tuple(path), heading, ("go",), graph.path_length(path), people)


def _score(trajectory, episode, graph, config):
    steps = [[r.viewpoint, r.heading, r.elevation, r.is_crushed] for r in trajectory.records]
    return Evaluator(config=config).score(EvalEpisode.from_ha_r2r(episode, steps), graph)


def _facing(graph, a, b):
    from havln_mj.frames import heading_to

    # The discretised view nearest the direction of b: no turn before the first move.
    return round(heading_to(graph.position(a), graph.position(b)) / (np.pi / 6)) * (np.pi / 6)


def _two_hop_path(graph):
    """A shortest path a-b-c, b's and c's neighbours more than 1.6 m from a and from c."""
    for a, c in itertools.permutations(graph.nodes, 2):
        path = graph.shortest_path(a, c)
        if len(path) != 3 or abs(graph.floor_z(a) - graph.floor_z(c)) > 0.05:
            continue
        far = all(
            np.linalg.norm(graph.position(v) - graph.position(end)) > 1.6
            for end in (a, c)
            for v in graph.nodes
            if v != end
        )
        if far:
            return path
    pytest.skip("no isolated two-hop path in this scene")


def test_protocols_by_name_and_what_they_configure():
    assert get_protocol("strict") is STRICT and get_protocol(HA3D) is HA3D
    with pytest.raises(InvalidArgumentError, match="strict, ha3d"):
        get_protocol("lenient")
    assert HA3D.metrics == MetricConfig.ha3d() and HA3D.expert_max_steps == 20
    sim = Simulator(humans=False)
    TaskStep(sim, protocol="ha3d")
    assert sim.collision_rule.check == "state" and sim.human_clock.kind == "ha3d"
    TaskStep(sim, protocol="strict")
    assert sim.collision_rule.check == "action" and sim.human_clock.kind == "continuous"
    TaskStep(sim)  # no protocol: the simulator's rules are left alone
    assert sim.collision_rule.check == "action"


def test_the_ha3d_clock_runs_on_across_episodes_and_task_steps(graph):
    # HA3D's counter is shared by every episode: a new task step does not restart it.
    a, b, c = _two_hop_path(graph)
    sim = _sim([])
    episode = _episode(graph, (a, b, c))
    run_expert(sim, episode, ShortestPathExpert(), protocol="ha3d")
    clock, frame = sim.human_clock, sim.human_clock_frame
    TaskStep(sim, protocol="ha3d").start([episode])
    assert sim.human_clock_frame == clock.after_start(frame)
    sim.set_rules(frame=40)
    TaskStep(sim, protocol="ha3d")
    assert sim.human_clock_frame == 40
    TaskStep(sim, protocol="strict")
    TaskStep(sim, protocol="ha3d")  # a new clock starts at 0
    assert sim.human_clock_frame == 0
    with pytest.raises(InvalidArgumentError, match="react"):
        TaskStep(Simulator(humans=False, reactions=True), protocol="ha3d")


def test_start_state_hit_and_beginning_subtraction(graph):
    # A person on the start (labelled Beginning): the start state collides, and HA3D's TCR
    # takes that person off again; its CR counts the raw hit, ours the adjusted count.
    a, b, c = _two_hop_path(graph)
    episode = _episode(graph, (a, b, c), [(a, "Beginning")], heading=_facing(graph, a, b))
    sim = _sim([_floor(graph, a)])
    tr = run_expert(sim, episode, ShortestPathExpert(), protocol="ha3d")
    assert tr.records[0].is_crushed == 1 and tr.final_viewpoint == c
    assert tr.collisions == 1  # facing b already: no turn at the start
    ha3d = _score(tr, episode, graph, HA3D.metrics)
    assert ha3d["collisions"] == 1 and ha3d["unavoidable"] == 1
    assert ha3d["tcr"] == 0 and ha3d["cr"] == 1  # raw CR
    ours = _score(tr, episode, graph, MetricConfig())
    assert ours["tcr"] == 0 and ours["cr"] == 0  # adjusted CR


def test_unclipped_tcr_goes_below_zero(graph):
    # A person labelled End 1.2 m from the goal, never within 1 m of the agent: HA3D
    # subtracts them anyway, so the episode scores −1; clipped, 0.
    a, b, c = _two_hop_path(graph)
    episode = _episode(graph, (a, b, c), [(c, "End")])
    sim = _sim([_floor(graph, c, dx=1.2)])
    tr = run_expert(sim, episode, ShortestPathExpert(), protocol="ha3d")
    assert tr.collisions == 0 and tr.final_viewpoint == c
    assert _score(tr, episode, graph, HA3D.metrics)["tcr"] == -1.0
    assert _score(tr, episode, graph, MetricConfig(critical="ha3d"))["tcr"] == 0.0


def _no_detour_case(graph):
    """Start a next to b, goal c: every path a -> c passes within 1 m of a person on b."""
    planner = PathPlanner(graph)
    for a, c in itertools.permutations(graph.nodes, 2):
        path = graph.shortest_path(a, c)
        if len(path) < 3:
            continue
        b = path[1]
        person = _floor(graph, b)
        point = person + np.array([0.0, 0.0, 1.36])
        if np.linalg.norm(point - graph.position(a)) >= 4.5:
            continue
        blocked = planner.blocked([point], 1.0, (a, c), "camera_3d")
        if planner.plan(a, c, blocked, weighted=False) is None:
            return a, b, c, person
    pytest.skip("no boxed-in case in this scene")


def test_stop_when_blocked_and_the_strict_wait_bound(graph):
    a, _, c, person = _no_detour_case(graph)
    episode = _episode(graph, graph.shortest_path(a, c))
    sim = _sim([person])
    ha3d = HumanAwareExpert.for_protocol("ha3d")
    tr = run_expert(sim, episode, ha3d, protocol="ha3d", max_steps=HA3D.expert_max_steps)
    assert tr.stopped and tr.path == [a] and [r.action for r in tr.steps] == [STOP]
    # Strict: waits max_waits times, then walks on regardless of the person.
    strict = HumanAwareExpert.for_protocol("strict")
    strict.max_waits = 3
    tr = run_expert(sim, episode, strict, protocol="strict")
    actions = [r.action for r in tr.steps]
    assert actions[:3] == [WAIT] * 3 and WAIT not in actions[3:]
    assert tr.stopped and tr.final_viewpoint == c and strict.walked_through > 0
    # Or stops after its waits; with no bound it waits to the step cap.
    patient = HumanAwareExpert("local", max_waits=2, after_waits="stop")
    tr = run_expert(sim, episode, patient, protocol="strict")
    assert [r.action for r in tr.steps] == [WAIT, WAIT, STOP] and tr.path == [a]
    forever = HumanAwareExpert("local", max_waits=None)
    tr = run_expert(sim, episode, forever, protocol="strict", max_steps=25)
    assert not tr.stopped and forever.waits == 25
    with pytest.raises(InvalidArgumentError, match="after_waits"):
        HumanAwareExpert(after_waits="run")


def test_ha3d_expert_plans_by_hops_in_3d(graph):
    expert = HumanAwareExpert.for_protocol("ha3d")
    rules = (expert.weighted, expert.distance, expert.max_waits, expert.after_waits)
    assert rules == (False, "camera_3d", 0, "stop")
    planner = PathPlanner(graph)
    vp = graph.nodes[0]
    cam = graph.position(vp)
    points = cam + np.array([[0.0, 0.0, 0.99], [0.0, 0.0, 3.0], [4.4, 0.0, 1.2]])
    # HA3D's tests are strict: closer than 1 m (3-D) blocks, closer than 4.5 m is near.
    assert vp in planner.blocked(points[:1], 1.0, (), "camera_3d")
    assert vp not in planner.blocked(points[1:2], 1.0, (), "camera_3d")
    near = planner.people_near(vp, points, 4.5, "camera_3d")
    assert np.array_equal(near, points[:2])  # the third is 4.56 m away in 3-D


def test_per_visit_counting(graph):
    a, b, c = _two_hop_path(graph)
    steps = [[a, 0.0, 0.0, 1], [a, 0.5, 0.0, 1], [a, 1.0, 0.0, 0], [b, 1.0, 0.0, 1], [c, 1, 0, 0]]
    episode = _episode(graph, (a, b, c))
    ev = EvalEpisode.from_ha_r2r(episode, steps)
    per_step = Evaluator(config=MetricConfig.ha3d()).score(ev, graph)
    per_visit = Evaluator(config=MetricConfig(count="viewpoint")).score(ev, graph)
    assert per_step["collisions"] == 3 and per_visit["collisions"] == 2
    with pytest.raises(InvalidArgumentError, match="count"):
        MetricConfig(count="minute")
