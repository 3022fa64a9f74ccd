"""The Simulator driving the GO1: graph and continuous actions, people, falls, images."""

from __future__ import annotations

import dataclasses
import math

import mujoco
import numpy as np
import pytest

import havln_mj as MatterSim  # noqa: N812 - MatterSim code, only the import changed
from havln_mj.errors import InvalidActionError, InvalidArgumentError
from havln_mj.frames import heading_to, wrap_angle
from havln_mj.humans.body import BodyShape
from havln_mj.humans.crowd import Crowd, Person
from havln_mj.humans.motion import idle
from havln_mj.scene.scan import load_scan
from havln_mj.sim.crowd import NO_CROWD
from havln_mj.sim.legged import LeggedAgent, LeggedOptions, LeggedWorld
from havln_mj.sim.world import WorldOptions

SCAN = "proc-0"


@pytest.fixture(scope="module")
def graph():
    return load_scan(SCAN).graph


@pytest.fixture(scope="module")
def edge(graph):
    """A flat edge of 2–4 m and the heading along it."""
    a, b, _ = next(
        (u, v, d)
        for u, v, d in graph.edges()
        if 2.0 < d < 4.0 and abs(graph.floor_z(u) - graph.floor_z(v)) < 0.05
    )
    return a, b, heading_to(graph.position(a), graph.position(b))


def _sim(**kwargs) -> MatterSim.Simulator:
    sim = MatterSim.Simulator(body="go1", **kwargs)
    sim.setRenderingEnabled(False)
    sim.setCameraResolution(64, 48)
    return sim


def test_graph_action_walks_to_the_viewpoint(graph, edge):
    a, b, h = edge
    sim = _sim()
    sim.newEpisode([SCAN], [a], [h + 0.4], [0.0])
    start = sim.getState()[0]
    assert start.pose is not None and not start.fell
    assert np.hypot(*(start.pose[:2] - graph.position(a)[:2])) < 0.05
    ids = [v.viewpointId for v in start.navigableLocations]
    sim.makeAction([ids.index(b)], [0.0], [0.0])
    state = sim.getState()[0]
    assert state.location.viewpointId == b  # the snapped viewpoint
    assert np.hypot(*(state.pose[:2] - graph.position(b)[:2])) < 0.3
    # MatterSim keeps the heading when moving: the robot turns back to it.
    assert abs(wrap_angle(state.heading - (h + 0.4))) < math.radians(5)
    assert state.heading == pytest.approx(state.pose[3])
    dist = float(np.linalg.norm(graph.position(b)[:2] - graph.position(a)[:2]))
    assert dist / 0.6 < state.time < dist / 0.2 + 6.0  # physics time, a walking robot's pace
    assert state.step == 1 and not state.fell


def test_the_terrain_gait_walks_graph_actions_too(graph, edge):
    a, b, h = edge
    sim = _sim(legged=LeggedOptions(controller="terrain"))
    sim.newEpisode([SCAN], [a], [h], [0.0])
    ids = [v.viewpointId for v in sim.getState()[0].navigableLocations]
    sim.makeAction([ids.index(b)], [0.0], [0.0])
    state = sim.getState()[0]
    assert state.arrived and state.location.viewpointId == b and not state.fell
    assert np.hypot(*(state.pose[:2] - graph.position(b)[:2])) < 0.3
    with pytest.raises(InvalidArgumentError, match="'hop' unknown; valid: trot, terrain"):
        LeggedOptions(controller="hop")


def test_continuous_actions(graph, edge):
    a, _, h = edge
    sim = _sim(legged=LeggedOptions(forward_m=0.5, turn_rad=math.pi / 4))
    sim.newEpisode([SCAN], [a], [h], [0.0])
    p0 = sim.getState()[0].pose
    sim.makeRobotAction(["forward"])
    p1 = sim.getState()[0].pose
    along = (p1[:2] - p0[:2]) @ [math.sin(p0[3]), math.cos(p0[3])]
    assert along == pytest.approx(0.5, abs=0.05)
    sim.makeRobotAction(["turn_right"])
    p2 = sim.getState()[0].pose
    assert math.degrees(wrap_angle(p2[3] - p1[3])) == pytest.approx(45.0, abs=3.0)
    before = sim.getState()[0]
    sim.make_robot_action(["stop"])
    assert sim.getState()[0] is before
    near = sim.getState()[0].location.viewpointId
    assert np.hypot(*(graph.position(near)[:2] - p2[:2])) == pytest.approx(
        min(np.hypot(*(graph.position(v)[:2] - p2[:2])) for v in graph.nodes), abs=1e-9
    )
    with pytest.raises(InvalidActionError, match="jump"):
        sim.makeRobotAction(["jump"])
    point = MatterSim.Simulator()
    point.setRenderingEnabled(False)
    point.newRandomEpisode([SCAN])
    with pytest.raises(InvalidActionError, match="go1"):
        point.makeRobotAction(["forward"])


