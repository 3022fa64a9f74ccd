"""Skybox mode: the cube-map sampler against MatterSim's own pipeline, faces rendered from
the mesh, and people composited only where they are nearer than the scene."""

from __future__ import annotations

import logging
import math

import cv2
import mujoco
import numpy as np
import pytest

from havln_mj import groups
from havln_mj.errors import MissingDataError
from havln_mj.render.camera import Camera
from havln_mj.render.cubemap import GL_FACES, render_faces
from havln_mj.render.labels import label_people
from havln_mj.render.skybox import (
    DEPTH_UNITS_PER_M,
    Skybox,
    SkyboxSource,
    load_skybox,
    render_skybox_frame,
    skybox_view,
)
from havln_mj.robot.point_body import CAMERA, PointBody
from havln_mj.scene.scan import load_scan
from havln_mj.sim.world import build_world

S = 32  # face size of the coded skyboxes


def coded_skybox() -> Skybox:
    """Each texel stores its own address: R = face·40 + 20, G = column·8, B = row·8."""
    rgb = np.zeros((6, S, S, 3), np.uint8)
    for k in range(6):
        rgb[k, ..., 0] = 40 * k + 20
        rgb[k, ..., 1] = (np.arange(S) * 8)[None, :]
        rgb[k, ..., 2] = (np.arange(S) * 8)[:, None]
    return Skybox(rgb, None)


