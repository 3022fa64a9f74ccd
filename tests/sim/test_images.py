"""State images in MatterSim's formats."""

from __future__ import annotations

import numpy as np

from havln_mj.sim.frame import ViewSettings
from havln_mj.sim.images import ImageFormat, depth_to_mattersim


def test_depth_in_quarter_millimetres_reads_zero_out_of_range():
    depth = np.array([[0.0, 0.00012, 1.0, 16.38375, 16.384, 30.0]], np.float32)
    units = depth_to_mattersim(depth)
    assert units.dtype == np.uint16 and units.shape == (1, 6, 1)
    assert units[0, :, 0].tolist() == [0, 0, 4000, 65535, 0, 0]
    rng = np.random.default_rng(0)
    wide = rng.uniform(0.0, 25.0, (48, 64)).astype(np.float32)
    expected = np.rint(wide * 4000.0)
    expected[expected > 65535] = 0
    np.testing.assert_array_equal(depth_to_mattersim(wide)[..., 0], expected.astype(np.uint16))


def test_a_bgr_format_asks_the_renderer_for_bgr_colour():
    settings = ViewSettings(64, 48, 1.0, depth=True)
    assert ImageFormat("BGR", "mattersim").settings(settings) == ViewSettings(
        64, 48, 1.0, depth=True, bgr=True
    )
    assert ImageFormat("RGB", "metres").settings(settings) is settings
