"""The Simulator with people: states, the collision signal in every mode, people in images."""

from __future__ import annotations

import math

import numpy as np
import pytest

import havln_mj as MatterSim  # noqa: N812 - MatterSim code, only the import changed
from havln_mj.frames import heading_to
from havln_mj.humans.body import BodyShape
from havln_mj.humans.crowd import Crowd, Person
from havln_mj.humans.motion import idle
from havln_mj.scene.scan import load_scan

SCAN = "proc-0"


@pytest.fixture(scope="module")
def graph():
    return load_scan(SCAN).graph


def _sim(rendering: bool = False, humans=True, seed: int = 1) -> MatterSim.Simulator:
    sim = MatterSim.Simulator(humans=humans)
    sim.setRenderingEnabled(rendering)
    sim.setCameraResolution(96, 72)
    sim.setDepthEnabled(True)
    sim.setSeed(seed)
    return sim


def _standing_at(points: list[np.ndarray]):
    """A crowd factory: one idling person on the floor at each point."""

    def make(scan_id, graph, rng):
        shape = BodyShape(1.7)
        return Crowd(
            [Person(shape, idle(1.7, rng), np.asarray(p, float), 0.0, "idle") for p in points]
        )

    return make


def test_human_states_follow_the_seed():
    def people(seed: int):
        sim = _sim(seed=seed)
        sim.newRandomEpisode([SCAN])
        return sim.getHumanState()[0]

    a, b = people(4), people(4)
    assert a and [p.activity for p in a] == [p.activity for p in b]
    np.testing.assert_array_equal([p.position for p in a], [p.position for p in b])
    for p in a:
        assert p.region != "-" and p.text and 0.0 <= p.heading < 2 * math.pi
        assert p.position.shape == (3,) and p.velocity.shape == (3,)


def test_collision_fires_exactly_at_the_threshold(graph):
    """A person stands 0.99 m or 1.01 m beside the middle of an edge the agent walks."""
    a, b = next((u, v) for u, v, d in graph.edges() if d > 2.5)
    pa, pb = graph.position(a), graph.position(b)
    side = np.array([pa[1] - pb[1], pb[0] - pa[0], 0.0]) / np.hypot(*(pb - pa)[:2])
    for gap, expected in ((0.99, 1), (1.01, 0)):
        floor = graph.floor_z(a)
        mid = (pa + pb) / 2
        spot = np.array([mid[0], mid[1], floor]) + gap * side
        sim = _sim(humans=_standing_at([spot]))
        sim.newEpisode([SCAN], [a], [heading_to(pa, pb)], [0.0])
        ids = [v.viewpointId for v in sim.getState()[0].navigableLocations]
        pelvis = sim.getHumanState()[0][0].position
        assert np.hypot(*(pelvis - spot)[:2]) < 0.03  # idling sways the pelvis only a little
        sim.makeAction([ids.index(b)], [0.0], [0.0])
        state = sim.getState()[0]
        closest = abs(np.dot(pelvis[:2] - mid[:2], side[:2]))
        assert state.isCrushed == int(closest <= 1.0), (gap, closest, state.minHumanDistance)
        assert state.isCrushed == expected


def test_rendering_does_not_change_the_signal():
    def walk(rendering: bool):
        sim = _sim(rendering=rendering, seed=2)
        sim.newRandomEpisode([SCAN])
        rng = np.random.default_rng(0)
        out = []
        for _ in range(25):
            n = len(sim.getState()[0].navigableLocations)
            sim.makeAction([int(rng.integers(n))], [float(rng.uniform(-1, 1))], [0.0])
            s = sim.getState()[0]
            out.append((s.location.viewpointId, s.isCrushed, s.crushedBy, s.minHumanDistance))
        return out

    assert walk(False) == walk(True)


def test_people_appear_in_rgb_depth_and_mask(graph):
    # One person 2.5 m in front of a viewpoint, looking at them.
    vp = max(graph.nodes, key=graph.degree)
    eye = graph.position(vp)
    heading = 0.0
    spot = np.array([eye[0], eye[1] + 2.5, graph.floor_z(vp)])

    def look(humans):
        sim = _sim(rendering=True, humans=humans)
        sim.set_human_mask_enabled(True)
        sim.set_depth_units("metres")
        sim.newEpisode([SCAN], [vp], [heading], [-0.1])
        state = sim.getState()[0]
        sim.close()
        return state

    with_person, empty = look(_standing_at([spot])), look(False)
    mask = with_person.humanMask
    assert mask.dtype == bool and mask.shape == (72, 96)
    if not (empty.depth[..., 0][mask.any(axis=1)] > 2.6).any():
        pytest.skip("a wall stands less than 2.6 m ahead of this viewpoint")
    assert mask.mean() > 0.01 and not empty.humanMask.any()
    depth = with_person.depth[..., 0]
    # The person is drawn in depth: ~2.5 m where the mask is, nearer than the empty room.
    assert np.median(depth[mask]) == pytest.approx(2.5, abs=0.35)
    assert (depth[mask] < empty.depth[..., 0][mask] - 0.05).mean() > 0.9
    assert (np.abs(with_person.rgb.astype(int) - empty.rgb).sum(-1)[mask] > 0).mean() > 0.9
    assert with_person.isCrushed == 0


