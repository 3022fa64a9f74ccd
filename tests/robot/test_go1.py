"""GO1 model, trot controller and navigation primitives."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import mujoco
import numpy as np
import pytest

from havln_mj import groups
from havln_mj.errors import InvalidArgumentError, MalformedDataError, MissingDataError
from havln_mj.frames import heading_to
from havln_mj.paths import asset_path
from havln_mj.robot.go1 import Go1Body, Go1Gains, add_go1, flat_floor_spec, load_gains
from havln_mj.robot.go1 import constants as const
from havln_mj.robot.go1.commands import ForwardCommand
from havln_mj.robot.go1.kinematics import leg_fk, leg_ik


def _robot(estimate: str = "truth", heading: float = 0.0, **kw) -> Go1Body:
    spec = flat_floor_spec()
    add_go1(spec, **kw)
    model = spec.compile()
    body = Go1Body(model, mujoco.MjData(model), estimate=estimate)
    body.reset(0.0, 0.0, 0.0, heading, settle=0.5)
    return body


def test_model_facts() -> None:
    spec = flat_floor_spec()
    h = add_go1(spec, (1.0, 2.0, 0.0), 0.3)
    m = spec.compile()
    robot_bodies = [i for i in range(m.nbody) if m.body(i).name.startswith("go1/")]
    assert sum(m.body_mass[robot_bodies]) == pytest.approx(const.TOTAL_MASS, abs=0.01)
    assert m.nu == 12 and m.opt.timestep == pytest.approx(0.002)
    assert m.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC and m.opt.impratio == 100
    assert [m.actuator(i).name for i in range(m.nu)] == list(h.actuators)
    assert m.actuator(h.prefix + "FR_calf").forcerange[1] == pytest.approx(35.55)
    assert m.actuator(h.prefix + "FR_hip").gainprm[0] == pytest.approx(100)
    for g in range(m.ngeom):
        if not m.geom(g).name.startswith("go1/") and m.geom_bodyid[g] not in robot_bodies:
            continue
        if m.geom_group[g] == groups.ROBOT:
            assert m.geom_contype[g] == 0 and m.geom_conaffinity[g] == 0
        else:
            assert m.geom_group[g] == groups.COLLISION
    foot = m.geom(h.feet[0])
    assert foot.size[0] == pytest.approx(0.023) and foot.condim[0] == 6 and foot.priority[0] == 1
    assert m.site(h.imu) is not None


def test_stands_and_camera_looks_forward() -> None:
    body = _robot(heading=0.7)
    body.stand(1.0)
    m, d = body.model, body.data
    p = body.true_pose()
    assert 0.24 <= p.z <= 0.30
    assert d.xmat[body.trunk_id, 8] > 0.99 and not body.is_fallen()
    assert p.heading == pytest.approx(0.7, abs=0.02)
    cam = m.camera("go1/head_cam").id
    look = -d.cam_xmat[cam].reshape(3, 3)[:, 2]
    assert np.dot(look, [math.sin(0.7), math.cos(0.7), 0.0]) > 0.99
    assert 0.2 < d.cam_xpos[cam, 2] < 0.35


def test_camera_height_mast() -> None:
    body = _robot(camera_height=1.5)
    cam = body.model.camera("go1/head_cam").id
    assert body.data.cam_xpos[cam, 2] == pytest.approx(1.5, abs=0.05)
    assert body.model.geom("go1/" + const.CAMERA_MAST).contype == 0


def test_leg_ik_inverts_fk() -> None:
    for leg in range(4):
        hx, hy = const.HIP_OFFSETS[leg]
        for target in ((0.03, 0.01, -0.25), (-0.05, -0.02, -0.3), (0.0, 0.0, -0.2)):
            y = const.LEG_SIDE[leg] * const.ABDUCTION + target[1]
            q = leg_ik(leg, target[0], y, target[2])
            x, yy, z = leg_fk(leg, *q)
            assert (x - hx, yy - hy, z) == pytest.approx((target[0], y, target[2]), abs=1e-9)


def test_forward_and_turns_reach_targets() -> None:
    body = _robot(heading=1.0)
    ticks: list[float] = []
    res = body.forward(0.5, on_tick=ticks.append)
    assert not res.fell and not res.timed_out
    assert abs(res.error) < 0.03 and abs(res.lateral) < 0.03
    assert abs(math.degrees(res.heading_change)) < 3.0
    assert res.duration < 3.0 and res.steps == round(res.duration / 0.002)
    assert np.max(np.diff([body.data.time - res.duration, *ticks])) <= 1 / 16 + 1e-9
    for theta in (math.pi / 4, -math.pi / 4):
        res = body.turn(theta)
        assert not res.fell and abs(math.degrees(res.error)) < 3.0
        assert math.hypot(res.distance, res.lateral) < 0.05
    assert body.pose().heading == pytest.approx(1.0, abs=0.1)


def test_forward_speeds_up_at_most_forward_accel() -> None:
    """The walk's commanded speed grows by forward_accel at most; slowing down is not held."""
    gains = load_gains()
    body = SimpleNamespace(
        gains=gains,
        est=SimpleNamespace(x=0.0, y=0.0, yaw=0.3),
        data=SimpleNamespace(time=5.0),
        measured_vx=0.0,
    )
    command = ForwardCommand(body, -3.0, gains.forward_v_max)
    speeds, dt = [], 0.004
    for _ in range(250):  # 1 s, the trunk left where it stands: the command keeps asking
        body.data.time += dt
        vx, vy, _, _ = command(False)
        speeds.append(-math.hypot(vx, vy))
    rises = np.diff([0.0, *speeds])
    assert np.all(rises >= -gains.forward_accel * dt - 1e-12)  # backwards: speeds grow negative
    assert speeds[0] == pytest.approx(-gains.forward_accel * dt)
    assert speeds[-1] == pytest.approx(-gains.forward_v_max)
    body.est.x -= 2.99 * math.cos(0.3)  # nearly there: the P term slows at once
    body.est.y -= 2.99 * math.sin(0.3)
    body.data.time += dt
    vx, vy, _, _ = command(False)
    assert abs(vx) < gains.forward_v_min + 1e-9


