"""The Matterport3DSimulator test suite's image-free cases, re-stated for havln_mj.Simulator.

Run on the 90 real connectivity graphs (rendering off). Unlike MatterSim's own action tests,
whose index list is never cleared so the agent never moves, the tests here that can move do
move, and every R2R path is followed through ``makeAction``. The agent loops are written as
MatterSim code: only the import differs.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

import havln_mj as MatterSim  # noqa: N812 - MatterSim code, only the import changed

SCANS = ["2t7WUuJeko7", "17DRP5sb8fy"]
VIEWPOINTS = ["cc34e9176bfe47ebb23c58c165203134", "5b9b2794954e4694a45fc424a8643081"]
# The action scripts of MatterSim's tests (degrees), and the states they must produce.
HEADING = [10, 350, 350, 1, 90, 180, 90, 270, 90, 270]
HEADING_CHG = [-20, -360, 371, 89, 90, -90, -180, -180, -180, 0]
DISCRETE_HEADING = [0, 330, 300, 330, 0, 30, 0, 330, 300, 270]
ELEVATION = [10, 10, -26, -40, -40, -40, 50, 50, 40, 0]
ELEVATION_CHG = [0, -36, -30, -10, 0, 90, 5, -10, -40, 0]
DISCRETE_ELEVATION = [0, 0, -30, -30, -30, -30, 0, 30, 0, -30]
VIEW_INDEX = [12, 23, 10, 11, 0, 1, 12, 35, 22, 9]


@pytest.fixture(scope="module")
def conn(shared_data: Path) -> Path:
    return shared_data / "mp3d_connectivity"


def _sim(conn: Path, batch: int, width: int = 200, height: int = 100, vfov_deg: float = 45):
    sim = MatterSim.Simulator()
    sim.setNavGraphPath(str(conn))
    sim.setCameraResolution(width, height)
    sim.setCameraVFOV(math.radians(vfov_deg))
    sim.setRenderingEnabled(False)
    sim.setBatchSize(batch)
    return sim


def _approx_angle(value: float, deg: float) -> bool:
    return abs(math.remainder(value - math.radians(deg), 2 * math.pi)) < 1e-6


def test_continuous_motion(conn):
    sim = _sim(conn, len(SCANS))
    assert sim.setElevationLimits(math.radians(-40), math.radians(50))
    sim.initialize()
    sim.newEpisode(SCANS, VIEWPOINTS, [math.radians(HEADING[0])] * 2, [math.radians(10)] * 2)
    for t in range(10):
        for i, state in enumerate(sim.getState()):
            assert state.scanId == SCANS[i]
            assert state.step == t
            assert state.heading == pytest.approx(math.radians(HEADING[t]))
            assert 0.0 <= state.heading < 2 * math.pi
            assert state.elevation == pytest.approx(math.radians(ELEVATION[t]))
            assert state.rgb.shape == (100, 200, 3)
            assert state.location.viewpointId == VIEWPOINTS[i]
            assert state.viewIndex == 0
        # Index 0 (stay), as MatterSim's test effectively does, so the location is fixed.
        chg = [math.radians(HEADING_CHG[t])] * 2
        sim.makeAction([0, 0], chg, [math.radians(ELEVATION_CHG[t])] * 2)
    sim.close()


def test_discrete_motion(conn):
    sim = _sim(conn, len(SCANS))
    sim.setDiscretizedViewingAngles(True)
    assert sim.setElevationLimits(math.radians(-10), math.radians(10))  # disregarded
    sim.initialize()
    sim.newEpisode(SCANS, VIEWPOINTS, [math.radians(HEADING[0])] * 2, [math.radians(10)] * 2)
    for t in range(10):
        for i, state in enumerate(sim.getState()):
            assert state.step == t
            assert _approx_angle(state.heading, DISCRETE_HEADING[t])
            assert state.elevation == pytest.approx(math.radians(DISCRETE_ELEVATION[t]))
            assert state.location.viewpointId == VIEWPOINTS[i]
            assert state.viewIndex == VIEW_INDEX[t]
        chg = [math.radians(HEADING_CHG[t])] * 2
        sim.makeAction([0, 0], chg, [math.radians(ELEVATION_CHG[t])] * 2)


def test_robot_relative_coords_while_moving(conn):
    sim = _sim(conn, len(SCANS))
    assert sim.setElevationLimits(math.radians(-40), math.radians(50))
    sim.newEpisode(SCANS, VIEWPOINTS, [math.radians(HEADING[0])] * 2, [math.radians(10)] * 2)
    visited = [set(), set()]
    for t in range(10):
        ix = []
        for i, state in enumerate(sim.getState()):
            visited[i].add(state.location.viewpointId)
            loc = state.location
            assert (loc.rel_heading, loc.rel_elevation, loc.rel_distance) == (0, 0, 0)
            assert state.navigableLocations[0].viewpointId == loc.viewpointId
            last = 0.0
            for cand in state.navigableLocations[1:]:
                angle = math.hypot(cand.rel_heading, cand.rel_elevation)
                assert angle >= last
                last = angle
                h = state.heading + cand.rel_heading
                e = state.elevation + cand.rel_elevation
                d = cand.rel_distance
                assert cand.x == pytest.approx(loc.x + math.sin(h) * math.cos(e) * d, abs=1e-5)
                assert cand.y == pytest.approx(loc.y + math.cos(h) * math.cos(e) * d, abs=1e-5)
                assert cand.z == pytest.approx(loc.z + math.sin(e) * d, abs=1e-5)
            ix.append(t % len(state.navigableLocations))
        chg = [math.radians(HEADING_CHG[t])] * 2
        sim.makeAction(ix, chg, [math.radians(ELEVATION_CHG[t])] * 2)
    assert all(len(v) > 1 for v in visited)  # the agents really moved


def test_navigable_locations_all_scans(conn):
    scans = (conn / "scans.txt").read_text().split()
    assert len(scans) == 90
    graphs = [json.loads((conn / f"{s}_connectivity.json").read_text()) for s in scans]
    sim = _sim(conn, len(scans), 20, 20, 90)
    half_hfov = math.pi / 4
    sim.setSeed(1)
    sim.initialize()
    sim.newRandomEpisode(scans)
    moves = 0
    for t in range(10):
        ix = []
        for k, state in enumerate(sim.getState()):
            root = graphs[k]
            assert state.scanId == scans[k]
            assert state.step == t
            locs = {v.viewpointId: v for v in state.navigableLocations}
            assert len(locs) == len(state.navigableLocations)
            current = next(v for v in root if v["image_id"] == state.location.viewpointId)
            assert current["included"]
            x, y = current["pose"][3], current["pose"][7]
            count = 0
            for i, target in enumerate(root):
                tid, pose = target["image_id"], target["pose"]
                if tid == current["image_id"]:
                    assert tid in locs
                    got = locs[tid]
                    assert (got.x, got.y, got.z) == pytest.approx((pose[3], pose[7], pose[11]))
                    count += 1
                elif not current["unobstructed"][i] or not target["included"]:
                    assert tid not in locs
                else:
                    bearing = math.pi / 2 - math.atan2(pose[7] - y, pose[3] - x)
                    diff = abs(math.remainder(state.heading - bearing, 2 * math.pi))
                    if abs(diff - half_hfov) < 1e-9:
                        count += tid in locs  # on the edge of the view: either is right
                    elif diff <= half_hfov:
                        assert tid in locs, f"{tid} within ±45° but not navigable"
                        got = locs[tid]
                        assert (got.x, got.y, got.z) == pytest.approx((pose[3], pose[7], pose[11]))
                        count += 1
                    else:
                        assert tid not in locs, f"{tid} outside ±45° but navigable"
            assert count == len(state.navigableLocations)
            ix.append(t % len(state.navigableLocations))
            moves += ix[-1] > 0
        sim.makeAction(ix, [math.radians(HEADING_CHG[t])] * 90, [0.0] * 90)
    assert moves > 100


def test_feature_extraction_sweep(conn):
    """36 views: start looking down at heading 0, turn right, look up at steps 12 and 24."""
    sim = _sim(conn, 1, 640, 480, 60)
    sim.setDiscretizedViewingAngles(True)
    sim.newEpisode([SCANS[1]], [VIEWPOINTS[1]], [0.0], [math.radians(-30)])
    for ix in range(36):
        if ix == 0:
            pass
        elif ix % 12 == 0:
            sim.makeAction([0], [1.0], [1.0])
        else:
            sim.makeAction([0], [1.0], [0.0])
        state = sim.getState()[0]
        assert state.viewIndex == ix
        assert _approx_angle(state.heading, 30 * (ix % 12))
        assert state.elevation == pytest.approx(math.radians(30 * (ix // 12 - 1)))


def _follow(sim, item) -> list[str]:
    """A MatterSim-style teacher: turn toward the next viewpoint until it is navigable."""
    sim.newEpisode([item["scan"]], [item["path"][0]], [item["heading"]], [0.0])
    visited = [sim.getState()[0].location.viewpointId]
    for nxt in item["path"][1:]:
        for _ in range(12):
            state = sim.getState()[0]
            ids = [v.viewpointId for v in state.navigableLocations]
            if nxt in ids:
                sim.makeAction([ids.index(nxt)], [0.0], [0.0])
                break
            sim.makeAction([0], [1.0], [0.0])  # one 30° step right
        visited.append(sim.getState()[0].location.viewpointId)
    return visited


@pytest.mark.parametrize("split", ["r2r/R2R_val_seen", "r2r/R2R_train", "ha_r2r/HA_val_seen"])
def test_every_r2r_path_is_followable(conn, shared_data, split):
    data = json.loads((shared_data / f"{split}.json").read_text())
    sim = _sim(conn, 1, 640, 480, 60)
    sim.setDiscretizedViewingAngles(True)
    sim.initialize()
    bad = [item["path_id"] for item in data if _follow(sim, item) != item["path"]]
    assert not bad, f"{len(bad)} of {len(data)} paths could not be followed: {bad[:10]}"
    assert len(data) in (340, 4675)


def test_a_real_scan_renders_through_its_graph_proxy(conn):
    sim = _sim(conn, 1, 32, 24, 60)
    sim.setRenderingEnabled(True)
    sim.setDepthEnabled(True)
    sim.newRandomEpisode(["gZ6f7yhEvPG"])  # the smallest graph
    state = sim.getState()[0]
    assert state.rgb.shape == (24, 32, 3) and state.rgb.any()
    assert (state.depth > 0).mean() > 0.5
    sim.close()
