"""Matterport heading / elevation conventions and the MuJoCo camera frame."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from havln_mj.frames import camera_quat, camera_xmat, forward, heading_to, wrap_angle, wrap_heading


def test_heading_zero_faces_plus_y_and_grows_to_the_right():
    np.testing.assert_allclose(forward(0.0), [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(forward(math.pi / 2), [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(
        forward(0.0, math.pi / 6), [0, math.cos(math.pi / 6), 0.5], atol=1e-12
    )
    assert heading_to(np.zeros(3), np.array([1.0, 0, 0])) == pytest.approx(math.pi / 2)
    assert heading_to(np.zeros(3), np.array([-1.0, 0, 0])) == pytest.approx(3 * math.pi / 2)


@pytest.mark.parametrize(
    ("value", "expected"),
    [
        (math.radians(10 - 20), math.radians(350)),
        (math.radians(350 + 371), math.radians(1)),
        (2 * math.pi, 0.0),
    ],
)
def test_wrap_heading_matches_mattersim(value, expected):
    assert wrap_heading(value) == pytest.approx(expected)
    assert 0.0 <= wrap_heading(value) < 2 * math.pi


def test_wrap_angle_range():
    assert wrap_angle(math.pi) == pytest.approx(math.pi)
    assert wrap_angle(-math.pi) == pytest.approx(math.pi)
    assert wrap_angle(3 * math.pi / 2) == pytest.approx(-math.pi / 2)


@pytest.mark.parametrize(("h", "e"), [(0.0, 0.0), (1.0, 0.3), (4.0, -0.5), (math.pi, 0.9)])
def test_camera_frame_looks_along_forward(h, e):
    m = camera_xmat(h, e)
    np.testing.assert_allclose(m @ m.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(m) == pytest.approx(1.0)
    np.testing.assert_allclose(-m[:, 2], forward(h, e), atol=1e-12)  # MuJoCo cameras look along -z
    assert m[2, 1] >= 0  # image up points up
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, camera_quat(h, e))
    np.testing.assert_allclose(mat.reshape(3, 3), m, atol=1e-9)
