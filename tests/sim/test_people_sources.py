"""Where a scan's people come from, and no real building silently left empty."""

from __future__ import annotations

import numpy as np
import pytest

from havln_mj.errors import InvalidArgumentError, MissingDataError
from havln_mj.scene.scan import scans_dir
from havln_mj.sim.people import PinnedCrowd
from havln_mj.sim.simulator import Simulator

SCAN = "17DRP5sb8fy"


def _cached(scan):
    """The cached scan folder's files and their times (empty when none is cached)."""
    folder = scans_dir() / scan
    return {p: p.stat().st_mtime_ns for p in folder.rglob("*")} if folder.is_dir() else {}


def _sim(shared_data, **kw):
    sim = Simulator(humans=True, **kw)
    sim.setNavGraphPath(str(shared_data / "mp3d_connectivity"))
    sim.setRenderingEnabled(False)
    return sim


def test_a_real_scan_without_placements_or_regions_is_an_error(shared_data, monkeypatch):
    monkeypatch.delenv("HAVLN_HA3D_PLACEMENTS", raising=False)
    monkeypatch.delenv("HAVLN_MP3D_DIR", raising=False)
    before = _cached(SCAN)
    sim = _sim(shared_data)
    with pytest.raises(MissingDataError, match="human_placements") as err:
        sim.newEpisode([SCAN], [""], [0.0], [0.0])
    assert "--human-placements" in str(err.value) and "humans=False" in str(err.value)
    with pytest.raises(MissingDataError):
        sim.people_source(SCAN)
    assert _cached(SCAN) == before  # no graph proxy was built to find that out


def test_placements_say_where_people_come_from(shared_data):
    placements = shared_data / "ha3d" / "human_placements.json"
    sim = _sim(shared_data, human_placements=placements)
    assert len(sim.crowd(SCAN)) > 0
    assert sim.people_source(SCAN) == f"HA3D placements ({placements})"
    assert "HA3D's rule" in sim.people_source("proc-0")
    assert Simulator(humans=False).people_source("proc-0") == "none (humans=False)"


def test_pinned_people_stay_on_their_floor_points(shared_data):
    placements = shared_data / "ha3d" / "human_placements.json"
    sim = _sim(shared_data, human_placements=placements, pinned_people=True)
    crowd = sim.crowd(SCAN)
    assert isinstance(crowd, PinnedCrowd)
    anchors = np.array([p.anchor[:2] for p in crowd.people])
    track = crowd.positions(np.linspace(0.0, 30.0, 61))
    assert np.allclose(track[..., :2], anchors)
    joints, _ = crowd.pose(7.3)
    assert np.allclose(joints[:, 0, :2], anchors)  # joint 0: the pelvis
    assert all(np.allclose(s.velocity[:2], 0.0) for s in crowd.states(7.3))
    with pytest.raises(InvalidArgumentError, match="react"):
        Simulator(humans=True, pinned_people=True, reactions=True)
