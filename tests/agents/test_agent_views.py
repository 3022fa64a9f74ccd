"""Views rendered through the simulator: the 36-view grid, time slots, pretraining targets."""

from __future__ import annotations

import math

import numpy as np
import pytest

import havln_mj as MatterSim  # noqa: N812 - MatterSim code, only the import changed
from havln_mj.agents.views import (
    REGION_CODES,
    ViewConfig,
    ViewRenderer,
    forward_possible,
    view_angles,
)
from havln_mj.errors import InvalidArgumentError
from havln_mj.sim.egocentric import EgoAction

SCAN = "proc-3"


def test_view_angles_follow_the_simulators_view_index():
    sim = MatterSim.Simulator()
    sim.setRenderingEnabled(False)
    sim.setDiscretizedViewingAngles(True)
    headings, elevations = view_angles()
    sim.newRandomEpisode([SCAN])
    vp = sim.getState()[0].location.viewpointId
    for k, (h, e) in enumerate(zip(headings, elevations, strict=True)):
        sim.newEpisode([SCAN], [vp], [float(h)], [float(e)])
        assert sim.getState()[0].viewIndex == k


def test_config_checks_and_time_slots():
    cfg = ViewConfig(slots=3, slot_seconds=5.0)
    assert [cfg.slot(t) for t in (0.0, 2.49, 2.5, 7.4, 7.6, 15.0)] == [0, 0, 1, 1, 2, 0]
    assert math.isclose(cfg.half_hfov, 0.8 * 64 / 48 / 2)
    assert cfg.key() == "64x48-v0.8-s3x5-rgbd"
    for bad in ({"width": 8}, {"vfov": 3.0}, {"slots": 0}, {"slot_seconds": float("nan")}):
        with pytest.raises(InvalidArgumentError):
            ViewConfig(**bad)


@pytest.fixture(scope="module")
def rendered():
    cfg = ViewConfig(width=32, height=24, slots=2, slot_seconds=3.0)
    with ViewRenderer(cfg, seed=0) as renderer:
        return cfg, renderer.viewpoints(SCAN), list(renderer.render(SCAN))


def test_every_view_and_slot_is_rendered_with_its_targets(rendered):
    _cfg, vps, views = rendered
    assert [v.viewpoint for v in views] == vps
    for v in views:
        assert v.rgb.shape == (36, 2, 24, 32, 3) and v.rgb.dtype == np.uint8
        assert v.depth.shape == (36, 2, 24, 32) and v.depth.dtype == np.float16
        assert v.person.shape == (36, 2) and ((v.person >= 0) & (v.person <= 1)).all()
        assert v.forward.shape == (36,) and -1 <= v.region < len(REGION_CODES)
        assert v.depth.max() > 0.5  # walls are in view
    assert all(v.region >= 0 for v in views)  # procedural viewpoints all lie in a room
    seen = [(v, k) for v in views for k in range(2) if v.person[:, k].max() > 0]
    assert seen, "nobody is seen from any viewpoint"
    # People move between the slots: the views that show them change.
    v = max(views, key=lambda v: v.person.max())
    i = int(np.argmax(v.person.max(axis=1)))
    assert not np.array_equal(v.rgb[i, 0], v.rgb[i, 1])


def test_forward_flag_is_the_simulators_forward(rendered):
    cfg, _vps, views = rendered
    sim = MatterSim.Simulator()
    sim.setRenderingEnabled(False)
    sim.setDiscretizedViewingAngles(True)
    sim.setCameraResolution(cfg.width, cfg.height)
    sim.setCameraVFOV(cfg.vfov)
    headings, _elevations = view_angles()
    for v in views[:4]:
        for k in range(12, 24):  # level views
            sim.newEpisode([SCAN], [v.viewpoint], [float(headings[k])], [0.0])
            state = sim.getState()[0]
            assert forward_possible(state, sim.half_hfov) == v.forward[k]
            sim.makeEgoAction([EgoAction.FORWARD])
            moved = sim.getState()[0].location.viewpointId != v.viewpoint
            assert moved == v.forward[k]
