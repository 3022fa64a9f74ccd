"""GO1 on terrain: height scan, footholds, courses and the terrain-aware gait."""

from __future__ import annotations

import json
import math
from pathlib import Path

import mujoco
import numpy as np
import pytest

from havln_mj.errors import InvalidArgumentError, MalformedDataError
from havln_mj.robot.go1 import Go1Body, add_go1, flat_floor_spec, load_gains
from havln_mj.robot.go1.courses import START_X, ramp_spec, stairs_spec
from havln_mj.robot.go1.footholds import foothold, swing_heights
from havln_mj.robot.go1.gains import TerrainGains
from havln_mj.robot.go1.height_scan import HeightScan

G = TerrainGains()


def _on(spec: mujoco.MjSpec, controller: str = "terrain") -> Go1Body:
    add_go1(spec)
    model = spec.compile()
    return Go1Body(model, mujoco.MjData(model), controller=controller)


def _stair(x: float) -> float:
    """Ground of a stair of 0.17 m risers on 0.28 m treads from x = 0."""
    return 0.17 * min(max(math.floor(x / 0.28) + 1, 0), 12) if x >= 0 else 0.0


def test_height_scan_reads_the_stairs_and_sees_through_the_robot() -> None:
    body = _on(stairs_spec(riser=0.17, tread=0.28, risers=4)[0])
    body.reset(START_X, 0.0, 0.0, math.pi / 2)
    scan = body.scan
    for x in (-0.5, 0.1, 0.4, 0.7, 1.0):
        assert scan.height(x, 0.0, _stair(x) + 0.3) == pytest.approx(_stair(x), abs=1e-6)
    assert scan.height(1.0, 0.0, 0.0) == math.inf  # from the floor, inside the top step
    # Under the robot the rays pass its legs and trunk and find the floor.
    for leg in body.foot_ids:
        fx, fy, _ = body.data.geom_xpos[leg]
        assert scan.height(fx, fy + 0.01, 0.3) == pytest.approx(0.0, abs=1e-6)
    rays = scan.rays
    assert scan.height(0.401, 0.002, 0.64) == pytest.approx(0.34)
    assert scan.rays == rays  # the building is static: a cell is cast once


def test_courses_climb_as_asked() -> None:
    spec, course = stairs_spec(riser=0.19, tread=0.28, risers=12)
    assert course.rise == pytest.approx(12 * 0.19) and course.run == pytest.approx(11 * 0.28)
    body = _on(spec)
    mujoco.mj_forward(body.model, body.data)
    top = course.rise + 0.3
    assert body.scan.height(course.run + 0.5, 0.0, top) == pytest.approx(course.rise)
    spec, course = ramp_spec(20.0, run=2.0)
    body = _on(spec)
    mujoco.mj_forward(body.model, body.data)
    h = [body.scan.height(x, 0.0, 1.2) for x in (0.5, 1.0)]
    assert (h[1] - h[0]) / 0.5 == pytest.approx(math.tan(math.radians(20)), abs=0.02)
    with pytest.raises(InvalidArgumentError, match="riser"):
        stairs_spec(riser=0.5)
    with pytest.raises(InvalidArgumentError, match="degrees"):
        ramp_spec(60.0)


def test_footholds_land_mid_tread_and_clear_the_nosings() -> None:
    def ground(x: float, y: float) -> float:
        return _stair(x)

    # A Raibert point on or near a nosing moves to the middle of a tread's safe part: the
    # drop margin past the nosing behind it, the edge margin short of the riser ahead.
    for aim in (0.28, 0.55, 0.30, 0.62):
        x, _ = foothold(ground, aim, 0.0, 1.0, 0.0, G)
        on = x - 0.28 * math.floor(x / 0.28)
        assert on >= G.drop_margin - 0.011 and 0.28 - on >= G.edge_margin - 0.011
        assert on == pytest.approx((G.drop_margin + 0.28 - G.edge_margin) / 2, abs=0.011)
        assert abs(x - aim) <= G.foothold_shift
    # On flat ground the point stays.
    assert foothold(lambda x, y: 0.0, 0.123, 0.4, 1.0, 0.0, G) == (0.123, 0.4)
    # A swing from one tread to the next keeps its clearance over the nosing.
    start, goal = (0.14, 0.0, 0.17 + 0.02), (0.42, 0.0, 0.34 + 0.02)
    zs = swing_heights(ground, start, goal, G)
    assert zs[0] == start[2] and zs[-1] == goal[2]
    assert max(zs) >= 0.34 + G.clearance
    from havln_mj.robot.go1.footholds import swing_along, swing_height

    for s in np.linspace(0.0, 1.0, 41):
        x = start[0] + (goal[0] - start[0]) * swing_along(s, G)
        if abs(x - 0.28) < 0.02:  # over the nosing
            assert swing_height(zs, s) > 0.34 + 0.023


