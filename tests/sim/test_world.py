"""World builder: box collision for procedural houses, CoACD hulls for mesh-only scans."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from havln_mj import groups
from havln_mj.errors import InvalidArgumentError
from havln_mj.frames import forward
from havln_mj.render.camera import Camera
from havln_mj.render.labels import LABELS, geom_labels
from havln_mj.robot.point_body import CAMERA, PointBody
from havln_mj.scene.collision import CoacdParams
from havln_mj.scene.matterport.categories import mpcat40_index
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


def test_label_meshes_are_left_out_of_worlds_that_never_render_labels():
    scan = load_scan("proc-5")
    with_labels = build_world(scan, WorldOptions(collision="none")).model
    without = build_world(scan, WorldOptions(collision="none", labels=False)).model
    assert (with_labels.geom_group == LABELS).sum() > 0
    assert (without.geom_group == LABELS).sum() == 0
    visual = groups.VISUAL
    assert (without.geom_group == visual).sum() == (with_labels.geom_group == visual).sum()


def test_simulator_worlds_have_label_meshes_only_with_segmentation():
    from havln_mj.sim.bodies import make_kind
    from havln_mj.sim.settings import Settings

    for labels in (False, True):
        kind = make_kind("point", load_scan, Settings(labels=labels), 1.0, 1.0, None)
        assert kind._options.labels is labels


def test_bad_collision_mode_is_rejected():
    with pytest.raises(InvalidArgumentError, match="'boxed'"):
        WorldOptions(collision="boxed")


def _pixel_ray(heading, row, col, width, height, vfov_deg=60.0):
    """The direction through a pixel's centre, camera level at ``heading``, scaled so that its
    component along the view axis is 1 (so a ray's hit distance is the planar depth)."""
    t = np.tan(np.radians(vfov_deg) / 2)
    x = (2 * (col + 0.5) / width - 1) * t * width / height
    y = (1 - 2 * (row + 0.5) / height) * t
    right = np.array([np.cos(heading), -np.sin(heading), 0.0])
    return forward(heading) + x * right + y * np.array([0.0, 0.0, 1.0])


def test_depth_to_the_wall_ahead_matches_the_geometry():
    # Depth is where the visual mesh is. Where a wall (or its door, window or picture) is
    # seen, that lies on the wall's collision box or up to 6 cm in front of it (skirting,
    # frames, pictures, an open door leaf), never behind it.
    scan = load_scan("proc-5")
    model = build_world(scan).model
    data = mujoco.MjData(model)
    semantic, _ = geom_labels(model)
    on_walls = [mpcat40_index(c) for c in ("wall", "door", "window", "picture")]
    geom = np.zeros(1, dtype=np.int32)
    with Camera(model, CAMERA, 96, 72, geom_groups=groups.CAMERA_GROUPS) as cam:
        checked = 0
        for vp in scan.graph.nodes[:12]:
            for heading in (0.0, np.pi / 2, np.pi, 3 * np.pi / 2):
                body = PointBody(scan.graph.position(vp), heading=heading)
                body.write(model, data)
                start, ahead = body.position, _pixel_ray(heading, 36, 48, 96, 72)
                seen = _ray(model, data, start, ahead, groups.VISUAL)
                depth = cam.render(data, rgb=False).depth
                assert abs(depth[36, 48] - seen) < 0.01, (vp, heading, depth[36, 48], seen)
                labelled = mujoco.mj_ray(
                    model, data, start, ahead, _group_mask(LABELS), 1, -1, geom
                )
                if labelled < 0 or semantic[geom[0]] not in on_walls:
                    continue
                solid = _ray(model, data, start, ahead, groups.COLLISION)
                assert solid - 0.06 <= seen <= solid + 0.002, (vp, heading, seen, solid)
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
