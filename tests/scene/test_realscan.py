"""Real scan ids: a made-up Matterport-layout folder uses its mesh, else the graph proxy."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from havln_mj.errors import FrameMismatchError, MissingDataError
from havln_mj.run import main as run_main
from havln_mj.scene.connectivity import Connectivity, write_connectivity
from havln_mj.scene.mesh import boxes_to_parts, parts_to_trimesh
from havln_mj.scene.procedural.generate import generate_house
from havln_mj.scene.proxy.params import ProxyParams
from havln_mj.scene.proxy.routes import route_floor_points
from havln_mj.scene.proxy.walk import path_fault
from havln_mj.scene.scan import load_scan
from havln_mj.sim.simulator import Simulator

SCAN = "TestHouse01"  # an 11-character id, like Matterport's


def _made_up_matterport(tmp_path, z_shift: float = 0.0):
    """A raw-layout scan (OBJ mesh + .house) and its connectivity graph, from a procedural house."""
    house = generate_house(21, area=60.0)
    root = tmp_path / "mp3d"
    mesh_dir = root / "v1" / "scans" / SCAN / "matterport_mesh" / "abc123"
    mesh_dir.mkdir(parents=True)
    parts_to_trimesh(boxes_to_parts(house.boxes)).export(mesh_dir / "abc123.obj")
    seg = root / "v1" / "scans" / SCAN / "house_segmentations"
    seg.mkdir(parents=True)
    c = house.connectivity
    n_regions = len(house.regions.regions)
    header = f"H {SCAN} house 0 {len(c.ids)} 0 0 0 0 0 {n_regions} 0 1 0 0 0 0 0"
    lines = ["ASCII 1.1", header + " 0 0 0 9 9 3 0 0 0 0 0"]
    lines.append("L 0 1 - 0 0 0 0 0 0 20 20 3 0 0 0 0 0")
    for rg in house.regions.regions:
        b = rg.bbox
        box = " ".join(str(v) for v in b)
        lines.append(f"R {rg.index} 0 0 0 {rg.label} 0 0 0 {box} {rg.height} 0 0 0 0")
    for k, vp in enumerate(c.ids):
        x, y, z = c.positions[k]
        lines.append(f"P {vp} {k} {house.regions.viewpoint_region[vp]} 0 {x} {y} {z} 0 0 0 0 0")
    (seg / f"{SCAN}.house").write_text("\n".join(lines) + "\n")
    conn_dir = tmp_path / "connectivity"
    conn_dir.mkdir()
    poses = c.poses.copy()
    poses[:, 2, 3] += z_shift
    write_connectivity(
        conn_dir / f"{SCAN}_connectivity.json",
        Connectivity(c.ids, poses, c.included, c.visible, c.unobstructed, c.heights),
    )
    return house, root, conn_dir


def test_matterport_layout_uses_the_mesh_and_the_house_file(tmp_path):
    house, root, conn_dir = _made_up_matterport(tmp_path)
    scan = load_scan(SCAN, mp3d_dir=root, connectivity_dir=conn_dir)
    assert scan.kind == "matterport"
    assert scan.mesh_path.suffix == ".obj" and str(root) in str(scan.mesh_path)
    assert scan.meta["frame_check"]["agreeing"] == scan.meta["frame_check"]["checked"] > 0
    assert [r.label for r in scan.regions.regions] == [r.label for r in house.regions.regions]
    assert scan.regions.viewpoint_region == house.regions.viewpoint_region
    assert not (scan.folder / "mesh.glb").exists()  # the licensed mesh is referenced, not copied

    out = tmp_path / "run"
    args = f"--scene {SCAN} --episodes 1 --width 48 --height 36 --fps 2 --collision none"
    rc = run_main(
        [
            *args.split(),
            "--mp3d-dir",
            str(root),
            "--connectivity-dir",
            str(conn_dir),
            "--out",
            str(out),
        ]
    )
    assert rc == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scene_kind"] == "matterport" and "Matterport3D scan" in summary["description"]


def test_frame_mismatch_is_reported(tmp_path):
    _, root, conn_dir = _made_up_matterport(tmp_path, z_shift=1.0)
    with pytest.raises(FrameMismatchError, match="floor"):
        load_scan(SCAN, mp3d_dir=root, connectivity_dir=conn_dir)


def test_graph_proxy_when_only_the_graph_is_there(tmp_path, shared_data):
    conn = shared_data / "mp3d_connectivity"
    scan = load_scan("17DRP5sb8fy", connectivity_dir=conn)
    assert scan.kind == "graph proxy" and "NOT the real mesh" in scan.description
    assert scan.boxes is not None and scan.meta["unwalkable_edges"] == 0
    out = tmp_path / "run"
    args = "--scene 17DRP5sb8fy --episodes 1 --width 48 --height 36 --fps 2"
    assert run_main([*args.split(), "--connectivity-dir", str(conn), "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scene_kind"] == "graph proxy" and "graph proxy" in summary["description"]
    assert (out / "egocentric.mp4").stat().st_size > 0 and (out / "topdown.png").is_file()


def test_a_proxy_stores_the_routes_of_edges_it_cannot_draw_straight(shared_data):
    # 5LpN3gDmAk7: one edge crosses another's corridor at body height and is walked round.
    scan = load_scan("5LpN3gDmAk7", connectivity_dir=shared_data / "mp3d_connectivity")
    assert scan.meta["unwalkable_edges"] == 0 and scan.meta["edges_by_route"] == 1
    assert json.loads((scan.folder / "routes.json").read_text())["routes"]
    (((a, b), via),) = scan.routes.items()
    assert via[0] == a and via[-1] == b and len(via) >= 3
    assert scan.route(b, a) == via[::-1] and scan.route(a, via[1]) is None
    for u, v in itertools.pairwise(via):
        assert v in scan.graph.neighbors(u)


def test_a_proxy_draws_a_flight_for_a_steep_edge_the_graph_cannot_route(shared_data):
    # D7G3Y4RVNrH: a line of sight up a turning stair climbs 0.79 m over 0.62 m (52°), and
    # the graph's other way round is 2.5 times as long: the proxy draws a flight for it.
    scan = load_scan("D7G3Y4RVNrH", connectivity_dir=shared_data / "mp3d_connectivity")
    assert scan.meta["unwalkable_edges"] == 0 and scan.meta["edges_by_flight"] == 1
    (((a, b), via),) = scan.routes.items()
    assert via[0] == a and via[-1] == b
    assert all(isinstance(s, tuple) and len(s) == 3 for s in via[1:-1])
    points = route_floor_points(scan.graph, via)
    assert path_fault(points, scan.boxes, ProxyParams()) is None


def test_a_real_scan_moves_the_same_with_rendering_on_and_off(shared_data, standing):
    # D7G3Y4RVNrH has an edge its proxy walks along a flight; the point body walks every edge
    # straight whether the proxy is built (rendering on) or not, so durations and the
    # collision signal cannot depend on the switch.
    conn = shared_data / "mp3d_connectivity"
    scan = load_scan("D7G3Y4RVNrH", connectivity_dir=conn)
    ((a, b), _), *_ = scan.routes.items()
    g = scan.graph
    mid = (g.position(a) + g.position(b)) / 2 - [0.0, 0.0, 1.0]

    def crowd(scan_id, graph, rng):
        offsets = np.array([[0.3, 0.2, 0.0], [2.5, 0.0, -1.0]])
        return standing(np.stack([mid, g.position(a)]) + offsets)

    runs = []
    for rendering in (False, True):
        sim = Simulator(humans=crowd)
        sim.setNavGraphPath(conn)
        sim.setRenderingEnabled(rendering)
        sim.setCameraResolution(32, 24)
        sim.setRestrictedNavigation(False)
        sim.newEpisode([scan.scene_id], [a], [0.0], [0.0])
        seen = []
        for _ in range(6):  # wander the neighbourhood with the same actions
            state = sim.getState()[0]
            seen.append((state.location.viewpointId, state.time, state.isCrushed, state.crushedBy))
            sim.makeAction([1 if len(state.navigableLocations) > 1 else 0], [0.4], [0.0])
        runs.append(seen)
        sim.close()
    assert runs[0] == runs[1]
    assert any(hit for *_, hit, _ in runs[0])


def test_proxy_is_replaced_once_the_mesh_appears(tmp_path):
    house, root, conn_dir = _made_up_matterport(tmp_path)
    proxy = load_scan(SCAN, connectivity_dir=conn_dir, mp3d_dir=tmp_path / "nothing")
    assert proxy.kind == "graph proxy"
    real = load_scan(SCAN, connectivity_dir=conn_dir, mp3d_dir=root)
    assert real.kind == "matterport"
    assert np.array_equal(real.graph.connectivity.unobstructed, house.connectivity.unobstructed)


def test_missing_data_says_what_was_looked_for_and_how_to_get_it(tmp_path):
    with pytest.raises(MissingDataError) as err:
        load_scan("XcA2TqTSSAj", mp3d_dir=tmp_path, connectivity_dir=tmp_path)
    text = str(err.value)
    assert str(tmp_path / "XcA2TqTSSAj_connectivity.json") in text
    assert "Matterport3DSimulator" in text and "Terms of Use" in text
    assert "matterport_mesh" in text


def test_proxy_takes_region_labels_from_a_house_file_without_mesh(tmp_path):
    house, root, conn_dir = _made_up_matterport(tmp_path)
    mesh_dir = root / "v1" / "scans" / SCAN / "matterport_mesh"
    for f in mesh_dir.rglob("*.obj"):
        f.unlink()
    scan = load_scan(SCAN, mp3d_dir=root, connectivity_dir=conn_dir, rebuild=True)
    assert scan.kind == "graph proxy"
    assert [r.label for r in scan.regions.regions] == [r.label for r in house.regions.regions]
    assert scan.regions.viewpoint_region == house.regions.viewpoint_region