def test_real_scans_get_ha3d_people(shared_data):
    placements = shared_data / "ha3d" / "human_placements.json"
    sim = MatterSim.Simulator(humans=True, human_placements=placements)
    sim.setNavGraphPath(str(shared_data / "mp3d_connectivity"))
    sim.setRenderingEnabled(False)
    sim.newRandomEpisode(["17DRP5sb8fy"])
    people = sim.getHumanState()[0]
    assert sorted(p.region for p in people) == ["f", "v"]  # family room and tv room, as HA3D


def test_wait_lets_people_move_and_checks_collisions_throughout():
    sim = _sim(seed=3)
    sim.setBatchSize(2)
    sim.newRandomEpisode([SCAN, SCAN])
    before = [s.location.viewpointId for s in sim.getState()]
    people0 = np.array([p.position for p in sim.getHumanState()[0]])
    sim.wait([4.0, 0.0])
    a, b = sim.getState()
    assert [a.location.viewpointId, b.location.viewpointId] == before
    assert (a.time, b.time, a.step) == (4.0, 0.0, 1)
    people4 = np.array([p.position for p in sim.getHumanState()[0]])
    assert np.abs(people4 - people0).max() > 0.01  # people went on moving
    # One wait of 3 s equals three makeAction waits of 1 s, collisions included.
    one, three = _sim(seed=3), _sim(seed=3)
    for s in (one, three):
        s.newRandomEpisode([SCAN])
    one.wait([3.0])
    for _ in range(3):
        three.makeAction([0], [0.0], [0.0])
    assert one.getState()[0].time == three.getState()[0].time == 3.0
    with pytest.raises(ValueError, match="finite number of seconds"):
        one.wait([-1.0])
    with pytest.raises(IndexError, match="batch size"):
        one.wait([1.0, 1.0])


@pytest.mark.parametrize("body", ["point", "go1"])
def test_skinned_people_appear_with_either_body(graph, blob_smpl, body):
    # A person drawn as an SMPL skin (a user's model file) 2.5 m ahead of a viewpoint: the
    # frame pipeline poses skins for every body, the GO1's head camera included.
    from havln_mj.humans.skinned import Skin
    from havln_mj.sim.legged import LeggedOptions

    vp = max(graph.nodes, key=graph.degree)
    eye = graph.position(vp)
    spot = np.array([eye[0], eye[1] + 2.5, graph.floor_z(vp)])

    def skinned(scan_id, g, rng):
        clip = idle(1.7, rng)
        return Crowd([Person(BodyShape(1.7), clip, spot, math.pi, "idle", skin=Skin(blob_smpl))])

    sim = MatterSim.Simulator(humans=skinned, body=body, legged=LeggedOptions(camera_height=1.2))
    sim.setCameraResolution(96, 72)
    sim.set_human_mask_enabled(True)
    sim.newEpisode([SCAN], [vp], [0.0], [-0.1])
    state = sim.getState()[0]
    sim.close()
    assert state.humanMask.mean() > 0.002, body


def test_people_react_to_the_agent_that_stands_in_their_way(graph):
    # A walker paces a 6 m corridor through a viewpoint where the agent waits: with
    # reactions it stops at the comfort distance, so no collision; without, it walks
    # through the agent. Each element's people react to that element alone.
    from havln_mj.humans.catalog import load_catalog, make_clip

    vp = max(graph.nodes, key=graph.degree)
    eye = graph.position(vp)
    start = np.array([eye[0], eye[1] - 3.0, graph.floor_z(vp)])

    def walker(scan_id, g, rng):
        pace = load_catalog().get("hallway/hall-call")
        clip = make_clip(pace, 1.7, rng, path=np.array([[0.0, 0.0], [0.0, 6.0]]))
        return Crowd([Person(BodyShape(1.7), clip, start, 0.0, pace.id, start=0.0)])

    def wait(reactions):
        sim = MatterSim.Simulator(humans=walker, reactions=reactions)
        sim.setRenderingEnabled(False)
        sim.setBatchSize(2)
        far = next(v for v in graph.nodes if np.hypot(*(graph.position(v) - eye)[:2]) > 8)
        sim.newEpisode([SCAN, SCAN], [vp, far], [0.0, 0.0], [0.0, 0.0])
        hits, closest = [], []
        for _ in range(12):
            sim.wait([2.0, 2.0])
            hits.append([s.isCrushed for s in sim.getState()])
            closest.append(sim.getState()[0].minHumanDistance)
        return np.array(hits), min(closest)

    calm, calm_closest = wait(True)
    blind, _ = wait(False)
    assert blind[:, 0].any() and not calm[:, 0].any()
    assert calm_closest >= 1.5 - 0.05
    assert not blind[:, 1].any() and not calm[:, 1].any()  # the far element never met anyone
    again, _ = wait(True)
    assert np.array_equal(calm, again)