def test_solid_people_touch_the_robot_and_count_as_collisions(graph, edge):
    a, b, h = edge
    mid = (graph.position(a) + graph.position(b)) / 2
    spot = np.array([mid[0], mid[1], graph.floor_z(a)])

    def standing(scan_id, g, rng):
        return Crowd([Person(BodyShape(1.7), idle(1.7, rng), spot, h + math.pi, "idle")])

    sim = _sim(humans=standing, legged=LeggedOptions(physical_humans=True))
    sim.newEpisode([SCAN], [a], [h], [0.0])
    ids = [v.viewpointId for v in sim.getState()[0].navigableLocations]
    sim.makeAction([ids.index(b)], [0.0], [0.0])
    state = sim.getState()[0]
    assert state.isCrushed == 1 and state.crushedBy == (0,)
    assert state.humanContacts > 0


def test_a_fall_ends_the_episode(edge):
    a, _, h = edge
    sim = _sim()
    sim.newEpisode([SCAN], [a], [h], [0.0])
    legged = sim._batch.elements[0].body.agent  # tip the robot onto its back
    qa = legged.body.qadr
    legged.data.qpos[qa + 2] += 0.2
    legged.data.qpos[qa + 3 : qa + 7] = (0.0, 1.0, 0.0, 0.0)
    mujoco.mj_forward(legged.world.model, legged.data)
    sim.makeRobotAction(["forward"])
    state = sim.getState()[0]
    assert state.fell
    sim.makeRobotAction(["forward"])  # nothing moves once fallen
    assert sim.getState()[0].fell
    np.testing.assert_allclose(sim.getState()[0].pose, state.pose)


def test_images_come_from_the_robot_camera(edge):
    a, _, h = edge
    sim = _sim(legged=LeggedOptions(camera_height=1.5))
    sim.setRenderingEnabled(True)
    sim.setDepthEnabled(True)
    sim.set_depth_units("metres")
    sim.newEpisode([SCAN], [a], [h], [0.0])
    level = sim.getState()[0]
    sim.makeAction([0], [0.0], [0.5])  # look up: the camera pitches, the robot stays
    up = sim.getState()[0]
    assert level.rgb.shape == (48, 64, 3) and level.rgb.any()
    assert (level.depth > 0).mean() > 0.8
    assert not np.array_equal(level.rgb, up.rgb)
    np.testing.assert_allclose(up.pose[:2], level.pose[:2], atol=0.05)
    sim.close()


def test_geodesic_distance_from_the_robot(graph, edge):
    a, b, h = edge
    sim = _sim()
    sim.newEpisode([SCAN], [a], [h], [0.0])
    (d0,) = sim.getGeodesicDistance([b])
    straight = float(np.hypot(*(graph.position(b)[:2] - graph.position(a)[:2])))
    assert straight - 0.1 <= d0 <= straight + 0.3  # an unobstructed edge: nearly straight
    sim.makeRobotAction(["forward"])
    (d1,) = sim.get_geodesic_distance([b])
    assert d1 == pytest.approx(d0 - 0.5, abs=0.1)  # the robot walked half a metre toward b


@pytest.mark.parametrize("by", ["viewpoint", "floor point"])
def test_an_edge_walked_by_a_route_passes_its_stops(graph, by):
    # Give one proc-0 edge a made-up route through a common neighbour, as graph proxies do
    # for a line of sight across a stairwell (through the viewpoint, or through its floor
    # point as a flight drawn for the edge is stored): the GO1 walks through that neighbour.
    a, b, c = next(
        (u, v, w)
        for u, v, _ in graph.edges()
        for w in graph.neighbors(u)
        if w in graph.neighbors(v) and w not in (u, v)
    )
    floor = {v: np.append(graph.position(v)[:2], graph.floor_z(v)) for v in (a, b, c)}
    stop = c if by == "viewpoint" else tuple(floor[c])
    scan = dataclasses.replace(load_scan(SCAN), routes={(a, b): (a, stop, b)})
    world = LeggedWorld(scan, WorldOptions(collision="boxes"), NO_CROWD, LeggedOptions())
    agent = LeggedAgent(world)
    agent.place(graph.position(a), graph.floor_z(a), 0.0, 0.0)
    np.testing.assert_array_equal(world.waypoints(agent.position(), floor[b]), [floor[c]])
    assert world.waypoints(agent.position(), floor[c]) == []  # a-c is walked straight
    out = agent.go_to(floor[b], None, 0.0)
    assert not out.fell
    track = out.track[:, 1:3]
    assert np.hypot(*(track - floor[c][:2]).T).min() < 0.3
    assert np.hypot(*(agent.position()[:2] - floor[b][:2])) < 0.3
    # From b the route runs backwards.
    np.testing.assert_array_equal(world.waypoints(agent.position(), floor[a]), [floor[c]])


def test_the_building_sleeps_and_the_robot_never_does(edge):
    # MuJoCo's sleep feature is on so the building's static geoms are posed once, not every
    # step; the actuated GO1 must stay awake even while it stands still.
    a, _, h = edge
    sim = _sim()
    sim.newEpisode([SCAN], [a], [h], [0.0])
    legged = sim._batch.elements[0].body.agent
    assert legged.world.model.opt.enableflags & mujoco.mjtEnableBit.mjENBL_SLEEP
    z0 = legged.position()[2]
    legged.run([("stand", 3.0)], 0.0)
    assert np.all(legged.data.tree_asleep < 0)  # negative: awake
    assert legged.position()[2] == pytest.approx(z0, abs=0.03)
    sim.makeRobotAction(["forward"])
    assert not sim.getState()[0].fell