def test_long_walk_after_a_wide_turn_stays_up() -> None:
    """A graph action's turn and walk: asked for cruise speed at once, this trot fell."""
    body = _robot(heading=5.058)
    turn = body.turn(1.9348)
    walk = body.forward(2.546)
    assert not turn.fell and not walk.fell and not body.is_fallen()
    assert abs(walk.error) < 0.03 and abs(math.degrees(turn.error)) < 3.0


def test_odometry_mode_walks_and_drifts_little() -> None:
    body = _robot(estimate="odometry")
    res = body.forward(0.5)
    assert abs(res.est_distance - 0.5) < 0.01  # closed on the estimate
    assert abs(res.distance - 0.5) < 0.06  # the truth drifts a little
    res = body.turn(-math.pi / 4)
    assert abs(math.degrees(res.heading_change) + 45) < 5


def test_fall_detected_upside_down_and_pushed() -> None:
    body = _robot()
    d = body.data
    d.qpos[body.qadr + 3 : body.qadr + 7] = (0.0, 1.0, 0.0, 0.0)  # upside down
    d.qpos[body.qadr + 2] = 0.4
    res = body.forward(0.5)
    assert res.fell and body.fallen
    body.reset(0.0, 0.0, 0.0, 0.0)
    assert not body.fallen

    def shove(t: float) -> None:
        d.xfrc_applied[body.trunk_id, :3] = (0.0, 600.0, 0.0) if t < 1.5 else 0.0

    res = body.forward(0.5, on_tick=shove)
    d.xfrc_applied[:] = 0.0
    assert res.fell and res.duration < 3.0
    assert body.forward(0.5).fell  # stays fallen until reset


def test_blocked_robot_times_out() -> None:
    spec = flat_floor_spec()
    spec.worldbody.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX, size=(0.05, 1.0, 0.5), pos=(0.6, 0, 0.5)
    )
    add_go1(spec)
    m = spec.compile()
    body = Go1Body(m, mujoco.MjData(m), gains=load_gains().with_(forward_v_min=0.3))
    body.reset(0.0, 0.0, 0.0, math.pi / 2)  # facing +x, the wall 0.25 m ahead of the head
    res = body.forward(1.5)
    assert res.timed_out and res.distance < 0.5
    assert res.duration < 2.0 + 1.5 / 0.3 + 1.0


def test_walks_in_procedural_house_with_mocap() -> None:
    from havln_mj.scene.scan import load_scan
    from havln_mj.sim.world import WorldOptions, world_spec

    scan = load_scan("proc-0")
    g = scan.graph
    vp = g.nodes[0]
    pos, z = g.position(vp), g.floor_z(vp)
    heading = heading_to(pos, g.position(g.neighbors(vp)[0]))
    spec, mode, _ = world_spec(scan, WorldOptions(collision="boxes"))
    add_go1(spec, (pos[0], pos[1], z), math.pi / 2 - heading)
    person = spec.worldbody.add_body(name="person", mocap=True, pos=(pos[0] + 1, pos[1], z + 1))
    person.add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=(0.2, 0.7, 0), contype=0)
    m = spec.compile()
    d = mujoco.MjData(m)
    body = Go1Body(m, d)
    body.reset(pos[0], pos[1], z, heading, settle=0.3)
    mocap = m.body("person").mocapid[0]

    def move(t: float) -> None:
        d.mocap_pos[mocap] = (pos[0] + 1 + 0.1 * t, pos[1], z + 1)

    res = body.forward(0.5, on_tick=move)
    assert mode == "boxes" and not res.fell and not res.timed_out
    assert abs(res.error) < 0.05