def decode(rgb: np.ndarray) -> np.ndarray:
    """(face, row, column) of each pixel of a view of :func:`coded_skybox`."""
    rgb = rgb.astype(int)
    return np.stack([(rgb[..., 0] - 20) // 40, rgb[..., 2] // 8, rgb[..., 1] // 8], axis=-1)


# ---------------------------------------------------------------- MatterSim, literally


def _rot(angle: float, axis: int) -> np.ndarray:
    """glm::rotate's 3×3 matrix: counter-clockwise by ``angle`` about a coordinate axis."""
    c, s = math.cos(angle), math.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    m = np.eye(3)
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    return m


def mattersim_texels(pose: np.ndarray, heading, elevation, width, height, vfov) -> np.ndarray:
    """(face, row, column) MatterSim samples for each pixel of ``state.rgb`` (row 0 first).

    Its renderScene, written out: glm::perspective(vfov, W/H); Model = pose rotation (cube
    scale aside); View = rotate(rotate(I, -π/2 + elevation, x), π + heading, z); the cube's
    model coordinates are the cube-map lookup direction; glReadPixels returns rows bottom
    first, so row r of the array is the r-th row from the bottom of the viewport.
    """
    rot = pose[:3, :3]
    view = _rot(-math.pi / 2 + elevation, 0) @ _rot(math.pi + heading, 2)
    t = math.tan(vfov / 2)
    x = ((2 * np.arange(width) + 1) / width - 1) * t * width / height
    y = ((2 * np.arange(height) + 1) / height - 1) * t  # bottom row first
    eye = np.stack(np.broadcast_arrays(x[None, :], y[:, None], -1.0), axis=-1)
    cube = eye @ view @ rot  # rotᵀ viewᵀ e, for row vectors
    out = np.zeros((height, width, 3), int)
    axis = np.argmax(np.abs(cube), axis=-1)
    ma = np.take_along_axis(cube, axis[..., None], -1)[..., 0]
    for (ax, sign), (face, (sa, ss), (ta, ts)) in GL_FACES.items():
        sel = (axis == ax) & (np.sign(ma) == sign)
        s_ = (ss * cube[..., sa][sel] / abs(ma[sel]) + 1) / 2
        t_ = (ts * cube[..., ta][sel] / abs(ma[sel]) + 1) / 2
        out[sel] = np.column_stack(
            [
                np.full(sel.sum(), face),
                np.minimum(t_ * S, S - 1).astype(int),
                np.minimum(s_ * S, S - 1).astype(int),
            ]
        )
    return out


def _nearest(sky: Skybox) -> Skybox:
    """A skybox whose bilinear filter returns texel values exactly (each texel repeated 4×)."""
    return Skybox(np.repeat(np.repeat(sky.rgb, 4, axis=1), 4, axis=2), None)


def _pose(yaw: float) -> np.ndarray:
    """A connectivity pose: Matterport camera (x right, y down, z look) turned by ``yaw``."""
    look = np.array([math.sin(yaw), math.cos(yaw), 0.0])
    right = np.array([math.cos(yaw), -math.sin(yaw), 0.0])
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([right, [0.0, 0.0, -1.0], look])
    return pose


@pytest.mark.parametrize("yaw", [0.0, 0.7, 2.9])
def test_views_match_mattersims_pipeline_texel_for_texel(yaw):
    rng = np.random.default_rng(int(yaw * 10))
    pose = _pose(yaw)
    sky = coded_skybox()
    for _ in range(6):
        heading, elevation = rng.uniform(0, 2 * math.pi), rng.uniform(-0.9, 0.9)
        vfov = rng.uniform(0.5, 1.6)
        width, height = 40, 30
        rgb, _ = skybox_view(
            sky, pose[:3, :3], heading, elevation, width, height, math.degrees(vfov)
        )
        ours = decode(rgb)
        theirs = mattersim_texels(pose, heading, elevation, width, height, vfov)
        # Bilinear filtering may round to a neighbouring texel code; faces must agree.
        assert np.mean(ours[..., 0] == theirs[..., 0]) > 0.995
        agree = np.all(np.abs(ours - theirs) <= [0, 1, 1], axis=-1)
        assert agree.mean() > 0.99, agree.mean()


def test_headings_and_elevations_follow_mattersims_conventions():
    # The pose faces +y: heading 0 sees the centre of face 3 (the README's "camera faces
    # skybox image 3"); turning right by 90° at a time: faces 4, 1, 2; up face 0, down 5.
    pose = _pose(0.0)
    sky = _nearest(coded_skybox())
    for heading, elevation, face in (
        (0.0, 0.0, 3), (math.pi / 2, 0.0, 4), (math.pi, 0.0, 1), (3 * math.pi / 2, 0.0, 2),
        (0.0, 1.5, 0), (0.0, -1.5, 5),
    ):  # fmt: skip
        rgb, _ = skybox_view(sky, pose[:3, :3], heading, elevation, 9, 9, 30.0)
        f, row, col = decode(rgb)[4, 4]
        off = 1 if elevation == 0.0 else 2  # 1.5 rad is 4° short of straight up or down
        assert f == face and abs(row - S // 2) <= off and abs(col - S // 2) <= off
    # Upright: in the level view at heading 0 the top row is nearer face 0 (up) than the
    # bottom row is; the left column is to the left (toward face 2 at -x).
    rgb, _ = skybox_view(sky, pose[:3, :3], 0.0, 0.0, 9, 9, 60.0)
    codes = decode(rgb)
    assert codes[0, 4, 1] < codes[8, 4, 1]  # rows of face 3 grow downwards
    assert codes[4, 0, 2] < codes[4, 8, 2]


def test_depth_faces_read_planar_metres():
    # A sphere of radius 3 m: the view's planar depth is 3·cos of each pixel's angle.
    depth = np.full((6, S, S), 3.0, np.float32)
    sky = Skybox(coded_skybox().rgb, depth)
    _, planar = skybox_view(sky, np.eye(3), 0.3, 0.1, 20, 16, 60.0)
    assert planar.shape == (16, 20)
    assert abs(planar[8, 10] - 3.0) < 0.05 and planar[0, 0] < planar[8, 10]
    t = math.tan(math.radians(30))
    corner = 3.0 / math.sqrt(1 + (t * (19 / 20) * 20 / 16) ** 2 + (t * 15 / 16) ** 2)
    assert abs(planar[0, 0] - corner) < 1e-3


# ---------------------------------------------------------------- files


def test_skybox_files_load_in_both_layouts(tmp_path):
    faces = coded_skybox().rgb[..., ::-1]  # BGR on disk, as cv2 writes
    strip = np.concatenate(list(faces), axis=1)
    cv2.imwrite(str(tmp_path / "vp_skybox_small.jpg"), strip, [cv2.IMWRITE_JPEG_QUALITY, 100])
    depth = np.full((S, 6 * S), int(2.5 * DEPTH_UNITS_PER_M), np.uint16)
    cv2.imwrite(str(tmp_path / "vp_skybox_depth_small.png"), depth)
    for k in range(6):
        big = np.repeat(np.repeat(faces[k], 2, 0), 2, 1)
        cv2.imwrite(
            str(tmp_path / f"other_skybox{k}_sami.jpg"), big, [cv2.IMWRITE_JPEG_QUALITY, 100]
        )
    small = load_skybox(tmp_path, "vp")
    big = load_skybox(tmp_path, "other", face_size=S)
    assert small.rgb.shape == big.rgb.shape == (6, S, S, 3)
    assert np.abs(small.rgb.astype(int) - coded_skybox().rgb).mean() < 3
    assert np.abs(big.rgb.astype(int) - coded_skybox().rgb).mean() < 3
    assert small.depth is not None and np.allclose(small.depth, 2.5) and big.depth is None


def test_missing_skybox_files_are_named_and_the_source_falls_back(tmp_path, caplog):
    with pytest.raises(MissingDataError, match=r"gone_skybox_small\.jpg.*gone_skybox0_sami\.jpg"):
        load_skybox(tmp_path, "gone")
    folder = tmp_path / "v1" / "scans" / "scanA" / "matterport_skybox_images"
    folder.mkdir(parents=True)
    with pytest.raises(MissingDataError, match="scanB"):
        SkyboxSource("scanB", tmp_path)
    source = SkyboxSource("scanA", tmp_path)
    with caplog.at_level(logging.WARNING):
        assert source.get("gone") is None
    assert "gone_skybox_small.jpg" in caplog.text and "mesh instead" in caplog.text


# ---------------------------------------------------------------- rendering


def test_skybox_rendered_from_the_mesh_gives_back_the_camera_view():
    # Faces rendered in Matterport's layout, then viewed as MatterSim views them, look like
    # a direct render of the same view: the face geometry and the sampler are consistent.
    scan = load_scan("proc-2")
    model = build_world(scan).model
    # Flat ambient light: the headlight follows each camera, so shading would differ.
    model.light_active[:] = 0
    model.vis.headlight.ambient[:] = 1.0
    model.vis.headlight.diffuse[:] = 0.0
    model.vis.headlight.specular[:] = 0.0
    data = mujoco.MjData(model)
    graph = scan.graph
    vp = graph.nodes[3]
    pose = graph.connectivity.poses[graph.connectivity.ids.index(vp)]
    PointBody(graph.position(vp), heading=0.0).write(model, data)
    with Camera(model, CAMERA, 96, 96, geom_groups=groups.CAMERA_GROUPS) as square:
        faces = render_faces(model, data, square, graph.position(vp), pose[:3, :3])
    sky = Skybox(faces.rgb, faces.depth)
    with Camera(model, CAMERA, 64, 48, 60.0, geom_groups=groups.CAMERA_GROUPS) as cam:
        for heading, elevation in ((0.4, 0.0), (2.0, -0.3), (4.5, 0.3)):
            PointBody(graph.position(vp), heading=heading, elevation=elevation).write(model, data)
            direct = cam.render(data)
            rgb, depth = skybox_view(sky, pose[:3, :3], heading, elevation, 64, 48, 60.0)
            assert np.abs(rgb.astype(int) - direct.rgb.astype(int)).mean() < 6
            close = np.abs(depth - direct.depth) < 0.05 * direct.depth
            assert close.mean() > 0.9


def _room_with_a_person():
    """A wall hiding the left half of the view at 2 m, a red person at 3.5 m straight ahead."""
    spec = mujoco.MjSpec()
    spec.worldbody.add_geom(
        name="wall", type=mujoco.mjtGeom.mjGEOM_BOX, size=[1.0, 0.05, 2.0], pos=[-1.0, 2.0, 1.0],
        rgba=[0.8, 0.8, 0.8, 1], group=groups.VISUAL,
    )  # fmt: skip
    person = spec.worldbody.add_body(name="human0/pelvis", mocap=True, pos=[0.0, 3.5, 0.0])
    person.add_geom(
        type=mujoco.mjtGeom.mjGEOM_CAPSULE,
        size=[0.3, 0.7],
        pos=[0, 0, 1.0],
        rgba=[0.9, 0.1, 0.1, 1],
        group=groups.HUMANS,
        contype=0,
        conaffinity=0,
    )
    agent = spec.worldbody.add_body(name="agent", mocap=True, pos=[0.0, 0.0, 1.2])
    agent.add_camera(name=CAMERA)
    label_people(spec)
    model = spec.compile()
    data = mujoco.MjData(model)
    PointBody(np.array([0.0, 0.0, 1.2]), heading=0.0).write(model, data)
    return model, data


def test_a_person_covers_the_skybox_only_where_nearer_than_the_scene():
    model, data = _room_with_a_person()
    sky = Skybox(
        np.full((6, 8, 8, 3), (20, 40, 200), np.uint8), np.full((6, 8, 8), 9.0, np.float32)
    )
    with Camera(model, CAMERA, 64, 48, 60.0, geom_groups=groups.CAMERA_GROUPS) as cam:
        out = render_skybox_frame(model, data, cam, sky, np.eye(3))
        body = cam.render_geom_ids(data, geom_groups=(groups.HUMANS,)) >= 0  # unoccluded
        wall = cam.render_geom_ids(data, geom_groups=(groups.VISUAL,)) >= 0
        frame = cam.render(data)
    assert body.sum() > 50 and (body & wall).sum() > 20 and (body & ~wall).sum() > 20
    np.testing.assert_array_equal(out.people, body & ~wall)
    np.testing.assert_array_equal(out.rgb[out.people], frame.rgb[out.people])
    assert np.all(out.rgb[out.people][:, 0] > out.rgb[out.people][:, 2])  # red, not sky blue
    np.testing.assert_array_equal(
        out.rgb[~out.people], np.broadcast_to((20, 40, 200), out.rgb[~out.people].shape)
    )
    assert np.allclose(out.depth[out.people], frame.depth[out.people])
    assert np.all(out.depth[~out.people] < 9.0 + 1e-4) and np.all(out.depth[~out.people] > 6.0)
