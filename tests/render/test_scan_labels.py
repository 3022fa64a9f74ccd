"""Semantic labels of Matterport3D scans, on made-up files in the real formats.

A raw-layout scan is made from a procedural house: its boxes are the textured mesh (OBJ) and
the house-segmentation PLY, whose faces carry each box's object index (``face_segment``);
the ``.house`` file gives each object a category and its mpcat40 class.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from havln_mj import groups
from havln_mj.errors import CorruptMeshError, MalformedDataError
from havln_mj.render.camera import Camera
from havln_mj.render.labels import geom_labels, render_labels, segmentation_groups
from havln_mj.robot.point_body import CAMERA, PointBody
from havln_mj.scene.connectivity import write_connectivity
from havln_mj.scene.matterport.categories import SceneLabels, mpcat40_index
from havln_mj.scene.matterport.house import read_object_classes
from havln_mj.scene.matterport.labelmesh import ply_label_meshes, read_ply
from havln_mj.scene.mesh import boxes_to_parts, boxes_to_triangles, parts_to_trimesh
from havln_mj.scene.procedural.generate import generate_house
from havln_mj.scene.scan import load_scan
from havln_mj.sim.world import WorldOptions, build_world

SCAN = "LabelHouse1"
CLASSES = {"wall": "wall", "floor": "floor", "ceiling": "ceiling", "furniture": "furniture"}


def write_ply(path, verts, faces, fields: dict, binary: bool = True) -> None:
    """A triangle PLY with int face properties ``fields`` (name -> (F,) values)."""
    head = ["ply", f"format {'binary_little_endian' if binary else 'ascii'} 1.0",
            f"element vertex {len(verts)}", "property float x", "property float y",
            "property float z", f"element face {len(faces)}",
            "property list uchar int vertex_indices"]  # fmt: skip
    head += [f"property int {name}" for name in fields] + ["end_header"]
    text = ("\n".join(head) + "\n").encode("ascii")
    if binary:
        vdt = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4")])
        v = np.zeros(len(verts), vdt)
        v["x"], v["y"], v["z"] = verts.T
        fdt = np.dtype([("n", "u1"), ("v", "<i4", 3)] + [(n, "<i4") for n in fields])
        f = np.zeros(len(faces), fdt)
        f["n"], f["v"] = 3, faces
        for name, values in fields.items():
            f[name] = values
        path.write_bytes(text + v.tobytes() + f.tobytes())
    else:
        rows = [" ".join(f"{c:.6f}" for c in p) for p in verts]
        extra = (
            np.column_stack([fields[n] for n in fields])
            if fields
            else np.zeros((len(faces), 0), int)
        )
        rows += [" ".join(map(str, [3, *tri, *e])) for tri, e in zip(faces, extra, strict=True)]
        path.write_bytes(text + ("\n".join(rows) + "\n").encode("ascii"))


def made_up_scan(tmp_path, unlabelled_box: int = 0):
    """A raw-layout scan whose PLY faces name one object per box (but ``unlabelled_box``)."""
    house = generate_house(21, area=60.0)
    boxes = house.boxes
    base = tmp_path / "mp3d" / "v1" / "scans" / SCAN
    (base / "matterport_mesh" / "m1").mkdir(parents=True)
    parts_to_trimesh(boxes_to_parts(boxes)).export(base / "matterport_mesh" / "m1" / "m1.obj")
    seg = base / "house_segmentations"
    seg.mkdir()
    verts, faces = boxes_to_triangles(boxes.lo, boxes.hi)
    objects = np.repeat(np.arange(len(boxes)), 12)
    objects[objects == unlabelled_box] = -1
    fields = {
        "face_material": objects,
        "face_segment": objects,
        "face_category": np.zeros(len(faces), int),
    }
    write_ply(seg / f"{SCAN}.ply", verts, faces, fields)
    kinds = list(CLASSES)
    counts = f"0 0 0 0 0 {len(boxes)} {len(kinds)} 1 0 1"
    lines = [
        "ASCII 1.1",
        f"H {SCAN} house {counts} 0 0 0 0 0 0 0 0 9 9 3 0 0 0 0 0",
        "L 0 1 - 0 0 0 0 0 0 20 20 3 0 0 0 0 0",
        "R 0 0 0 0 l 0 0 0 0 0 0 20 20 3 2.7 0 0 0 0",
    ]
    for k, kind in enumerate(kinds):
        lines.append(
            f"C {k} {k + 1} {kind} {mpcat40_index(CLASSES[kind])} {CLASSES[kind]} 0 0 0 0 0"
        )
    for k, kind in enumerate(boxes.kind):
        c = (boxes.lo[k] + boxes.hi[k]) / 2
        r = (boxes.hi[k] - boxes.lo[k]) / 2
        where = f"{c[0]} {c[1]} {c[2]} 1 0 0 0 1 0 {r[0]} {r[1]} {r[2]}"
        lines.append(f"O {k} 0 {kinds.index(kind)} {where} 0 0 0 0 0 0 0 0")
    (seg / f"{SCAN}.house").write_text("\n".join(lines) + "\n")
    conn = tmp_path / "connectivity"
    conn.mkdir()
    write_connectivity(conn / f"{SCAN}_connectivity.json", house.connectivity)
    return house, tmp_path / "mp3d", conn


def test_ply_reads_alike_in_ascii_and_binary(tmp_path):
    verts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    faces = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 1]])
    ids = {"object_id": np.array([4, 4, 7])}
    write_ply(tmp_path / "b.ply", verts, faces, ids, binary=True)
    write_ply(tmp_path / "a.ply", verts, faces, ids, binary=False)
    for name in ("a.ply", "b.ply"):
        v, f, extra = read_ply(tmp_path / name)
        np.testing.assert_allclose(v, verts)
        np.testing.assert_array_equal(f, faces)
        np.testing.assert_array_equal(extra["object_id"], [4, 4, 7])
    (tmp_path / "bad.ply").write_bytes(b"not a ply")
    with pytest.raises(CorruptMeshError, match="not a PLY"):
        read_ply(tmp_path / "bad.ply")
    write_ply(tmp_path / "none.ply", verts, faces, {})
    with pytest.raises(CorruptMeshError, match="object id"):
        ply_label_meshes(tmp_path / "none.ply", None)


def test_house_gives_each_object_its_mpcat40_class(tmp_path):
    house, root, _ = made_up_scan(tmp_path)
    classes = read_object_classes(
        root / "v1" / "scans" / SCAN / "house_segmentations" / f"{SCAN}.house"
    )
    assert len(classes) == len(house.boxes)
    for k, kind in enumerate(house.boxes.kind):
        assert classes[k] == (kind, mpcat40_index(CLASSES[kind]))
    bad = tmp_path / "bad.house"
    bad.write_text("ASCII 1.1\nO 0 0 5 0 0 0 1 0 0 0 1 0 1 1 1 0 0 0 0 0 0 0 0\n")
    with pytest.raises(MalformedDataError, match="category 5"):
        read_object_classes(bad)


def test_matterport_scan_segments_by_its_ply_objects(tmp_path):
    house, root, conn = made_up_scan(tmp_path, unlabelled_box=3)
    scan = load_scan(SCAN, mp3d_dir=root, connectivity_dir=conn)
    assert scan.kind == "matterport"
    model = build_world(scan, WorldOptions(collision="none")).model
    semantic, instance = geom_labels(model)
    labelled = segmentation_groups(model)
    assert labelled[0] != groups.VISUAL  # the PLY's objects, not the textured mesh
    # Object k (box k) is instance k + 1 with its kind's class; box 3's faces are unlabelled.
    for g in np.flatnonzero(instance > 0):
        k = instance[g] - 1
        assert semantic[g] == mpcat40_index(CLASSES[house.boxes.kind[k]])
    unl = np.flatnonzero((instance == 0) & (semantic == 41) & (model.geom_group == labelled[0]))
    assert len(unl) == 1
    data = mujoco.MjData(model)
    graph = scan.graph
    seen = set()
    with Camera(model, CAMERA, 48, 36) as cam:
        for vp in graph.nodes[:6]:
            for heading in (0.0, math.pi / 2, math.pi, 3 * math.pi / 2):
                PointBody(graph.position(vp), heading=heading, elevation=-0.3).write(model, data)
                seg = render_labels(model, data, cam)
                seen |= set(np.unique(seg.semantic).tolist())
                # Every pixel shows one of the boxes: its instance's class.
                inst = seg.instance[seg.instance > 0]
                kinds = np.array(house.boxes.kind)[inst - 1]
                expected = [mpcat40_index(CLASSES[k]) for k in kinds]
                np.testing.assert_array_equal(seg.semantic[seg.instance > 0], expected)
    assert {mpcat40_index("wall"), mpcat40_index("floor")} <= seen


def test_procedural_labels_file_round_trips_and_rejects_bad_ids(tmp_path):
    scan = load_scan("proc-1")
    labels = SceneLabels.read(scan.folder / "semantics.json")
    assert labels.instances and set(labels.parts.values()) <= {i.id for i in labels.instances}
    labels.write(tmp_path / "s.json")
    again = SceneLabels.read(tmp_path / "s.json")
    assert again == labels
    text = (tmp_path / "s.json").read_text().replace('"mpcat40":1,', '"mpcat40":99,', 1)
    (tmp_path / "bad.json").write_text(text)
    with pytest.raises(MalformedDataError, match="99"):
        SceneLabels.read(tmp_path / "bad.json")