def test_deterministic() -> None:
    a, b = _robot(heading=2.0), _robot(heading=2.0)
    ra = [a.forward(0.5), a.turn(-math.pi / 4)]
    rb = [b.forward(0.5), b.turn(-math.pi / 4)]
    assert ra == rb
    assert np.array_equal(a.data.qpos, b.data.qpos)


def _menagerie_like(tmp_path: Path, with_mesh_file: bool) -> Path:
    """Our model rewritten the Menagerie way: a mesh asset and visual mesh geoms in group 2."""
    xml = asset_path("robots", "go1", "go1.xml").read_text()
    xml = xml.replace(
        '<compiler angle="radian" autolimits="true"/>',
        '<compiler angle="radian" autolimits="true" meshdir="assets"/>'
        '<asset><mesh name="trunk" file="trunk.obj"/></asset>',
    )
    xml = xml.replace(
        '<freejoint name="root"/>',
        '<freejoint/><geom type="mesh" mesh="trunk" contype="0" conaffinity="0" group="2"/>',
    )
    (tmp_path / "assets").mkdir()
    if with_mesh_file:
        (tmp_path / "assets" / "trunk.obj").write_text(
            "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n"
        )
    path = tmp_path / "go1.xml"
    path.write_text(xml)
    return path


@pytest.mark.parametrize("with_mesh_file", [True, False])
def test_menagerie_file(tmp_path: Path, with_mesh_file: bool) -> None:
    path = _menagerie_like(tmp_path, with_mesh_file)
    spec = flat_floor_spec()
    h = add_go1(spec, menagerie_xml=path)
    m = spec.compile()
    assert h.meshes == with_mesh_file
    mesh_geoms = [g for g in range(m.ngeom) if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH]
    assert len(mesh_geoms) == int(with_mesh_file)
    assert all(m.geom_group[g] == groups.ROBOT for g in mesh_geoms)
    body = Go1Body(m, mujoco.MjData(m))
    body.reset(0.0, 0.0, 0.0, 0.0)
    assert not body.forward(0.3).fell


def test_bad_inputs_rejected(tmp_path: Path) -> None:
    spec = flat_floor_spec()
    with pytest.raises(InvalidArgumentError, match="pos"):
        add_go1(spec, (0.0, float("nan"), 0.0))
    with pytest.raises(InvalidArgumentError, match="camera_height"):
        add_go1(spec, camera_height=10.0)
    with pytest.raises(InvalidArgumentError, match="prefix"):
        add_go1(spec, prefix="")
    with pytest.raises(MissingDataError, match="not found"):
        add_go1(spec, menagerie_xml=tmp_path / "nope.xml")
    (tmp_path / "bad.xml").write_text("<mujoco><worldbody/></mujoco>")
    with pytest.raises(MalformedDataError, match="not a GO1"):
        add_go1(spec, menagerie_xml=tmp_path / "bad.xml")
    add_go1(spec)
    with pytest.raises(InvalidArgumentError, match="already used"):
        add_go1(spec)
    m = spec.compile()
    d = mujoco.MjData(m)
    with pytest.raises(InvalidArgumentError, match="estimate"):
        Go1Body(m, d, estimate="gps")
    with pytest.raises(InvalidArgumentError, match="prefix"):
        Go1Body(m, d, prefix="robot/")
    body = Go1Body(m, d)
    with pytest.raises(InvalidArgumentError, match="distance"):
        body.forward(float("nan"))
    with pytest.raises(InvalidArgumentError, match="theta"):
        body.turn(float("inf"))
    with pytest.raises(InvalidArgumentError, match="seconds"):
        body.stand(-1.0)
    with pytest.raises(InvalidArgumentError, match="heading"):
        body.reset(0.0, 0.0, 0.0, float("nan"))
    with pytest.raises(InvalidArgumentError, match="duty"):
        Go1Gains(duty=0.95)
    with pytest.raises(InvalidArgumentError, match="tick_period"):
        Go1Gains(tick_period=0.1)
    with pytest.raises(InvalidArgumentError, match="forward_accel"):
        Go1Gains(forward_accel=0.0)
