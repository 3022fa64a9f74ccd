"""Procedural houses: determinism, the scan-folder contract and the generator invariants."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

from havln_mj import groups
from havln_mj.errors import InvalidArgumentError
from havln_mj.scene.connectivity import FIELDS, dumps_connectivity
from havln_mj.scene.procedural.generate import generate_house, write_scan
from havln_mj.scene.regions import REGION_LABELS
from havln_mj.scene.scan import load_scan, read_scan_folder
from havln_mj.sim.world import build_world

SEEDS = range(20)
MIN_WALL_CLEARANCE = 0.3
FLOOR_RAY_HEIGHT = 0.3


@pytest.fixture(scope="module")
def scans():
    return {seed: load_scan(f"proc-{seed}") for seed in SEEDS}


@pytest.fixture(scope="module")
def worlds(scans):
    return {seed: build_world(scan) for seed, scan in scans.items()}


def test_same_seed_gives_identical_bytes_and_model(tmp_path):
    a, b = generate_house(7), generate_house(7)
    assert dumps_connectivity(a.connectivity) == dumps_connectivity(b.connectivity)
    write_scan(a, tmp_path / "a")
    write_scan(b, tmp_path / "b")
    for name in ("connectivity.json", "regions.json", "boxes.json", "scan.json"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name
    ma = build_world(read_scan_folder(tmp_path / "a")).model
    mb = build_world(read_scan_folder(tmp_path / "b")).model
    for field in (
        "geom_type",
        "geom_size",
        "geom_pos",
        "geom_rgba",
        "geom_group",
        "mesh_vert",
        "mesh_face",
    ):
        np.testing.assert_array_equal(getattr(ma, field), getattr(mb, field), err_msg=field)


def test_different_seeds_give_different_houses():
    a, b = generate_house(1), generate_house(2)
    assert dumps_connectivity(a.connectivity) != dumps_connectivity(b.connectivity)


def test_bad_seed_is_rejected():
    with pytest.raises(InvalidArgumentError, match="-3"):
        generate_house(-3)


def test_sizes_and_room_kinds_look_like_homes(scans):
    kinds = set()
    for scan in scans.values():
        assert 40.0 <= scan.meta["area_m2"] <= 250.0
        labels = [r.label for r in scan.regions.regions]
        assert {"l", "k", "a", "b"} <= set(labels)
        kinds |= set(labels)
        assert all(label in REGION_LABELS for label in labels)
    assert len(kinds) >= 10, sorted(kinds)


def test_connectivity_follows_the_mattersim_schema(scans):
    raw = json.loads((scans[0].folder / "connectivity.json").read_text())
    assert isinstance(raw, list) and raw
    for entry in raw:
        assert tuple(entry) == FIELDS
        assert len(entry["pose"]) == 16
        pose = np.array(entry["pose"]).reshape(4, 4)
        np.testing.assert_allclose(pose[:3, 1], [0, 0, -1])  # Matterport camera: y down
        assert len(entry["visible"]) == len(entry["unobstructed"]) == len(raw)
        assert 1.4 < entry["height"] < 1.7
        assert abs(pose[2, 3] - entry["height"]) < 1e-6  # floor at z = 0


@pytest.mark.parametrize("seed", SEEDS)
def test_every_viewpoint_is_reachable_and_inside_a_room(scans, seed):
    scan = scans[seed]
    graph, regions, boxes = scan.graph, scan.regions, scan.boxes
    assert graph.is_connected()
    assert graph.num_nodes >= 8
    unob = graph.connectivity.unobstructed
    np.testing.assert_array_equal(unob, unob.T)
    walls = boxes.of_kind("wall")
    body_high = walls.hi[:, 2] > FLOOR_RAY_HEIGHT
    lo, hi = walls.lo[body_high, :2], walls.hi[body_high, :2]
    for vp in graph.nodes:
        xy = graph.position(vp)[:2]
        region = regions.region_of(vp)
        assert region is not None and region.contains(xy), vp
        gap = np.hypot(*np.maximum(np.maximum(lo - xy, xy - hi), 0.0).T)
        assert gap.min() >= MIN_WALL_CLEARANCE, (vp, gap.min())


@pytest.mark.parametrize("seed", SEEDS)
def test_every_edge_is_walkable_at_body_height(scans, worlds, seed):
    # Independent of the generator's own ray casts: MuJoCo's mj_ray against the compiled
    # collision geoms, 0.3 m above the floor, along every edge in both directions.
    graph, model = scans[seed].graph, worlds[seed].model
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    only_collision = np.zeros(mujoco.mjNGROUP, dtype=np.uint8)
    only_collision[groups.COLLISION] = 1
    geom = np.zeros(1, dtype=np.int32)
    for a, b, _ in graph.edges():
        for p, q in ((a, b), (b, a)):
            start = graph.position(p).copy()
            start[2] = graph.floor_z(p) + FLOOR_RAY_HEIGHT
            end = graph.position(q).copy()
            end[2] = graph.floor_z(q) + FLOOR_RAY_HEIGHT
            hit = mujoco.mj_ray(model, data, start, end - start, only_collision, 1, -1, geom)
            assert hit < 0 or hit > 1.0, (p, q, model.geom(geom[0]).name)


def test_walls_block_edges_between_rooms_without_a_door(scans):
    # Every edge between two different rooms passes through a door opening.
    scan = scans[3]
    graph, regions = scan.graph, scan.regions
    crossings = 0
    for a, b, _ in graph.edges():
        if regions.viewpoint_region[a] != regions.viewpoint_region[b]:
            crossings += 1
    rooms = len({regions.viewpoint_region[v] for v in graph.nodes})
    assert crossings >= rooms - 1  # the rooms are joined, so at least a spanning tree


@pytest.mark.parametrize("seed", SEEDS)
def test_every_seed_renders(scans, worlds, seed):
    from havln_mj.render.camera import Camera
    from havln_mj.robot.point_body import CAMERA, PointBody

    model = worlds[seed].model
    data = mujoco.MjData(model)
    graph = scans[seed].graph
    vp = graph.nodes[len(graph.nodes) // 2]
    PointBody(graph.position(vp), heading=1.0).write(model, data)
    with Camera(model, CAMERA, 64, 48, geom_groups=groups.CAMERA_GROUPS) as cam:
        frame = cam.render(data)
    assert frame.rgb.shape == (48, 64, 3) and frame.rgb.dtype == np.uint8
    assert frame.rgb.std() > 1.0  # not a blank image
    assert np.all(frame.depth > 0.0) and np.all(
        frame.depth < 30.0
    )  # closed house: walls everywhere


# ---------------------------------------------------------------- the look


@pytest.mark.parametrize("seed", [0, 3, 7])
def test_every_part_is_labelled_and_furniture_keeps_to_its_boxes(scans, seed):
    from havln_mj.scene.matterport.categories import SceneLabels, mpcat40_index

    scan = scans[seed]
    labels = SceneLabels.read(scan.folder / "semantics.json")
    parts = scan.mesh_parts
    assert {p.name for p in parts} == set(labels.parts)
    objects = scan.regions.objects
    by_object: dict[int, list] = {}
    for part in parts:
        inst = labels.instance(part.name)
        if inst.object is not None:
            by_object.setdefault(inst.object, []).append((inst, part))
    assert set(by_object) == {o.index for o in objects}  # every item is drawn
    for obj in objects:
        drawn = by_object[obj.index]
        own = [inst for inst, _ in drawn if inst.category == obj.category.replace("_", " ")]
        assert own and all(i.mpcat40 == mpcat40_index(obj.mpcat40) for i in own)
        verts = np.concatenate([p.vertices for _, p in drawn])
        lo, hi = obj.bbox[:3], obj.bbox[3:]
        # Inside the item's footprint; above it only soft things resting on it or cabinets
        # and mirrors hung over it.
        assert np.all(verts[:, :2] >= lo[:2] - 0.011) and np.all(verts[:, :2] <= hi[:2] + 0.011)
        assert verts[:, 2].min() >= -1e-6
    kinds = {i.category for i in labels.instances}
    assert {"floor", "wall", "ceiling", "door", "ceiling lamp"} <= kinds
    assert any(p.textured for p in parts)


def test_the_look_never_changes_the_house():
    # Houses are drawn from their seed alone: dressing them draws from its own generator.
    a = generate_house(4)
    b = generate_house(4)
    from havln_mj.scene.procedural.look import dress_house

    dress_house(b)
    np.testing.assert_array_equal(a.boxes.lo, b.boxes.lo)
    assert dumps_connectivity(a.connectivity) == dumps_connectivity(b.connectivity)
