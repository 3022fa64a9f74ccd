"""havln_mj.Simulator on built-in procedural houses: API rules, errors, clock, people, images."""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest

import havln_mj as MatterSim  # noqa: N812 - MatterSim code, only the import changed
from havln_mj.errors import (
    BatchSizeError,
    InvalidActionError,
    NotInitializedError,
    UnknownScanError,
    UnknownViewpointError,
)
from havln_mj.frames import heading_to
from havln_mj.scene.scan import load_scan
from havln_mj.sim import point, scenes
from havln_mj.sim.egocentric import EgoAction
from havln_mj.sim.simulator import WAIT_S

SCAN = "proc-0"


@pytest.fixture(scope="module")
def graph():
    return load_scan(SCAN).graph


def _sim(batch: int = 1, rendering: bool = False, **kwargs) -> MatterSim.Simulator:
    sim = MatterSim.Simulator(**kwargs)
    sim.setRenderingEnabled(rendering)
    sim.setCameraResolution(64, 48)
    sim.setBatchSize(batch)
    return sim


def _edge(graph):
    """A viewpoint with a neighbour, the neighbour, and the heading facing it."""
    a, b, _ = graph.edges()[0]
    return a, b, heading_to(graph.position(a), graph.position(b))


def test_moves_along_an_edge_and_keeps_heading(graph):
    a, b, h = _edge(graph)
    sim = _sim()
    sim.newEpisode([SCAN], [a], [h], [0.0])
    state = sim.getState()[0]
    ids = [v.viewpointId for v in state.navigableLocations]
    assert ids[0] == a and b in ids
    sim.make_action([ids.index(b)], [0.0], [0.0])  # the Pythonic alias
    after = sim.get_state()[0]
    assert after.location.viewpointId == b
    assert after.step == 1
    assert after.heading == pytest.approx(h)  # heading is kept when moving
    assert after.location.rel_distance == 0.0


def test_clock_advances_by_each_actions_duration(graph):
    a, b, h = _edge(graph)
    sim = _sim(speed=0.5, turn_rate=1.0)
    sim.newEpisode([SCAN], [a], [h], [0.0])
    assert sim.getState()[0].time == 0.0
    ids = [v.viewpointId for v in sim.getState()[0].navigableLocations]
    dist = float(np.linalg.norm(graph.position(b) - graph.position(a)))
    sim.makeAction([ids.index(b)], [0.5], [0.0])  # move, then turn 0.5 rad
    assert sim.getState()[0].time == pytest.approx(dist / 0.5 + 0.5)
    sim.makeAction([0], [0.0], [0.0])  # neither moves nor turns: a wait
    assert sim.getState()[0].time == pytest.approx(dist / 0.5 + 0.5 + WAIT_S)


