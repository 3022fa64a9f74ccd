"""R2R / HA-R2R loading, validation, writing, and HA3D's annotation rules."""

from __future__ import annotations

import json

import numpy as np
import pytest

from havln_mj.errors import (
    InvalidArgumentError,
    MalformedDataError,
    MissingDataError,
    UnknownScanError,
    UnknownViewpointError,
)
from havln_mj.scene.connectivity import Connectivity, write_connectivity
from havln_mj.scene.navgraph import NavGraph
from havln_mj.tasks.annotate import crux_points, humans_on_path, rel_pos
from havln_mj.tasks.datasets import load_dataset, resolve_dataset_path, write_dataset
from havln_mj.tasks.episodes import Episode, HumanOnPath

SCAN = "toyScan0001"
VPS = ["vp_a", "vp_b", "vp_c", "vp_d"]


@pytest.fixture
def conn_dir(tmp_path):
    """A made-up scan: a-b-c in a line 2 m apart, d excluded; everyone sees everyone."""
    n = len(VPS)
    poses = np.tile(np.eye(4), (n, 1, 1))
    for i in range(n):
        poses[i, 0, 3] = 2.0 * i
        poses[i, 2, 3] = 1.5
    unob = np.zeros((n, n), bool)
    for i in range(2):
        unob[i, i + 1] = unob[i + 1, i] = True
    visible = ~np.eye(n, dtype=bool)
    c = Connectivity(VPS, poses, [True, True, True, False], visible, unob, [1.5] * n)
    folder = tmp_path / "conn"
    write_connectivity(folder / f"{SCAN}_connectivity.json", c)
    return folder


def _entry(**over):
    entry = {
        "distance": 4.0,
        "scan": SCAN,
        "path_id": 7,
        "path": ["vp_a", "vp_b", "vp_c"],
        "heading": 1.5,
        "instructions": ["go", "walk", "move"],
    }
    entry.update(over)
    return entry


def _write(tmp_path, entries, name="data.json"):
    path = tmp_path / name
    path.write_text(json.dumps(entries))
    return path


# ---------------------------------------------------------------------- real files


def test_r2r_val_seen_counts_and_ids(shared_data):
    ds = load_dataset(
        shared_data / "r2r" / "R2R_val_seen.json",
        connectivity_dir=shared_data / "mp3d_connectivity",
    )
    assert len(ds) == 340 and ds.num_instructions == 1021
    ids = [i.instr_id for i in ds.instructions]
    assert len(set(ids)) == 1021
    first = ds[0]
    assert ids[:3] == [f"{first.path_id}_{k}" for k in range(3)]
    instr = ds.instruction(f"{first.path_id}_1")
    assert instr.text == first.instructions[1] and instr.episode is first and instr.k == 1
    assert all(4 <= len(e.path) <= 7 and e.humans is None for e in ds)


def test_split_names_resolve_in_the_shared_layout(shared_data, monkeypatch):
    monkeypatch.setenv("HAVLN_VLN_DATA", str(shared_data))
    assert resolve_dataset_path("val_seen").name == "R2R_val_seen.json"
    assert resolve_dataset_path("HA_val_seen").name == "HA_val_seen.json"
    test = load_dataset("R2R_test", connectivity_dir=shared_data / "mp3d_connectivity")
    assert len(test) == 1391 and test.num_instructions == 4173
    assert all(len(e.path) == 1 and e.distance is None for e in test)


def test_ha_val_seen_counts_and_round_trip(shared_data, tmp_path):
    src = shared_data / "ha_r2r" / "HA_val_seen.json"
    ds = load_dataset(src, connectivity_dir=shared_data / "mp3d_connectivity")
    assert len(ds) == 340 and ds.num_instructions == 1021
    assert sum(bool(e.humans) for e in ds) == 268
    assert all(e.crux_points is not None for e in ds)
    assert sum(e.rel_pos_descriptions is not None for e in ds) == 268
    out = tmp_path / "copy.json"
    write_dataset(ds, out)
    assert json.loads(out.read_text()) == json.loads(src.read_text())
    assert load_dataset(out).episodes == ds.episodes


def test_ha3d_rules_rebuild_the_ha_r2r_annotations(shared_data):
    ds = load_dataset(shared_data / "ha_r2r" / "HA_val_seen.json")
    placements = json.loads((shared_data / "ha3d" / "human_placements.json").read_text())
    graphs = {}
    for e in ds:
        g = graphs.get(e.scan) or graphs.setdefault(
            e.scan,
            NavGraph.from_file(shared_data / "mp3d_connectivity" / f"{e.scan}_connectivity.json"),
        )
        assert humans_on_path(e.path, g, placements[e.scan]) == e.humans, e.path_id
        assert crux_points(e.path, g) == e.crux_points, e.path_id


# ---------------------------------------------------------------------- made-up files


