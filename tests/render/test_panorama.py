"""360° panoramas: directions, and depth and labels that agree with rays into the scene."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from havln_mj import groups
from havln_mj.errors import InvalidArgumentError
from havln_mj.render.camera import Camera
from havln_mj.render.labels import geom_labels, segmentation_groups
from havln_mj.render.panorama import panorama_directions, render_panorama
from havln_mj.robot.point_body import CAMERA, PointBody
from havln_mj.scene.scan import load_scan
from havln_mj.sim.world import build_world


def test_panorama_directions_follow_heading_and_elevation():
    d = panorama_directions(8, heading=1.0)
    assert d.shape == (8, 16, 3)
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1.0)
    centre = d[4, 8]  # just right of the centre column, just below the horizon
    assert abs(math.atan2(centre[0], centre[1]) - (1.0 + math.pi / 16)) < 1e-9
    assert d[0, 0, 2] > 0.98 and d[-1, 0, 2] < -0.98  # top row up, bottom row down
    yaw = np.arctan2(d[4, :, 0], d[4, :, 1])
    assert np.all(np.diff(np.unwrap(yaw)) > 0)  # left to right turns right


def test_panorama_depth_and_labels_agree_with_rays():
    scan = load_scan("proc-1")
    model = build_world(scan).model
    data = mujoco.MjData(model)
    graph = scan.graph
    eye = graph.position(graph.nodes[2])
    PointBody(eye, heading=0.0).write(model, data)
    before = data.cam_xmat.copy()
    with Camera(model, CAMERA, 96, 96, geom_groups=groups.CAMERA_GROUPS) as cam:
        pano = render_panorama(model, data, cam, eye, height=48, heading=0.3)
        assert cam.vfov == 60.0  # restored
    np.testing.assert_array_equal(data.cam_xmat, before)  # the caller's state is untouched
    assert pano.rgb.shape == (48, 96, 3) and pano.depth.shape == (48, 96)
    assert pano.semantic.shape == pano.instance.shape == (48, 96)
    semantic, instance = geom_labels(model)
    visual = np.zeros(mujoco.mjNGROUP, np.uint8)
    visual[groups.VISUAL] = 1
    labelled = np.zeros(mujoco.mjNGROUP, np.uint8)
    labelled[list(segmentation_groups(model))] = 1
    dirs = panorama_directions(48, heading=0.3)
    geom = np.zeros(1, np.int32)
    depth_ok = label_ok = total = 0
    for row in range(4, 44, 3):
        for col in range(0, 96, 3):
            if np.any(
                pano.instance[row - 1 : row + 2, max(col - 1, 0) : col + 2]
                != pano.instance[row, col]
            ):
                continue
            total += 1
            dist = mujoco.mj_ray(model, data, eye, dirs[row, col], visual, 1, -1, geom)
            depth_ok += abs(pano.depth[row, col] - dist) < 0.03 * dist + 0.01
            mujoco.mj_ray(model, data, eye, dirs[row, col], labelled, 1, -1, geom)
            label_ok += (semantic[geom[0]], instance[geom[0]]) == (
                pano.semantic[row, col],
                pano.instance[row, col],
            )
    assert total > 200
    assert depth_ok / total > 0.97 and label_ok / total > 0.97


def test_panorama_needs_a_square_camera_and_a_height():
    scan = load_scan("proc-1")
    model = build_world(scan).model
    data = mujoco.MjData(model)
    with Camera(model, CAMERA, 32, 24) as cam, pytest.raises(InvalidArgumentError, match="square"):
        render_panorama(model, data, cam, np.zeros(3), height=16)
    with Camera(model, CAMERA, 32, 32) as cam, pytest.raises(InvalidArgumentError, match="height"):
        render_panorama(model, data, cam, np.zeros(3), height=0)