def test_terrain_gait_walks_and_turns_accurately_on_flat_ground() -> None:
    body = _on(flat_floor_spec())
    body.reset(0.0, 0.0, 0.0, 0.4)
    res = body.forward(0.5)
    assert not res.fell and not res.timed_out
    assert abs(res.error) < 0.03 and abs(res.lateral) < 0.06  # it drifts more than the trot
    res = body.turn(math.pi / 4)
    assert not res.fell and abs(math.degrees(res.error)) < 2.0


@pytest.mark.parametrize("degrees", [10.0, 30.0])
def test_terrain_gait_walks_up_and_down_a_ramp_onto_its_landings(degrees: float) -> None:
    # Up 30°, without the stance feet following the ground the feet slipped back down the
    # slope and the robot stalled a third of the way up; at the crest the hind feet, still
    # on the slope, tripped the flat rhythm.
    spec, course = ramp_spec(degrees, run=1.5)
    body = _on(spec)
    body.reset(START_X, 0.0, 0.0, math.pi / 2)
    res = body.forward(course.top_x - START_X)
    p = body.true_pose()
    assert not res.fell and not res.timed_out
    assert p.x == pytest.approx(course.top_x, abs=0.1) and abs(p.y) < 0.15
    assert p.z == pytest.approx(course.rise + 0.27, abs=0.05)
    res = body.forward(-0.5)  # and back a little, backwards
    assert not res.fell and body.true_pose().x == pytest.approx(course.top_x - 0.5, abs=0.1)
    body.reset(course.top_x, 0.0, course.rise, -math.pi / 2)  # then all the way down
    res = body.forward(course.top_x - START_X)
    p = body.true_pose()
    assert not res.fell and not res.timed_out
    assert p.x == pytest.approx(START_X, abs=0.1) and p.z == pytest.approx(0.27, abs=0.05)


def test_placed_on_a_stair_it_stands_on_its_treads() -> None:
    spec, _ = stairs_spec(riser=0.17, tread=0.28, risers=12)
    body = _on(spec)
    mujoco.mj_forward(body.model, body.data)
    x = 1.0
    body.reset(x, 0.0, body.scan.height(x, 0.0, 2.0), math.pi / 2)
    res = body.stand(2.0)
    assert not res.fell and not body.is_fallen()
    for leg in body.foot_ids:
        fx, _, fz = body.data.geom_xpos[leg]
        assert fz - 0.023 == pytest.approx(_stair(fx), abs=0.03)  # on a tread, not a nosing
        assert 0.05 < fx - 0.28 * math.floor(fx / 0.28) < 0.23


@pytest.mark.parametrize("controller", ["terrain", "trot", "crawl"])
def test_a_robot_pushed_over_on_a_stair_is_fallen(controller: str) -> None:
    spec, _ = stairs_spec(riser=0.17, tread=0.28, risers=12)
    body = _on(spec, controller)
    mujoco.mj_forward(body.model, body.data)
    body.reset(1.0, 0.0, body.scan.height(1.0, 0.0, 2.0), math.pi / 2)
    d = body.data

    def shove(t: float) -> None:
        d.xfrc_applied[body.trunk_id, :3] = (0.0, 500.0, 0.0) if t < d.time + 1.0 else 0.0

    res = body.stand(2.0, on_tick=shove)
    d.xfrc_applied[:] = 0.0
    assert res.fell and body.fallen and body.is_fallen()
    assert body.forward(0.3).fell  # stays fallen until reset


def test_controller_and_terrain_gains_are_checked(tmp_path: Path) -> None:
    spec = flat_floor_spec()
    add_go1(spec)
    m = spec.compile()
    with pytest.raises(InvalidArgumentError, match="controller"):
        Go1Body(m, mujoco.MjData(m), controller="mpc")
    with pytest.raises(InvalidArgumentError, match="rough_duty"):
        TerrainGains(rough_duty=0.95)
    with pytest.raises(InvalidArgumentError, match="swing_start"):
        TerrainGains(swing_start=0.9)
    with pytest.raises(InvalidArgumentError, match="control_decimation"):
        TerrainGains(control_decimation=0)
    path = tmp_path / "gains.json"
    path.write_text(json.dumps({"terrain": {"rough_speed": 0.1}}))
    assert load_gains(path).terrain.rough_speed == 0.1
    path.write_text(json.dumps({"terrain": {"rough_sped": 0.1}}))
    with pytest.raises(MalformedDataError, match="rough_sped"):
        load_gains(path)
    path.write_text(json.dumps({"terrain": 3}))
    with pytest.raises(MalformedDataError, match="terrain"):
        load_gains(path)


def test_height_scan_ignores_people() -> None:
    spec = flat_floor_spec()
    person = spec.worldbody.add_body(name="person", mocap=True, pos=(1.0, 0.0, 0.9))
    person.add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=(0.2, 0.7, 0), group=2)
    add_go1(spec)
    m = spec.compile()
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    scan = HeightScan(m, d, m.body("go1/trunk").id)
    assert scan.height(1.0, 0.0, 0.3) == pytest.approx(0.0)
