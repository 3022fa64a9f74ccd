"""Defect 2: damaged caches heal, unwritable caches are reported, permissions follow the umask."""

from __future__ import annotations

import logging
import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest

from havln_mj.scene.procedural.generate import generate_house, write_scan
from havln_mj.scene.scan import load_scan, scans_dir
from havln_mj.sim.simulator import Simulator


def test_a_truncated_proxy_mesh_is_rebuilt(fresh_cache, graph_dir, small_scan, caplog):
    good = load_scan(small_scan, connectivity_dir=graph_dir)
    mesh = good.folder / "mesh.glb"
    expected = mesh.read_bytes()
    mesh.write_bytes(expected[: len(expected) // 2])
    with caplog.at_level(logging.WARNING):
        again = load_scan(small_scan, connectivity_dir=graph_dir)
    assert "damaged" in caplog.text and "mesh.glb" in caplog.text
    assert mesh.read_bytes() == expected
    assert len(again.mesh_parts) > 0


@pytest.mark.parametrize(
    "deleted", [("boxes.json",), ("regions.json",), ("boxes.json", "regions.json")]
)
def test_a_procedural_house_missing_files_is_rebuilt(fresh_cache, caplog, deleted):
    good = load_scan("proc-4")
    expected = {name: (good.folder / name).read_bytes() for name in deleted}
    for name in deleted:
        (good.folder / name).unlink()
    with caplog.at_level(logging.WARNING):
        again = load_scan("proc-4")
    assert "damaged" in caplog.text
    assert {name: (again.folder / name).read_bytes() for name in deleted} == expected
    # Box collision (not a silent switch to CoACD) and labelled regions for the people.
    assert again.boxes is not None and again.regions.to_json() == good.regions.to_json()


def test_a_healed_house_has_its_people(fresh_cache):
    folder = load_scan("proc-4").folder
    (folder / "boxes.json").unlink()
    (folder / "regions.json").unlink()
    sim = Simulator(humans=True)
    sim.setRenderingEnabled(False)
    sim.initialize()
    sim.newRandomEpisode(["proc-4"])
    assert len(sim.crowd("proc-4")) > 0
    sim.close()


def test_a_scan_folder_without_regions_is_loaded_with_a_warning(tmp_path, caplog):
    folder = tmp_path / "house"
    write_scan(generate_house(4), folder)
    (folder / "regions.json").unlink()
    with caplog.at_level(logging.WARNING):
        sim = Simulator(humans=True)
        sim.setRenderingEnabled(False)
        sim.initialize()
        sim.newRandomEpisode([str(folder)])
    assert "no regions.json" in caplog.text
    assert sim.scan(str(folder)).regions.levels  # one unlabelled region per storey
    sim.close()


def test_a_cache_path_that_is_a_file_is_reported_once(tmp_path, monkeypatch, caplog):
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("")
    monkeypatch.setenv("HAVLN_CACHE", str(blocker))
    with caplog.at_level(logging.WARNING):
        first = load_scan("proc-5")
        second = load_scan("proc-5")
    warnings = [r for r in caplog.records if "cannot be written" in r.getMessage()]
    assert len(warnings) == 1
    assert str(blocker) in warnings[0].getMessage() and "HAVLN_CACHE" in warnings[0].getMessage()
    assert first.graph.nodes == second.graph.nodes
    assert blocker.is_file()


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_a_read_only_cache_is_reported_once(tmp_path, monkeypatch, caplog):
    cache = tmp_path / "read-only"
    cache.mkdir(mode=0o555)
    monkeypatch.setenv("HAVLN_CACHE", str(cache))
    with caplog.at_level(logging.WARNING):
        assert load_scan("proc-5").graph.num_nodes > 0
    assert "cannot be written" in caplog.text and str(cache) in caplog.text


@pytest.mark.parametrize("umask", [0o022, 0o002])
def test_cache_folders_and_files_follow_the_umask(fresh_cache, umask):
    old = os.umask(umask)
    try:
        folder = load_scan("proc-6").folder
    finally:
        os.umask(old)
    for path in [folder.parent, folder]:
        assert stat.S_IMODE(path.stat().st_mode) == 0o777 & ~umask, path
    for path in folder.iterdir():
        assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~umask, path


def _session_alive(sid: int) -> bool:
    """Whether a process of session ``sid`` still runs (zombies not yet reaped have ended)."""
    for stat_file in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat_file.read_text().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            continue
        if fields[0] != "Z" and int(fields[3]) == sid:  # state, ppid, pgrp, session
            return True
    return False


def test_a_killed_scenes_build_leaves_nothing_after_the_next_build(fresh_cache):
    scans = fresh_cache / "scans"
    # Start the build in its own session, so the kill reaches its worker processes too.
    proc = subprocess.Popen(
        [sys.executable, "-m", "havln_mj.cli", "scenes", "build", "proc-8", "--workers", "1"],
        cwd=fresh_cache.parent,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    deadline = time.monotonic() + 120
    try:
        while not (scans.is_dir() and any(p.name.startswith(".proc-8.") for p in scans.iterdir())):
            assert proc.poll() is None and time.monotonic() < deadline, "no staging folder seen"
            time.sleep(0.005)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    assert any(p.name.startswith(".proc-8.") for p in scans.iterdir())  # what the kill left
    while _session_alive(proc.pid):  # the killed worker processes, until they have ended
        assert time.monotonic() < deadline
        time.sleep(0.01)
    load_scan("proc-8")
    assert sorted(p.name for p in scans_dir().iterdir()) == ["proc-8"]
