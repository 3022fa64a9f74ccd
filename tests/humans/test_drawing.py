"""People out of a camera's view are left out of its scene: the images do not change."""

from __future__ import annotations

import math

import numpy as np

import havln_mj as MatterSim  # noqa: N812 - MatterSim code, only the import changed
from havln_mj.humans.drawing import PeoplePoser


def _frames(monkeypatch, cull: bool) -> tuple[list, int]:
    hidden = []
    real = PeoplePoser.hide_unseen

    def counting(self, data, camera, aspect, walled=None):
        out = real(self, data, camera, aspect, walled) if cull else False
        hidden.append(out)
        return out

    monkeypatch.setattr(PeoplePoser, "hide_unseen", counting)
    sim = MatterSim.Simulator(humans=True)
    sim.setCameraResolution(96, 72)
    sim.setCameraVFOV(math.radians(60))
    sim.setDepthEnabled(True)
    sim.set_human_mask_enabled(True)
    sim.setSeed(3)
    frames = []
    rng = np.random.default_rng(0)
    for _ in range(6):
        sim.newRandomEpisode(["proc-0"])
        for _ in range(10):
            state = sim.getState()[0]
            frames.append((state.rgb.copy(), state.depth.copy(), state.humanMask.copy()))
            k = int(rng.integers(len(state.navigableLocations)))
            sim.makeAction([k], [float(rng.uniform(-2, 2))], [0.0])
    model = sim._kind.stage("proc-0", sim.people(0)).world.model
    alphas = model.geom_rgba[:, 3].copy()
    sim.close()
    return frames, sum(hidden), alphas


def test_leaving_out_people_out_of_view_changes_no_pixel(monkeypatch):
    culled, n_hidden, alphas = _frames(monkeypatch, cull=True)
    with monkeypatch.context() as m:
        full, _, alphas_full = _frames(m, cull=False)
    assert n_hidden > 5  # people were left out of many frames
    assert sum(mask.any() for _, _, mask in full) > 3  # and were seen in others
    for (rgb, depth, mask), (rgb0, depth0, mask0) in zip(culled, full, strict=True):
        np.testing.assert_array_equal(rgb, rgb0)
        np.testing.assert_array_equal(depth, depth0)
        np.testing.assert_array_equal(mask, mask0)
    np.testing.assert_array_equal(alphas, alphas_full)  # everyone is put back after a frame


def test_a_person_half_in_view_keeps_only_the_pieces_that_may_show(monkeypatch):
    halves = []
    real = PeoplePoser.hide_unseen

    def watching(self, data, camera, aspect, walled=None):
        out = real(self, data, camera, aspect, walled)
        shown = self.model.geom_rgba[self._geoms, 3] > 0
        for k in set(self._owner.tolist()):
            mine = shown[self._owner == k]
            halves.append(bool(mine.any() and not mine.all()))
        return out

    monkeypatch.setattr(PeoplePoser, "hide_unseen", watching)
    sim = MatterSim.Simulator(humans=True)
    sim.setCameraResolution(64, 48)
    sim.setSeed(3)
    rng = np.random.default_rng(0)
    for _ in range(3):
        sim.newRandomEpisode(["proc-0"])
        for _ in range(10):
            state = sim.getState()[0]
            k = int(rng.integers(len(state.navigableLocations)))
            sim.makeAction([k], [float(rng.uniform(-2, 2))], [0.0])
    sim.close()
    assert sum(halves) > 3  # people partly in view drew only part of their pieces
