"""Rooms a camera cannot see are left out of its frames, and the frames stay the same."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from havln_mj.frames import camera_quat
from havln_mj.render.culling import RoomCulling, rooms_tag, view_wedge
from havln_mj.robot.point_body import PointBody
from havln_mj.scene.boxes import BoxSet
from havln_mj.scene.regions import Level, Region, Regions
from havln_mj.scene.rooms import FULL, RoomPlan, room_plan
from havln_mj.scene.scan import load_scan
from havln_mj.sim.frame import Frames, ViewSettings
from havln_mj.sim.world import WorldOptions, build_world
from havln_mj.tasks.procedural import scene_crowd


def _xmat(heading: float, elevation: float) -> np.ndarray:
    """The camera orientation the point body gives (heading 0 faces +y, turning right)."""
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, camera_quat(heading, elevation))
    return mat


def test_a_level_view_spans_its_horizontal_field_of_view():
    centre, half = view_wedge(_xmat(0.0, 0.0), math.radians(60), 4 / 3)
    assert centre == pytest.approx(math.pi / 2)  # heading 0 faces +y
    hfov = 2 * math.atan(math.tan(math.radians(30)) * 4 / 3)
    assert half == pytest.approx(hfov / 2, abs=1e-6)
    centre, _ = view_wedge(_xmat(math.pi / 2, 0.0), math.radians(60), 4 / 3)
    assert centre == pytest.approx(0.0, abs=1e-9)  # heading π/2 faces +x


def test_a_tilted_view_spans_more_and_a_view_down_spans_all():
    _, level = view_wedge(_xmat(0.0, 0.0), math.radians(60), 4 / 3)
    _, tilted = view_wedge(_xmat(0.0, -0.9), math.radians(60), 4 / 3)
    assert level < tilted < math.pi / 2
    assert view_wedge(_xmat(0.0, -1.3), math.radians(60), 4 / 3) == FULL  # holds straight down
    assert view_wedge(_xmat(0.0, 1.3), math.radians(60), 4 / 3) == FULL  # and straight up
    _, wide = view_wedge(_xmat(0.0, 0.0), math.radians(150), 2.0)  # as wide as it gets, level
    assert math.pi / 2 - wide < 0.2


def test_every_ray_of_a_turned_rolled_tilted_view_lies_in_its_wedge():
    rng = np.random.default_rng(0)
    u, v = np.meshgrid(np.linspace(-1, 1, 21), np.linspace(-1, 1, 21))
    for _ in range(300):
        quat = rng.normal(size=4)
        quat /= np.linalg.norm(quat)
        mat = np.zeros(9)
        mujoco.mju_quat2Mat(mat, quat)
        vfov, aspect = rng.uniform(0.3, 2.0), rng.uniform(0.5, 2.5)
        wedge = view_wedge(mat, vfov, aspect)
        if wedge == FULL:
            continue
        centre, half = wedge
        assert half < math.pi / 2
        tan_v = math.tan(vfov / 2)
        rays = np.stack([u.ravel() * tan_v * aspect, v.ravel() * tan_v, -np.ones(u.size)])
        world = mat.reshape(3, 3) @ rays
        off = np.remainder(np.arctan2(world[1], world[0]) - centre + math.pi, math.tau) - math.pi
        assert np.all(np.abs(off) <= half + 1e-9)


def _two_rooms_model() -> tuple[mujoco.MjModel, RoomPlan]:
    """Rooms x 0–4 and 4–8 (y 0–4), a wall at x = 4 with a door at y 1.5–2.5; a box in each."""
    rects = [(0.0, 0.0, 4.0, 4.0), (4.0, 0.0, 8.0, 4.0)]
    regions = Regions(
        (Level(0, 0.0, 2.5),),
        tuple(
            Region(k, 0, "b", np.array([[a, b], [c, b], [c, d], [a, d]]), np.zeros(6), 2.5)
            for k, (a, b, c, d) in enumerate(rects)
        ),
    )
    walls = BoxSet(
        np.array([[4.0, 0.0, 0.0], [4.0, 2.5, 0.0]]),
        np.array([[4.1, 1.5, 2.5], [4.1, 4.0, 2.5]]),
        ("wall", "wall"),
        ("paint", "paint"),
        np.ones((2, 4)),
    )
    spec = mujoco.MjSpec()
    box = mujoco.mjtGeom.mjGEOM_BOX
    spec.worldbody.add_geom(name="visual/0_a" + rooms_tag((0,)), type=box, size=[0.2] * 3)
    spec.worldbody.add_geom(name="visual/1_b" + rooms_tag((1,)), type=box, size=[0.2] * 3)
    cam = spec.worldbody.add_body(name="rig", mocap=True)
    cam.add_camera(name="cam")
    return spec.compile(), room_plan(regions, walls)


def test_walled_spheres_are_those_wholly_in_unseen_rooms():
    model, plan = _two_rooms_model()
    data = mujoco.MjData(model)
    culling = RoomCulling(model, plan)
    assert culling.n_geoms == 2
    data.mocap_pos[0] = (2.0, 0.5, 1.5)  # in room 0, facing the wall beside the door (+x)
    data.mocap_quat[0] = camera_quat(math.pi / 2, 0.0)
    mujoco.mj_kinematics(model, data)
    mujoco.mj_camlight(model, data)
    assert culling.walled(np.zeros((1, 3)), np.ones(1)) is None  # before any frame
    assert culling.hide_unseen(data, 0, math.radians(20), 1.0)
    np.testing.assert_array_equal(model.geom_rgba[:, 3], [1.0, 0.0])  # room 1's box hidden
    centres = np.array([[2.0, 2.0, 1.0], [6.0, 2.0, 1.0], [3.9, 2.0, 1.0], [-3.0, 2.0, 1.0]])
    radii = np.array([0.3, 0.3, 0.3, 0.3])  # in 0, in 1, across the door, outdoors
    np.testing.assert_array_equal(culling.walled(centres, radii), [False, True, False, False])
    culling.show_all()
    np.testing.assert_array_equal(model.geom_rgba[:, 3], [1.0, 1.0])
    data.mocap_pos[0] = (2.0, 2.0, 3.0)  # above the storey: it cannot tell
    mujoco.mj_kinematics(model, data)
    mujoco.mj_camlight(model, data)
    assert not culling.hide_unseen(data, 0, math.radians(20), 1.0)
    assert culling.walled(centres, radii) is None


def test_rooms_tag_names_the_rooms():
    assert rooms_tag((2, 5)) == "__rooms_2.5"
    assert rooms_tag(()) == ""


@pytest.mark.parametrize(
    ("scene", "style"), [("proc-0", "pieces"), ("proc-4", "pieces"), ("proc-1", "skinned")]
)
def test_frames_are_the_same_with_hidden_rooms_left_out(scene, style):
    scan = load_scan(scene)
    crowd = scene_crowd(scan, 0)
    model = build_world(scan, WorldOptions(people_style=style), crowd.shapes, crowd.skins).model
    data = mujoco.MjData(model)
    culled = Frames(model, crowd, style, rooms=scan.room_plan)
    whole = Frames(model, crowd, style)
    rooms = culled._rooms
    assert rooms.n_geoms > 0 and len(crowd.shapes) > 0
    settings = ViewSettings(96, 72, math.radians(60), depth=True, human_mask=True)
    rng = np.random.default_rng(0)
    lo, hi = scan.room_plan.rects[:, :2].min(axis=0), scan.room_plan.rects[:, 2:].max(axis=0)
    rig = PointBody(np.zeros(3))
    counts = {"rooms": 0, "people": 0}
    hide, walled = rooms.hide_unseen, rooms.walled

    def hiding(*args):
        out = hide(*args)
        counts["rooms"] += out
        return out

    def walling(*args):
        out = walled(*args)
        counts["people"] += out is not None and bool(out.any())
        return out

    rooms.hide_unseen, rooms.walled = hiding, walling
    views, seen_people = 30, 0
    for k in range(views):
        t = 4.0 * k
        heading = rng.uniform(0.0, 2 * math.pi)
        if k % 3 == 1:  # anywhere in the house, looking anywhere
            at = np.array([*rng.uniform(lo, hi), rng.uniform(0.2, 2.7)])
        elif k % 3 == 2:  # 1.5 m from someone, facing them
            pelvis = crowd.pose(t)[0][k % len(crowd.shapes), 0]
            at = pelvis + np.array([1.5 * math.sin(heading), 1.5 * math.cos(heading), 0.4])
            heading += math.pi
        else:  # near a viewpoint
            at = np.array(scan.graph.position(scan.graph.nodes[k % scan.graph.num_nodes]))
            at[:2] += rng.normal(0.0, 0.3, 2)
        rig.set_pose(at, heading, rng.uniform(-0.6, 0.6) if k % 3 == 2 else rng.uniform(-1.2, 1.2))
        rig.write(model, data)
        a = culled.render(data, t, "agent_cam", settings)
        b = whole.render(data, t, "agent_cam", settings)
        np.testing.assert_array_equal(a.rgb, b.rgb)
        np.testing.assert_array_equal(a.depth, b.depth)
        np.testing.assert_array_equal(a.human_mask, b.human_mask)
        seen_people += int(b.human_mask.any())
    # Most views have a room behind a wall, and some have someone in it.
    assert counts["rooms"] >= views // 2 and counts["people"] > 0 and seen_people > 0
    # Afterwards every geom is drawn again.
    np.testing.assert_array_equal(model.geom_rgba[rooms._ids, 3], rooms._alpha)
    culled.close()
    whole.close()