def test_setters_lock_after_initialize_with_a_warning():
    sim = _sim(batch=2)
    sim.initialize()
    with pytest.warns(UserWarning, match="setBatchSize"):
        sim.setBatchSize(3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sim.setCameraResolution(32, 24)  # resolution, VFOV and limits stay settable
        sim.setCameraVFOV(1.0)
        assert sim.setElevationLimits(-0.5, 0.5)
    with pytest.raises(BatchSizeError, match="batch size is 2"):
        sim.newRandomEpisode([SCAN] * 3)
    sim.newRandomEpisode([SCAN] * 2)
    assert sim.getState()[0].rgb.shape == (24, 32, 3)


def test_elevation_limits_follow_mattersims_rule():
    sim = _sim()
    assert not sim.setElevationLimits(0.1, 0.5)
    assert not sim.setElevationLimits(-0.5, math.pi / 2)
    assert sim.setElevationLimits(-0.2, 0.3)
    sim.newRandomEpisode([SCAN])
    sim.makeAction([0], [0.0], [1.0])
    assert sim.getState()[0].elevation == pytest.approx(0.3)


def test_errors_name_the_bad_value(graph):
    a, _, _ = _edge(graph)
    sim = _sim()
    with pytest.raises(NotInitializedError):
        sim.makeAction([0], [0.0], [0.0])
    sim.initialize()
    with pytest.raises(RuntimeError, match="newEpisode"):
        sim.makeAction([0], [0.0], [0.0])
    with pytest.raises(IndexError, match="proc_0") as info:
        sim.newEpisode(["proc_0"], [a], [0.0], [0.0])
    assert isinstance(info.value, UnknownScanError) and "proc-0" in str(info.value)
    with pytest.raises(ValueError, match="nope"):
        sim.newEpisode([SCAN], ["nope"], [0.0], [0.0])
    with pytest.raises(UnknownViewpointError):
        sim.newEpisode([SCAN], [a[:-1]], [0.0], [0.0])
    with pytest.raises(ValueError, match="nan"):
        sim.newEpisode([SCAN], [a], [float("nan")], [0.0])
    with pytest.raises(IndexError, match="2 entries"):
        sim.newEpisode([SCAN, SCAN], [a, a], [0.0, 0.0], [0.0, 0.0])
    with pytest.raises(BatchSizeError, match="list"):
        sim.newEpisode(SCAN, a, 0.0, 0.0)
    sim.newEpisode([SCAN], [a], [0.0], [0.0])
    n = len(sim.getState()[0].navigableLocations)
    with pytest.raises(ValueError, match=rf"index {n} .* valid 0–{n - 1}"):
        sim.makeAction([n], [0.0], [0.0])
    with pytest.raises(InvalidActionError, match="-1"):
        sim.makeAction([-1], [0.0], [0.0])
    with pytest.raises(InvalidActionError, match="inf"):
        sim.makeAction([0], [math.inf], [0.0])
    assert sim.getState()[0].step == 0  # nothing changed


def test_a_bad_batch_element_changes_nothing(graph):
    a, b, h = _edge(graph)
    sim = _sim(batch=2)
    sim.newEpisode([SCAN, SCAN], [a, b], [h, h], [0.0, 0.0])
    before = [s.location.viewpointId for s in sim.getState()]
    with pytest.raises(InvalidActionError, match="batch element 1"):
        sim.makeAction([0, 99], [0.1, 0.1], [0.0, 0.0])
    assert [s.location.viewpointId for s in sim.getState()] == before
    assert [s.step for s in sim.getState()] == [0, 0]


def test_random_episodes_follow_the_seed():
    def starts(seed: int) -> list[tuple[str, float]]:
        sim = _sim(batch=4)
        sim.setSeed(seed)
        sim.newRandomEpisode([SCAN] * 4)
        return [(s.location.viewpointId, s.heading) for s in sim.getState()]

    assert starts(3) == starts(3)
    assert starts(3) != starts(4)
    assert all(e == 0.0 for e in (s.elevation for s in _started(5)))


def _started(seed: int):
    sim = _sim(batch=3)
    sim.setSeed(seed)
    sim.newRandomEpisode([SCAN] * 3)
    return sim.getState()


def test_is_crushed_catches_a_person_passed_mid_action(graph, standing):
    # Find an edge longer than 2.5 m, and stand a person beside its middle.
    a, b = next((u, v) for u, v, d in graph.edges() if d > 2.5)
    pa, pb = graph.position(a), graph.position(b)
    side = np.array([pa[1] - pb[1], pb[0] - pa[0], 0.0])
    person = (pa + pb) / 2 + 0.4 * side / np.linalg.norm(side) - [0.0, 0.0, 0.5]
    sim = _sim(humans=lambda scan, g, rng: standing([person]))
    sim.newEpisode([SCAN], [a], [heading_to(pa, pb)], [0.0])
    start = sim.getState()[0]
    assert start.isCrushed == 0  # both ends are more than 1 m away
    ids = [v.viewpointId for v in start.navigableLocations]
    sim.makeAction([ids.index(b)], [0.0], [0.0])
    state = sim.getState()[0]
    assert state.isCrushed == 1 and state.crushedBy == (0,)
    # Sampled at 16 Hz at 1 m/s: a sample falls within 3.2 cm of the closest point.
    assert 0.4 - 1e-9 <= state.minHumanDistance <= math.hypot(0.4, 0.032)
    assert sim.getHumanState() == [[tuple(person)]]
    sim.makeAction([0], [0.0], [0.0])  # waiting at b, far from the person
    assert sim.getState()[0].isCrushed == int(np.hypot(*(pb - person)[:2]) <= 1.0)


def _detour(graph):
    """Viewpoints a, b, c: a-b, a-c and c-b are edges, and c lies over 1.5 m off the line a-b."""
    for a, b, _ in graph.edges():
        pa, pb = graph.position(a)[:2], graph.position(b)[:2]
        for c in graph.neighbors(a):
            if c == b or c not in graph.neighbors(b):
                continue
            pc = graph.position(c)[:2]
            t = np.clip((pc - pa) @ (pb - pa) / ((pb - pa) @ (pb - pa)), 0.0, 1.0)
            if np.hypot(*(pc - pa - t * (pb - pa))) > 1.5:
                return a, b, c
    raise AssertionError("proc-0 has no such triangle")


@pytest.fixture(params=["viewpoint", "floor point"])
def routed(graph, monkeypatch, request):
    """proc-0 with one edge a-b walked by a route through c, as graph proxies store them:
    through the viewpoint c, or (a flight drawn for the edge) through c's floor point."""
    a, b, c = _detour(graph)
    stop = c if request.param == "viewpoint" else (*graph.position(c)[:2], graph.floor_z(c))
    real = scenes.load_scan
    monkeypatch.setattr(
        scenes,
        "load_scan",
        lambda *args, **kwargs: dataclasses.replace(
            real(*args, **kwargs), routes={(a, b): (a, stop, b)}
        ),
    )
    return a, b, c, stop


def test_the_point_body_walks_a_routed_edge_straight(graph, routed, standing):
    # Routes are for bodies that walk the building (the GO1); the point body is MatterSim's
    # agent, and moves straight between cameras whatever the scan stores.
    a, b, c, _ = routed
    pa, pb = graph.position(a), graph.position(b)
    person = graph.position(c) - [0.0, 0.0, 1.0]  # on the route, off the straight line
    for rendering in (False, True):
        sim = _sim(speed=0.5, rendering=rendering, humans=lambda s, g, r: standing([person]))
        sim.newEpisode([SCAN], [a], [heading_to(pa, pb)], [0.0])
        ids = [v.viewpointId for v in sim.getState()[0].navigableLocations]
        sim.makeAction([ids.index(b)], [0.0], [0.0])
        state = sim.getState()[0]
        assert state.location.viewpointId == b and state.arrived
        assert state.time == pytest.approx(float(np.linalg.norm(pb - pa)) / 0.5)
        assert state.isCrushed == 0
        sim.close()


def test_an_edge_walked_straight_misses_a_person_off_its_line(graph, standing):
    a, b, c = _detour(graph)  # no route stored: a-b is walked straight
    person = graph.position(c) - [0.0, 0.0, 1.0]
    sim = _sim(humans=lambda scan, g, rng: standing([person]))
    pa, pb = graph.position(a), graph.position(b)
    sim.newEpisode([SCAN], [a], [heading_to(pa, pb)], [0.0])
    ids = [v.viewpointId for v in sim.getState()[0].navigableLocations]
    sim.makeAction([ids.index(b)], [0.0], [0.0])
    state = sim.getState()[0]
    assert state.time == pytest.approx(float(np.linalg.norm(pb - pa)))
    assert state.isCrushed == 0 and state.minHumanDistance > 1.5


def test_scenes_without_people_report_no_collision():
    sim = _sim()
    sim.newRandomEpisode([SCAN])
    state = sim.getState()[0]
    assert state.isCrushed == 0 and state.minHumanDistance == math.inf
    assert sim.getHumanState() == [[]]


def test_egocentric_actions(graph):
    a, _, h = _edge(graph)
    sim = _sim()
    sim.setDiscretizedViewingAngles(True)
    sim.newEpisode([SCAN], [a], [h], [0.0])
    start = sim.getState()[0]
    sim.makeEgoAction([EgoAction.TURN_RIGHT])
    assert sim.getState()[0].viewIndex == (start.viewIndex % 12 + 1) % 12 + 12
    sim.makeEgoAction(["turn_left"])
    sim.makeEgoAction([EgoAction.LOOK_UP])
    sim.makeEgoAction([EgoAction.LOOK_UP])  # saturates at +30°
    assert sim.getState()[0].elevation == pytest.approx(math.pi / 6)
    sim.makeEgoAction([EgoAction.LOOK_DOWN])
    before = sim.getState()[0]
    sim.makeEgoAction([EgoAction.STOP])
    assert sim.getState()[0] is before  # STOP leaves the element alone
    sim.makeEgoAction([1])  # FORWARD: the navigable location nearest the view centre
    assert sim.getState()[0].location.viewpointId == before.navigableLocations[1].viewpointId
    with pytest.raises(InvalidActionError, match="jump"):
        sim.makeEgoAction(["jump"])


def test_forward_never_goes_backwards_without_restriction(graph):
    a, b, h = _edge(graph)
    sim = _sim()
    sim.setRestrictedNavigation(False)
    back = (h + math.pi) % (2 * math.pi)  # b is now straight behind
    sim.newEpisode([SCAN], [a], [back], [0.0])
    state = sim.getState()[0]
    assert b in [v.viewpointId for v in state.navigableLocations]
    sim.makeEgoAction([EgoAction.FORWARD])
    moved_to = sim.getState()[0].location
    half_hfov = 0.8 * 64 / 48 / 2
    ahead = [v for v in state.navigableLocations[1:] if abs(v.rel_heading) <= half_hfov]
    assert moved_to.viewpointId == (ahead[0].viewpointId if ahead else a)


def test_rendering_off_does_no_gl_work(monkeypatch):
    def fail(*args, **kwargs):
        raise AssertionError("a world was built with rendering off")

    monkeypatch.setattr(point, "Stage", fail)
    sim = _sim()
    sim.newRandomEpisode([SCAN])
    sim.makeAction([0], [0.3], [0.0])
    state = sim.getState()[0]
    assert state.rgb.shape == (48, 64, 3) and state.rgb.dtype == np.uint8
    assert state.depth.shape == (48, 64, 1) and state.depth.dtype == np.uint16
    assert not state.rgb.any()


def test_rendered_images_in_mattersim_and_plain_formats(graph):
    a, b, h = _edge(graph)

    def render(order: str, units: str):
        sim = _sim(batch=2, rendering=True)
        sim.setDepthEnabled(True)
        sim.set_color_order(order)
        sim.set_depth_units(units)
        sim.newEpisode([SCAN, SCAN], [a, b], [h, h + 1.0], [0.0, -0.3])
        states = sim.getState()
        sim.close()
        return states

    bgr = render("BGR", "mattersim")
    rgb = render("RGB", "metres")
    for s_bgr, s_rgb in zip(bgr, rgb, strict=True):
        assert s_bgr.rgb.dtype == np.uint8 and s_bgr.rgb.shape == (48, 64, 3)
        np.testing.assert_array_equal(s_bgr.rgb, s_rgb.rgb[..., ::-1])
        assert s_bgr.depth.dtype == np.uint16 and s_bgr.depth.shape == (48, 64, 1)
        assert s_rgb.depth.dtype == np.float32
        seen = s_rgb.depth > 0
        assert seen.mean() > 0.9  # a house interior: walls everywhere
        expected = np.rint(s_rgb.depth[seen] * 4000)
        np.testing.assert_array_equal(s_bgr.depth[seen], expected)
    assert not np.array_equal(bgr[0].rgb, bgr[1].rgb)  # two poses, two images


def _fields(state) -> tuple:
    """A state's fields, images by shape, viewpoints by value."""
    nav = [tuple(v) for v in state.navigableLocations]
    shapes = (state.rgb.shape, state.depth.shape)
    return (*state[:2], shapes, tuple(state.location), *state[5:8], nav, *state[9:])


@pytest.mark.parametrize("people", [False, True])
def test_a_batch_of_one_steps_alike_on_the_plain_and_the_checked_path(people):
    # Plain one-entry lists take the batch-of-one path; numpy values take the checked path.
    plain, checked = _sim(humans=people), _sim(humans=people)
    rng = np.random.default_rng(3)
    for sim in (plain, checked):
        sim.newEpisode([SCAN], [""], [1.0], [0.0])
    for step in range(60):
        a, b = plain.getState()[0], checked.getState()[0]
        assert _fields(a) == _fields(b), step
        k = int(rng.integers(len(a.navigableLocations)))
        dh, de = float(rng.uniform(-3, 3)), float(rng.uniform(-0.3, 0.3))
        plain.makeAction([k], [dh], [de])
        checked.makeAction([np.int64(k)], [np.float64(dh)], np.array([de]))
    assert plain.getState()[0].step == 60


def test_states_and_viewpoints_are_read_only_records_compared_by_identity(graph):
    import pickle

    sim = _sim()
    sim.newEpisode([SCAN], [graph.nodes[0]], [0.0], [0.0])
    state = sim.getState()[0]
    with pytest.raises(AttributeError):
        state.heading = 1.0
    with pytest.raises(AttributeError):
        state.location.x = 1.0
    again = pickle.loads(pickle.dumps(state))
    assert again is not state and again != state  # identity, as objects (images inside)
    assert again.location.viewpointId == state.location.viewpointId
    assert again.navigableLocations[0].ix == state.location.ix
    assert state.location == state.location and hash(state) == hash(state)
    assert MatterSim.ViewPoint("v", 3, 1.0, 2.0, 3.0).rel_distance == 0.0
    assert MatterSim.SimState("s", 0, None, None, None, 0.0, 0.0, 0, []).isCrushed == 0