def test_a_move_that_stalls_short_never_reports_the_target(tmp_path, edge, graph):
    # A scan folder whose edge a-b is blocked by a wall across its middle: the robot walks
    # into it and stops. The state must say where it really stands: still at a, not arrived,
    # its true pose well short of b; the point body, which does not collide, arrives.
    import json
    import shutil

    a, b, h = edge
    folder = tmp_path / "walled"
    shutil.copytree(load_scan(SCAN).folder, folder)
    boxes = json.loads((folder / "boxes.json").read_text())
    pa, pb = graph.position(a), graph.position(b)
    mid, floor = (pa + pb) / 2, graph.floor_z(a)
    half = np.array([1.2, 1.2])
    boxes["boxes"].append(
        {
            "lo": [*(mid[:2] - half), floor],
            "hi": [*(mid[:2] + half), floor + 1.0],
            "kind": "furniture",
            "material": "test_wall",
            "rgba": [1.0, 0.0, 0.0, 1.0],
        }
    )
    (folder / "boxes.json").write_text(json.dumps(boxes))
    sim = _sim()
    sim.newEpisode([str(folder)], [a], [h], [0.0])
    ids = [v.viewpointId for v in sim.getState()[0].navigableLocations]
    sim.makeAction([ids.index(b)], [0.0], [0.0])
    state = sim.getState()[0]
    assert not state.arrived and state.location.viewpointId == a
    assert np.hypot(*(state.pose[:2] - pb[:2])) > 1.0
    assert sim.getGeodesicDistance([b])[0] > 1.0  # measured from where it stands


@pytest.mark.parametrize("controller", ["trot", "crawl", "hybrid"])
def test_go_to_turns_the_crawls_back_to_a_stair_it_descends(graph, edge, controller):
    # The robot stands on a platform two risers above the floor at a; b lies down a stair of
    # two risers. The crawl and the hybrid (which crawls over the risers) turn their backs to
    # b and walk backwards; the trot faces b. Primitives are recorded, not walked.
    from havln_mj.scene.boxes import BoxSet

    a, b, h = edge
    pa, pb = graph.position(a), graph.position(b)
    floor = graph.floor_z(a)
    u = (pb[:2] - pa[:2]) / np.hypot(*(pb[:2] - pa[:2]))
    steps = [(pa[:2], 0.5, 0.34), (pa[:2] + 0.8 * u, 0.3, 0.17)]  # centre, half side, top
    lo = [[*(c - r), floor] for c, r, _ in steps]
    hi = [[*(c + r), floor + top] for c, r, top in steps]
    scan = load_scan(SCAN)
    boxes = BoxSet(
        np.vstack([scan.boxes.lo, lo]),
        np.vstack([scan.boxes.hi, hi]),
        (*scan.boxes.kind, "floor", "floor"),
        (*scan.boxes.material, "test_step", "test_step"),
        np.vstack([scan.boxes.rgba, np.ones((2, 4))]),
    )
    scan = dataclasses.replace(scan, boxes=boxes)
    world = LeggedWorld(
        scan, WorldOptions(collision="boxes"), NO_CROWD, LeggedOptions(controller=controller)
    )
    agent = LeggedAgent(world)
    agent.place(pa, floor + 0.34, h, 0.0)
    calls = []

    def record(kind):
        def primitive(amount, on_tick=None):
            calls.append((kind, amount))

        return primitive

    agent.body.turn, agent.body.forward = record("turn"), record("forward")
    agent.go_to(np.append(pb[:2], floor), None, 0.0)
    (_, turn), (_, forward) = calls[:2]
    backwards = controller != "trot"
    assert abs(abs(turn) - math.pi) < 0.2 if backwards else abs(turn) < 0.2
    assert (forward < 0) == backwards
    assert abs(abs(forward) - np.hypot(*(pb[:2] - pa[:2]))) < 0.1


def test_physics_diverging_while_the_robot_is_placed_ends_the_episode(graph, edge):
    a, _, h = edge
    agent = LeggedAgent(
        LeggedWorld(load_scan(SCAN), WorldOptions(collision="boxes"), NO_CROWD, LeggedOptions())
    )
    stand = agent.body.stand

    def diverging_stand(seconds, **kw):
        agent.data.qvel[:] = np.nan  # MuJoCo resets the state and counts a warning
        return stand(seconds, **kw)

    agent.body.stand = diverging_stand
    agent.place(graph.position(a), graph.floor_z(a), h, 0.0)
    assert agent.diverged and agent.fell
    np.testing.assert_allclose(agent.position()[:2], graph.position(a)[:2])
    agent.body.stand = stand
    agent.place(graph.position(a), graph.floor_z(a), h, 0.0)
    assert not agent.diverged and not agent.fell