def test_round_trip_keeps_unknown_keys(tmp_path, conn_dir):
    entries = [
        _entry(
            human=[
                {"human_viewpoint": "vp_d", "human_rel_pos": "Obstacle", "human_description": "x"}
            ],
            crux_points=["vp_a", "vp_c"],
            my_key={"nested": [1, 2]},
        ),
        _entry(path_id=8, distance=2.0, path=["vp_b", "vp_a"], instructions=[]),
    ]
    src = _write(tmp_path, entries)
    ds = load_dataset(src, connectivity_dir=conn_dir)
    assert ds[0].humans == (HumanOnPath("vp_d", "Obstacle", "x"),)
    assert ds[0].extra == {"my_key": {"nested": [1, 2]}}
    assert ds[1].humans is None and ds[1].crux_points is None
    out = tmp_path / "out.json"
    write_dataset(ds.episodes, out)
    assert json.loads(out.read_text()) == entries
    assert list(json.loads(out.read_text())[0]) == [*entries[0]]  # the files' key order
    assert load_dataset(out).episodes == ds.episodes


def test_unknown_scan_names_file_path_id_and_suggestion(tmp_path, conn_dir):
    src = _write(tmp_path, [_entry(scan="toyScan0002")])
    with pytest.raises(UnknownScanError, match=r"data\.json.*path_id 7.*toyScan0002.*toyScan0001"):
        load_dataset(src, connectivity_dir=conn_dir)
    assert load_dataset(src, connectivity_dir=conn_dir, validate=False)[0].scan == "toyScan0002"


def test_unknown_and_excluded_viewpoints(tmp_path, conn_dir):
    src = _write(tmp_path, [_entry(path=["vp_a", "vp_bb"])])
    with pytest.raises(UnknownViewpointError, match=r"path_id 7.*path\[1\] 'vp_bb'.*'vp_b'"):
        load_dataset(src, connectivity_dir=conn_dir)
    src = _write(tmp_path, [_entry(path=["vp_c", "vp_d"])])
    with pytest.raises(UnknownViewpointError, match="excluded"):
        load_dataset(src, connectivity_dir=conn_dir)


def test_path_steps_must_be_edges(tmp_path, conn_dir):
    src = _write(tmp_path, [_entry(path=["vp_a", "vp_c"])])
    with pytest.raises(MalformedDataError, match="not an edge"):
        load_dataset(src, connectivity_dir=conn_dir)


@pytest.mark.parametrize(
    ("bad", "match"),
    [
        ({"path_id": "7"}, "path_id"),
        ({"path": []}, "'path' must not be empty"),
        ({"heading": None}, "'heading'"),
        ({"instructions": "go"}, "'instructions'"),
        ({"human": [{"human_viewpoint": "vp_a", "human_rel_pos": "Near"}]}, "human"),
        (
            {"human": [{"human_viewpoint": "a", "human_rel_pos": "Near", "human_description": ""}]},
            "'Near' is not one of Beginning",
        ),
    ],
)
def test_schema_errors(tmp_path, bad, match):
    src = _write(tmp_path, [_entry(**bad)])
    with pytest.raises(MalformedDataError, match=match):
        load_dataset(src)


def test_file_level_errors(tmp_path):
    with pytest.raises(MissingDataError):
        load_dataset(tmp_path / "nope.json")
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(MalformedDataError, match="not valid JSON"):
        load_dataset(tmp_path / "bad.json")
    with pytest.raises(MalformedDataError, match="not unique"):
        load_dataset(_write(tmp_path, [_entry(), _entry()]))
    with pytest.raises(InvalidArgumentError, match="val_seen"):
        load_dataset("val_sen", data_dir=tmp_path)
    with pytest.raises(MissingDataError, match=r"R2R_val_seen\.json"):
        load_dataset("val_seen", data_dir=tmp_path)
    (tmp_path / "HA_train.json").write_text(json.dumps([_entry()]))
    assert len(load_dataset("HA_train", data_dir=tmp_path)) == 1


def test_instruction_lookup_errors():
    e = Episode(3, SCAN, ("vp_a",), 0.0, ("only",))
    assert e.instruction(0).instr_id == "3_0"
    with pytest.raises(InvalidArgumentError, match="0–0"):
        e.instruction(1)


def test_rel_pos_rule(conn_dir):
    g = NavGraph.from_file(conn_dir / f"{SCAN}_connectivity.json")
    path = ["vp_a", "vp_b", "vp_c"]
    assert rel_pos("vp_a", path, g) == "Beginning"
    assert rel_pos("vp_b", path, g) == "Obstacle"
    assert rel_pos("vp_c", path, g) == "End"
    assert rel_pos("vp_d", path, g) == "Around"  # 2 m past the goal
    assert rel_pos("vp_d", ["vp_a"], g) == "Around"
    # A copy where nobody sees d: d is not linked.
    c = g.connectivity
    vis = c.visible.copy()
    vis[:, 3] = False
    blind = NavGraph(Connectivity(c.ids, c.poses, c.included, vis, c.unobstructed, c.heights))
    assert rel_pos("vp_d", path, blind) is None
    assert humans_on_path(path, blind, {"vp_d": ["r:x", 0, 0.0], "vp_b": "r:y"}) == (
        HumanOnPath("vp_b", "Obstacle", "r:y"),
    )
