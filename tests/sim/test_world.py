"""World builder: box collision for procedural houses, CoACD hulls for mesh-only scans."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from havln_mj import groups
from havln_mj.errors import InvalidArgumentError
from havln_mj.frames import forward
from havln_mj.render.camera import Camera
from havln_mj.robot.point_body import CAMERA, PointBody
from havln_mj.scene.collision import CoacdParams
from havln_mj.scene.procedural.generate import generate_house, write_scan
from havln_mj.scene.scan import load_scan, read_scan_folder
from havln_mj.sim.world import WorldOptions, build_world

# Small enough for CI: a ~15 m² house and a coarse remesh.
FAST_COACD = CoacdParams(
    threshold=0.08, preprocess_resolution=30, mcts_iterations=40, mcts_max_depth=2
)


def _group_mask(*gs: int) -> np.ndarray:
    mask = np.zeros(mujoco.mjNGROUP, dtype=np.uint8)
    mask[list(gs)] = 1
    return mask


def _ray(model, data, start, direction, group):
    geom = np.zeros(1, dtype=np.int32)
    return mujoco.mj_ray(model, data, start, direction, _group_mask(group), 1, -1, geom)


def test_procedural_world_uses_exact_boxes():
    scan = load_scan("proc-5")
    world = build_world(scan)
    model = world.model
    assert world.collision == "boxes"
    assert world.n_collision_geoms == len(scan.boxes)
    collision = model.geom_group == groups.COLLISION
    assert collision.sum() == len(scan.boxes)
    assert np.all(model.geom_contype[collision] == 1)
    visual = model.geom_group == groups.VISUAL
    assert np.all(model.geom_contype[visual] == 0) and np.all(model.geom_conaffinity[visual] == 0)
    assert model.body("agent").mocapid[0] >= 0 and model.camera("agent_cam").id >= 0
    names = [model.geom(i).name for i in range(model.ngeom)]
    assert all(names) and len(set(names)) == len(names)


def test_bad_collision_mode_is_rejected():
    with pytest.raises(InvalidArgumentError, match="'boxed'"):
        WorldOptions(collision="boxed")


def test_depth_to_the_wall_ahead_matches_the_geometry():
    scan = load_scan("proc-5")
    model = build_world(scan).model
    data = mujoco.MjData(model)
    with Camera(model, CAMERA, 96, 72, geom_groups=groups.CAMERA_GROUPS) as cam:
        checked = 0
        for vp in scan.graph.nodes[:12]:
            for heading in (0.0, np.pi / 2, np.pi, 3 * np.pi / 2):
                body = PointBody(scan.graph.position(vp), heading=heading)
                body.write(model, data)
                expected = _ray(model, data, body.position, forward(heading), groups.COLLISION)
                if expected < 0:
                    continue
                depth = cam.render(data, rgb=False).depth
                assert abs(depth[36, 48] - expected) < 0.02, (vp, heading, depth[36, 48], expected)
                checked += 1
    assert checked >= 20


@pytest.mark.slow
def test_mesh_only_scan_gets_coacd_hulls(tmp_path):
    house = generate_house(11, area=14.0)
    write_scan(house, tmp_path / "mesh_only", with_boxes=False)
    scan = read_scan_folder(tmp_path / "mesh_only")
    assert scan.boxes is None
    world = build_world(scan, WorldOptions(coacd=FAST_COACD))
    assert world.collision == "coacd" and world.n_collision_geoms >= 4
    model = world.model
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    # Looking level from each viewpoint, the hulls sit where the exact walls are, within the
    # remesh's thickening (a few cm at this resolution).
    exact = build_world(read_scan_folder(tmp_path / "mesh_only"), WorldOptions(collision="none"))
    boxes = house.boxes.of_kind("wall", "furniture")
    agree = 0
    for vp in scan.graph.nodes:
        p = scan.graph.position(vp).copy()
        p[2] = 1.0
        for heading in (0.0, np.pi / 2, np.pi, 3 * np.pi / 2):
            d = forward(heading)
            hull_hit = _ray(model, data, p, d, groups.COLLISION)
            exact_data = mujoco.MjData(exact.model)
            mujoco.mj_forward(exact.model, exact_data)
            mesh_hit = _ray(exact.model, exact_data, p, d, groups.VISUAL)
            assert hull_hit > 0, (vp, heading)
            assert mesh_hit > 0
            assert hull_hit <= mesh_hit + 0.02  # hulls never let the body pass through a wall
            agree += abs(hull_hit - mesh_hit) < 0.15
    assert agree >= 0.8 * 4 * scan.graph.num_nodes
    assert len(boxes) > 0
