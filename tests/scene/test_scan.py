"""Scan loading: the procedural cache (miss, hit, corruption, staleness) and scene ids."""

from __future__ import annotations

import json
import logging

import pytest

from havln_mj.errors import MalformedDataError, MissingDataError, UnknownSceneError
from havln_mj.scene import scan as scan_module
from havln_mj.scene.ids import parse_scene_id
from havln_mj.scene.scan import load_scan, read_scan_folder, scans_dir


@pytest.fixture
def builds(monkeypatch):
    calls = []
    real = scan_module._build_procedural

    def counting(seed, target):
        calls.append(seed)
        real(seed, target)

    monkeypatch.setattr(scan_module, "_build_procedural", counting)
    return calls


def test_cache_miss_then_hit(builds):
    first = load_scan("proc-101")
    assert builds == [101]
    second = load_scan("proc-101")
    assert builds == [101]
    assert second.graph.nodes == first.graph.nodes
    assert first.folder == scans_dir() / "proc-101"
    assert not [p for p in scans_dir().iterdir() if p.name.startswith(".")]  # no staging left


@pytest.mark.parametrize(
    "damage",
    [
        ("connectivity.json", b'[{"image_id": "x"'),
        ("regions.json", b"not json"),
        ("mesh.glb", b"glTF garbage"),
        ("boxes.json", b'{"boxes": [{"lo": [0, 0]}]}'),
    ],
)
def test_corrupt_cache_entry_is_rebuilt(builds, caplog, damage):
    name, content = damage
    good = load_scan("proc-102")
    expected = (good.folder / name).read_bytes()
    (good.folder / name).write_bytes(content)
    with caplog.at_level(logging.WARNING):
        again = load_scan("proc-102")
    assert "rebuilding" in caplog.text
    assert (again.folder / name).read_bytes() == expected
    assert again.graph.nodes == good.graph.nodes


def test_stale_generator_version_is_rebuilt(builds):
    scan = load_scan("proc-103")
    meta = json.loads((scan.folder / "scan.json").read_text())
    meta["generator_version"] = -1
    (scan.folder / "scan.json").write_text(json.dumps(meta))
    load_scan("proc-103")
    assert builds == [103, 103]


def test_unknown_scene_ids_fail_with_valid_forms_and_nearest():
    with pytest.raises(UnknownSceneError, match=r"proc-<seed>.*Did you mean 'proc-12'"):
        load_scan("proc12")
    with pytest.raises(UnknownSceneError, match="Did you mean '17DRP5sb8fy'"):
        parse_scene_id("17DRP5sb8f", known=["17DRP5sb8fy"])
    with pytest.raises(UnknownSceneError, match="valid forms"):
        parse_scene_id("")


def test_matterport_id_without_data_says_where_it_looked(monkeypatch):
    monkeypatch.delenv("HAVLN_MP3D_DIR", raising=False)
    monkeypatch.delenv("HAVLN_CONNECTIVITY_DIR", raising=False)
    with pytest.raises(MissingDataError, match=r"'1LXtFkjw3qL'.*--connectivity-dir.*--mp3d-dir"):
        load_scan("1LXtFkjw3qL")


def test_scan_folder_path_loads_and_bad_folders_fail(tmp_path):
    src = load_scan("proc-104").folder
    scan = load_scan(str(src))
    assert scan.kind == "procedural" and scan.graph.num_nodes > 0
    with pytest.raises(MissingDataError, match="mesh"):
        read_scan_folder(tmp_path)
    (tmp_path / "mesh.glb").write_bytes((src / "mesh.glb").read_bytes())
    (tmp_path / "connectivity.json").write_text('{"not": "a list"}')
    with pytest.raises(MalformedDataError, match="connectivity"):
        read_scan_folder(tmp_path)
