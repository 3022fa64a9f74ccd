"""Matterport3D support on made-up files in the real formats (the real data is licensed).

Covers the ``.house`` parser, finding a scan in both dataset layouts, the frame check and the
up axis of glb meshes.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import trimesh

from havln_mj.errors import (
    FrameMismatchError,
    MalformedDataError,
    MissingDataError,
    UnknownSceneError,
)
from havln_mj.scene.connectivity import Connectivity
from havln_mj.scene.matterport.frame import check_frame, sample_viewpoints
from havln_mj.scene.matterport.house import read_house
from havln_mj.scene.matterport.layout import (
    ENV_VAR,
    MatterportFiles,
    find_matterport_files,
    resolve_mp3d_root,
)
from havln_mj.scene.mesh import load_mesh_parts, parts_to_trimesh
from havln_mj.scene.regions import Regions

SCAN = "ab12CD34ef5"
VP_A = "0123456789abcdef0123456789abcdef"
VP_B = "fedcba9876543210fedcba9876543210"
VP_DIGITS = "00000000000000000000000000000042"  # a uuid made only of digits
VP_NOWHERE = "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa"  # region -1

# A made-up two-room house in the real .house format: one level, a bedroom whose floor
# surface is listed clockwise, a room with an unknown label and a degenerate surface, one
# portal, four panoramas, two categories, three objects (one outside any region).
HOUSE = f"""ASCII 1.1
H  madeup  house  1 4 6 2 1 3 2 2 1 1  0 0 0 0 0  0 0 -0.05 8 4 2.9  0 0 0 0 0
L  0 2 -  4 2 1.2  0 0 -0.05 8 4 2.9  0 0 0 0 0
R  0 0 0 0 b  2 2 0  0 0 -0.05 4 4 2.9  2.9  0 0 0 0
R  1 0 0 0 q  6 2 0  4 0 -0.05 8 4 2.9  2.8  0 0 0 0
P  0 0 1 d  3.9 1.5 0  4.1 2.5 2.1  0 0 0 0
S  0 0 0 f  2 2 0  0 0 1  0 0 0 4 4 0  0 0 0 0 0
S  1 1 0 f  6 2 0  0 0 1  4 0 0 8 4 0  0 0 0 0 0
V  0 0 f  0 0 0  0 0 1  0 0 0
V  1 0 f  0 4 0  0 0 1  0 0 0
V  2 0 f  4 4 0  0 0 1  0 0 0
V  3 0 f  4 0 0  0 0 1  0 0 0
V  4 1 f  4 0 0  0 0 1  0 0 0
V  5 1 f  8 0 0  0 0 1  0 0 0
P  {VP_A}  0 0 0  2 2 1.5  0 0 0 0 0
P  {VP_B}  1 1 0  6 2 1.5  0 0 0 0 0
P  {VP_DIGITS}  2 1 0  7 3 1.5  0 0 0 0 0
P  {VP_NOWHERE}  3 -1 0  9 9 1.5  0 0 0 0 0
I  0 0 {VP_A}_i0_0 0 0  1 0 0 2 0 1 0 2 0 0 1 1.5 0 0 0 1  1 0 0 0 1 0 0 0 1  1280 1024  \
2 2 1.5  0 0 0 0 0
C  0 5 kitchen#cabinet 7 cabinet 0 0 0 0 0
C  1 2 chair 3 chair 0 0 0 0 0
O  0 0 1  1 1 0.5  1 0 0  0 1 0  0.3 0.4 0.5  0 0 0 0 0 0 0 0
O  1 1 0  6 2 1  0.70710678 0.70710678 0  -0.70710678 0.70710678 0  1 0.5 1  0 0 0 0 0 0 0 0
O  2 -1 -1  9 9 1  1 0 0  0 1 0  0.1 0.1 0.1  0 0 0 0 0 0 0 0
E  0 0 1 0.5  1 1 0.5  0.7 0.6 0 1.3 1.4 1  0 0 0 0 0
"""


def _write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


# ----------------------------------------------------------------------------- .house


def test_house_levels_regions_and_polygons(tmp_path):
    regions = read_house(_write(tmp_path / "x.house", HOUSE))
    assert regions.levels[0].index == 0
    assert regions.levels[0].z_floor == pytest.approx(-0.05)
    assert regions.levels[0].z_ceiling == pytest.approx(2.9)
    bedroom, other = regions.regions
    assert (bedroom.index, bedroom.level, bedroom.label, bedroom.name) == (0, 0, "b", "bedroom")
    assert bedroom.height == pytest.approx(2.9)
    np.testing.assert_allclose(bedroom.bbox, [0, 0, -0.05, 4, 4, 2.9])
    # Listed clockwise in the file; returned counter-clockwise (positive shoelace area).
    poly = bedroom.polygon
    assert poly.shape == (4, 2)
    area = 0.5 * np.sum(poly[:, 0] * np.roll(poly[:, 1], -1) - np.roll(poly[:, 0], -1) * poly[:, 1])
    assert area == pytest.approx(16.0)
    assert bedroom.contains(np.array([1.0, 3.0])) and not bedroom.contains(np.array([5.0, 1.0]))
    # Unknown label code 'q' becomes '-'; a 2-vertex surface falls back to the bbox.
    assert other.label == "-" and other.height == pytest.approx(2.8)
    np.testing.assert_allclose(other.polygon, [[4, 0], [8, 0], [8, 4], [4, 4]])


def test_house_panoramas_and_portals_share_p(tmp_path):
    regions = read_house(_write(tmp_path / "x.house", HOUSE))
    # The portal line is not a viewpoint; the all-digit uuid is one (the header has 1 portal);
    # the panorama outside every region is dropped.
    assert regions.viewpoint_region == {VP_A: 0, VP_B: 1, VP_DIGITS: 1}
    assert regions.region_of(VP_A).label == "b"
    kept = read_house(tmp_path / "x.house", viewpoint_ids=[VP_B, "not-there"])
    assert kept.viewpoint_region == {VP_B: 1}


def test_house_objects_become_axis_aligned_boxes(tmp_path):
    regions = read_house(_write(tmp_path / "x.house", HOUSE))
    assert [o.index for o in regions.objects] == [0, 1]  # object 2 has no region
    chair, cabinet = regions.objects
    assert (chair.category, chair.mpcat40, chair.region) == ("chair", "chair", 0)
    np.testing.assert_allclose(chair.bbox, [0.7, 0.6, 0.0, 1.3, 1.4, 1.0])
    assert chair.yaw == pytest.approx(0.0)
    # '#' in category names reads as a space; the 45° box grows to its axis-aligned extent.
    assert (cabinet.category, cabinet.mpcat40, cabinet.region) == ("kitchen cabinet", "cabinet", 1)
    half = 1.5 / math.sqrt(2)
    np.testing.assert_allclose(
        cabinet.bbox, [6 - half, 2 - half, 0.0, 6 + half, 2 + half, 2.0], atol=1e-6
    )
    assert cabinet.yaw == pytest.approx(math.pi / 4)


def test_house_round_trips_through_the_regions_file(tmp_path):
    regions = read_house(_write(tmp_path / "x.house", HOUSE))
    regions.write(tmp_path / "regions.json")
    again = Regions.read(tmp_path / "regions.json")
    assert again.viewpoint_region == regions.viewpoint_region
    assert [r.label for r in again.regions] == ["b", "-"]
    assert [o.category for o in again.objects] == ["chair", "kitchen cabinet"]


def test_house_header_must_be_ascii_1_1(tmp_path):
    path = _write(tmp_path / "bad.house", HOUSE.replace("ASCII 1.1", "ASCII 1.0", 1))
    with pytest.raises(MalformedDataError, match=r"bad\.house.*'ASCII 1\.1'.*'ASCII 1\.0'"):
        read_house(path)
    with pytest.raises(MalformedDataError, match="found ''"):
        read_house(_write(tmp_path / "empty.house", ""))
    with pytest.raises(MissingDataError, match="not found"):
        read_house(tmp_path / "absent.house")


@pytest.mark.parametrize(
    ("old", "new", "match"),
    [
        ("2.9  2.9  0 0 0 0", "2.9  tall  0 0 0 0", r":4: R line: height \(field 15\).*'tall'"),
        ("R  1 0 0 0 q  6 2 0  4 0 -0.05 8 4 2.9  2.8  0 0 0 0", "R  1 0 0", r":5: R line: needs"),
        ("O  1 1 0  6 2 1", "O  1 1 9  6 2 1", r":23: O line: .*category 9"),
        ("C  1 2 chair", "X  1 2 chair", r":21: X line: unknown record type 'X'"),
        ("P  0 0 1 d  3.9 1.5 0  4.1 2.5 2.1  0 0 0 0", "P  0 0 1", r":6: P line: a portal"),
        ("P  0 0 1 d", "P  0 0 one d", r":6: P line: region1_index \(field 3\).*'one'"),
        ("V  3 0 f  4 0 0", "V  3 0 f  4 nan 0", r":12: V line: position\[1\].*finite"),
    ],
)
def test_house_malformed_lines_name_file_line_and_field(tmp_path, old, new, match):
    assert old in HOUSE
    path = _write(tmp_path / "scan.house", HOUSE.replace(old, new, 1))
    with pytest.raises(MalformedDataError, match=r"scan\.house" + match):
        read_house(path)


# ----------------------------------------------------------------------------- layout


def _raw_scan(base: Path) -> None:
    _write(base / "matterport_mesh" / "m3sh1d" / "m3sh1d.obj", "v 0 0 0\n")
    _write(base / "house_segmentations" / f"{SCAN}.house", HOUSE)
    _write(base / "house_segmentations" / f"{SCAN}.ply", "ply\n")


def _habitat_scan(base: Path) -> None:
    _write(base / f"{SCAN}.glb", "glb")
    _write(base / f"{SCAN}.house", HOUSE)


@pytest.mark.parametrize("sub", [("v1", "scans"), ("scans",), ()])
def test_finds_raw_layout(tmp_path, sub):
    _raw_scan(tmp_path.joinpath(*sub, SCAN))
    files = find_matterport_files(SCAN, tmp_path)
    base = tmp_path.joinpath(*sub, SCAN)
    assert files == MatterportFiles(
        SCAN,
        "raw",
        base / "matterport_mesh" / "m3sh1d" / "m3sh1d.obj",
        base / "house_segmentations" / f"{SCAN}.house",
        base / "house_segmentations" / f"{SCAN}.ply",
    )
    assert files.up == "z"


@pytest.mark.parametrize("sub", [("scene_datasets", "mp3d"), ("mp3d",), ()])
def test_finds_habitat_layout(tmp_path, sub):
    base = tmp_path.joinpath(*sub, SCAN)
    _habitat_scan(base)
    files = find_matterport_files(SCAN, str(tmp_path))
    assert files == MatterportFiles(
        SCAN, "habitat", base / f"{SCAN}.glb", base / f"{SCAN}.house", None
    )
    assert files.up == "z"


def test_prefers_a_candidate_with_the_house_file(tmp_path):
    _write(tmp_path / "v1" / "scans" / SCAN / "matterport_mesh" / "a" / "a.obj", "v 0 0 0\n")
    _habitat_scan(tmp_path / "mp3d" / SCAN)
    files = find_matterport_files(SCAN, tmp_path)
    assert files.layout == "habitat" and files.house is not None
    (tmp_path / "mp3d" / SCAN / f"{SCAN}.house").unlink()
    files = find_matterport_files(SCAN, tmp_path)
    assert files.layout == "raw" and files.house is None and files.ply is None


def test_missing_scan_lists_every_path_and_how_to_get_the_data(tmp_path):
    _write(tmp_path / "v1" / "scans" / SCAN / "matterport_mesh.zip", "zip")
    with pytest.raises(MissingDataError) as info:
        find_matterport_files(SCAN, tmp_path)
    message = str(info.value)
    expected = [
        tmp_path / "v1" / "scans" / SCAN / "house_segmentations" / f"{SCAN}.house",
        tmp_path / "scans" / SCAN / "matterport_mesh" / "<mesh_id>" / "<mesh_id>.obj",
        tmp_path / SCAN / "house_segmentations" / f"{SCAN}.house",
        tmp_path / "scene_datasets" / "mp3d" / SCAN / f"{SCAN}.glb",
        tmp_path / "mp3d" / SCAN / f"{SCAN}.house",
        tmp_path / SCAN / f"{SCAN}.glb",
    ]
    for path in expected:
        assert str(path) in message
    assert "https://niessner.github.io/Matterport/" in message
    assert "Terms of Use" in message and "--mp3d-dir" in message and ENV_VAR in message
    assert "matterport_mesh.zip" in message  # still zipped: say so


def test_root_from_environment(tmp_path, monkeypatch):
    monkeypatch.delenv(ENV_VAR, raising=False)
    assert resolve_mp3d_root(None) is None
    with pytest.raises(MissingDataError, match=r"no folder was given.*niessner"):
        find_matterport_files(SCAN, None)
    monkeypatch.setenv(ENV_VAR, str(tmp_path))
    assert resolve_mp3d_root(None) == tmp_path
    assert resolve_mp3d_root(tmp_path / "other") == tmp_path / "other"
    _habitat_scan(tmp_path / SCAN)
    assert find_matterport_files(SCAN, None).layout == "habitat"
    with pytest.raises(MissingDataError, match="does not exist"):
        find_matterport_files(SCAN, tmp_path / "nowhere")


@pytest.mark.parametrize("bad", ["", "../etc", "a/b", "x y"])
def test_scan_id_must_be_a_plain_name(tmp_path, bad):
    with pytest.raises(UnknownSceneError):
        find_matterport_files(bad, tmp_path)


# ----------------------------------------------------------------------------- frame


def _room() -> trimesh.Trimesh:
    """A 10 m × 8 m room: floor top at z = 0, ceiling underside at z = 2.8, a table."""
    floor = trimesh.creation.box(extents=[10, 8, 0.1])
    floor.apply_translation([5, 4, -0.05])
    ceiling = trimesh.creation.box(extents=[10, 8, 0.1])
    ceiling.apply_translation([5, 4, 2.85])
    table = trimesh.creation.box(extents=[1.0, 1.0, 0.05])
    table.apply_translation([9, 7, 0.75])
    return trimesh.util.concatenate([floor, ceiling, table])


def _connectivity(n: int = 30, z: float = 1.5, height: float = 1.5) -> Connectivity:
    rng = np.random.default_rng(0)
    xy = rng.uniform([0.5, 0.5], [8.0, 6.0], size=(n, 2))
    poses = np.tile(np.eye(4), (n, 1, 1))
    poses[:, :2, 3] = xy
    poses[:, 2, 3] = z
    included = np.ones(n, dtype=bool)
    included[3] = False
    flags = np.zeros((n, n), dtype=bool)
    ids = [f"{k:032x}" for k in range(n)]
    return Connectivity(ids, poses, included, flags, flags, np.full(n, height))


def test_frame_check_passes_on_a_consistent_scan():
    report = check_frame(_room(), _connectivity())
    assert report.checked == 29 and report.agreeing == 29 and report.missed == 0
    assert report.fraction == 1.0
    assert abs(report.median_offset) < 1e-6


def test_frame_check_samples_at_most_max_viewpoints_deterministically():
    conn = _connectivity(n=30)
    picks = sample_viewpoints(conn, 10)
    assert len(picks) == 10 and 3 not in picks
    np.testing.assert_array_equal(picks, sample_viewpoints(conn, 10))
    assert check_frame(_room(), conn, max_viewpoints=10).checked == 10


def test_frame_check_reports_an_offset_mesh():
    room = _room()
    room.apply_translation([0, 0, 0.6])  # floor now 0.6 m above where the viewpoints say
    with pytest.raises(FrameMismatchError, match=r"0/29 .*\(0%\).*offset.*\+0\.60 m") as info:
        check_frame(room, _connectivity())
    assert "different scan" in str(info.value) and "y-up" in str(info.value)


def test_frame_check_reports_a_y_up_mesh():
    room = _room()
    room.vertices = room.vertices @ np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]]).T  # z-up -> y-up
    with pytest.raises(FrameMismatchError, match=r"no surface below.*up='y'"):
        check_frame(room, _connectivity())


def test_frame_check_tolerates_a_few_bad_viewpoints():
    conn = _connectivity(n=30)
    heights = conn.heights.copy()
    heights[:4] = 0.5  # 3 included viewpoints now expect the floor 1 m higher
    conn = Connectivity(
        conn.ids, conn.poses, conn.included, conn.visible, conn.unobstructed, heights
    )
    report = check_frame(_room(), conn)
    assert (report.checked, report.agreeing) == (29, 26)
    with pytest.raises(FrameMismatchError, match=r"26/29"):
        check_frame(_room(), conn, min_fraction=0.95)


# ----------------------------------------------------------------------------- glb up axis


def test_glb_written_by_trimesh_keeps_its_frame(tmp_path):
    path = tmp_path / "zup.glb"
    path.write_bytes(_room().export(file_type="glb"))
    (part,) = load_mesh_parts(path)
    np.testing.assert_allclose(part.vertices, _room().vertices, atol=1e-5)


def test_y_up_glb_is_read_back_z_up(tmp_path):
    room = _room()
    y_up = room.copy()
    y_up.vertices = room.vertices @ np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]]).T
    assert y_up.bounds[1][1] == pytest.approx(2.9)  # the ceiling's top is now at y = 2.9
    path = tmp_path / "yup.glb"
    path.write_bytes(y_up.export(file_type="glb"))
    (part,) = load_mesh_parts(path, up="y")
    np.testing.assert_allclose(part.vertices, room.vertices, atol=1e-5)
    conn = _connectivity()
    assert check_frame(parts_to_trimesh([part]), conn).agreeing == 29
    (as_stored,) = load_mesh_parts(path)  # read without the y-up rule: caught
    with pytest.raises(FrameMismatchError):
        check_frame(parts_to_trimesh([as_stored]), conn)


def test_unknown_up_axis_is_rejected(tmp_path):
    path = tmp_path / "zup.glb"
    path.write_bytes(_room().export(file_type="glb"))
    with pytest.raises(ValueError, match=r"up must be one of \('z', 'y'\), got 'x'"):
        load_mesh_parts(path, up="x")
