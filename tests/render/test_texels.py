"""Texture sizes fitted to the camera: densities, the halving rule, the box filter."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from havln_mj.errors import InvalidArgumentError
from havln_mj.render.texels import (
    MIN_SIZE,
    REACH_M,
    halvings,
    resolved_density,
    shrink,
    surface_areas,
)
from havln_mj.scene.mesh import MeshPart
from havln_mj.sim.visual import add_visual_parts
from havln_mj.sim.world import WorldOptions

# A 2 m square whose texture repeats twice each way: 4 UV units² on 4 m².
SQUARE = np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]], dtype=float)
FACES = np.array([[0, 1, 2], [0, 2, 3]])
UV = np.array([[0, 0], [2, 0], [2, 2], [0, 2]], dtype=float)


def test_resolved_density_is_rows_over_the_view_height_at_the_reach():
    # 480 rows over 2·tan(30°)·1.5 m of view height.
    assert resolved_density(480, 60.0, 1.5) == pytest.approx(
        480 / (2 * math.tan(math.pi / 6) * 1.5)
    )
    assert resolved_density(480, 60.0) == resolved_density(480, 60.0, REACH_M)
    assert resolved_density(960, 60.0) == pytest.approx(2 * resolved_density(480, 60.0))


def test_surface_areas_count_texture_repeats():
    uv_area, area = surface_areas(SQUARE, FACES, UV)
    assert uv_area == pytest.approx(4.0) and area == pytest.approx(4.0)
    assert surface_areas(SQUARE, FACES[:0], UV) == (0.0, 0.0)


def test_a_texture_is_halved_until_it_is_no_finer_than_the_limit():
    # 256 texels per repeat, one repeat per metre: 256 texels/m.
    assert halvings((256, 256, 3), 4.0, 4.0, 300.0) == 0
    assert halvings((256, 256, 3), 4.0, 4.0, 256.0) == 0
    assert halvings((256, 256, 3), 4.0, 4.0, 255.0) == 1
    assert halvings((256, 256, 3), 4.0, 4.0, 64.0) == 2
    assert halvings((256, 256, 3), 4.0, 4.0, None) == 0
    assert halvings((256, 256, 3), 0.0, 4.0, 1.0) == 0  # no texture-space area
    # Never below MIN_SIZE on the shorter side.
    assert halvings((4 * MIN_SIZE, 64 * MIN_SIZE, 3), 4.0, 4.0, 1e-3) == 2


def test_shrink_is_a_rounded_two_by_two_box_filter():
    image = np.array([[[0], [1], [10]], [[2], [4], [20]], [[9], [9], [9]]], dtype=np.uint8)
    out = shrink(image, 1)  # the odd last row and column are dropped
    assert out.shape == (1, 1, 1) and out.dtype == np.uint8
    assert out[0, 0, 0] == 2  # (0 + 1 + 2 + 4) / 4 = 1.75, rounded
    big = np.random.default_rng(0).integers(0, 256, (64, 32, 3), dtype=np.uint8)
    assert shrink(big, 0) is big
    assert shrink(big, 2).shape == (16, 8, 3)
    np.testing.assert_allclose(shrink(big, 2).mean(), big.mean(), atol=1.0)


def _texture_side(limit: float | None, size: int = 256) -> int:
    image = np.zeros((size, size, 3), dtype=np.uint8)
    part = MeshPart("floor", SQUARE, FACES, (1, 1, 1, 1), UV, image)
    spec = mujoco.MjSpec()
    add_visual_parts(spec, [part], texel_limit=limit)
    return int(spec.compile().tex_width[0])


def test_world_textures_finer_than_the_camera_resolves_are_halved():
    assert _texture_side(None) == 256
    assert _texture_side(1000.0) == 256
    assert _texture_side(200.0) == 128
    assert _texture_side(100.0) == 64


def test_world_options_give_the_limit_of_their_frame():
    assert WorldOptions().texel_limit() == pytest.approx(resolved_density(480, 60.0))
    assert WorldOptions(offscreen=(1280, 960)).texel_limit() == pytest.approx(
        2 * WorldOptions().texel_limit()
    )
    assert WorldOptions(texel_reach_m=None).texel_limit() is None
    with pytest.raises(InvalidArgumentError, match="texel_reach_m"):
        WorldOptions(texel_reach_m=0.0)
