"""Defect 5 (in process): bad input refused early with a specific error; recovery after one.

The command-line calls of the defect run as subprocesses in ``test_cli_tracebacks.py``.
"""

from __future__ import annotations

import json
import logging
import re
from concurrent.futures import Future

import mujoco
import pytest

from havln_mj import cli
from havln_mj.commands import scenes as scene_commands
from havln_mj.errors import InvalidArgumentError, MalformedDataError, RenderingUnavailableError
from havln_mj.scene.scan import load_scan
from havln_mj.sim.simulator import Simulator
from havln_mj.tasks.datasets import load_dataset


def _no_edges(data):
    for entry in data:
        entry["unobstructed"] = [False] * len(data)


def _one_viewpoint(data):
    del data[1:]
    data[0]["visible"] = data[0]["unobstructed"] = [False]


def _one_point(data):
    for entry in data:
        entry["pose"][3] = entry["pose"][7] = entry["pose"][11] = 1.0


def _far_away(data):
    data[3]["pose"][3] = 1e12


def _zero_poses(data):
    for entry in data:
        entry["pose"] = [0.0] * 16


def _negative_height(data):
    data[2]["height"] = -1.5


DEGENERATE = {
    "no edges": (_no_edges, "no edge joins"),
    "one viewpoint": (_one_viewpoint, r"1 included viewpoint\(s\) of 1; at least 2"),
    "one point": (_one_point, "stand at one point"),
    "a coordinate of 1e12": (_far_away, r"entry 3 .* lies outside ±10000 m"),
    "all-zero poses": (_zero_poses, "entry 0 .* rigid camera-to-world transform"),
    "a negative height": (_negative_height, r"entry 2 .* height .* got -1\.5"),
}


@pytest.mark.parametrize("case", DEGENERATE)
def test_a_degenerate_graph_is_refused_with_a_specific_error(
    fresh_cache, graph_dir, small_scan, case
):
    damage, message = DEGENERATE[case]
    path = graph_dir / f"{small_scan}_connectivity.json"
    data = json.loads(path.read_text())
    damage(data)
    path.write_text(json.dumps(data))
    with pytest.raises(MalformedDataError, match=message):
        load_scan(small_scan, connectivity_dir=graph_dir)


class _InlinePool:
    """Runs submitted jobs at once, recording how many workers it was asked for."""

    def __init__(self, max_workers: int, asked: list[int]) -> None:
        asked.append(max_workers)

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        return None

    def submit(self, fn, *args) -> Future:
        future: Future = Future()
        try:
            future.set_result(fn(*args))
        except Exception as exc:
            future.set_exception(exc)
        return future


def _built(scene: str, *args) -> dict:
    """The summary row of a scene build that did nothing."""
    return {
        "scene": scene,
        "kind": "procedural",
        "viewpoints": 1,
        "collision": "boxes",
        "collision_geoms": 1,
        "edges_by_route": 0,
        "edges_by_flight": None,
        "unwalkable_edges": None,
        "seconds": 0.0,
    }


def test_scenes_build_starts_no_more_workers_than_scenes_and_cpus(monkeypatch, capsys):
    asked: list[int] = []
    monkeypatch.setattr(
        scene_commands,
        "ProcessPoolExecutor",
        lambda max_workers, **_: _InlinePool(max_workers, asked),
    )
    monkeypatch.setattr(scene_commands, "build_scene", _built)
    assert cli.main(["scenes", "build", "proc-0", "--workers", "100000"]) == 0
    assert asked == [1]
    assert "using 1 worker process, not 100000" in capsys.readouterr().err


def test_a_crash_in_one_scene_does_not_end_the_batch(monkeypatch, capsys):
    def build(scene, *args):
        if scene == "proc-1":
            raise ZeroDivisionError("a bug")
        return _built(scene)

    monkeypatch.setattr(
        scene_commands, "ProcessPoolExecutor", lambda max_workers, **_: _InlinePool(max_workers, [])
    )
    monkeypatch.setattr(scene_commands, "build_scene", build)
    assert cli.main(["scenes", "build", "proc-0", "proc-1", "proc-2"]) == 1
    out = capsys.readouterr().out
    assert "proc-1: FAILED unexpectedly (ZeroDivisionError: a bug)" in out
    assert "built 2 of 3 scenes" in out


def test_a_failed_resolution_change_leaves_the_simulator_usable(monkeypatch):
    real = mujoco.MjrContext

    def small_gpu(model, font):  # a GL whose offscreen buffers hold at most 1024 pixels a side
        if max(model.vis.global_.offwidth, model.vis.global_.offheight) > 1024:
            raise mujoco.FatalError("Could not allocate offscreen framebuffer")
        return real(model, font)

    monkeypatch.setattr(mujoco, "MjrContext", small_gpu)
    sim = Simulator(humans=False)
    sim.setCameraResolution(64, 48)
    sim.initialize()
    start = sim.graph("proc-0").nodes[0]
    sim.newEpisode(["proc-0"], [start], [0.0], [0.0])
    sim.setCameraResolution(2048, 2048)
    with pytest.raises(RenderingUnavailableError, match="2048×2048"):
        sim.makeAction([0], [0.5], [0.0])
    sim.setCameraResolution(96, 64)
    sim.makeAction([0], [0.5], [0.0])
    assert sim.getState()[0].rgb.shape == (64, 96, 3)
    sim.close()


def test_an_impossible_resolution_is_refused_at_once():
    sim = Simulator()
    with pytest.raises(InvalidArgumentError, match=r"\[1, 8192\]"):
        sim.setCameraResolution(10**9, 10**9)


def test_blank_instructions_and_paths_without_any_are_reported(tmp_path, caplog):
    entry = {"scan": "s", "path": ["a", "b"], "heading": 0.0, "distance": 1.0}
    data = [
        {**entry, "path_id": 1, "instructions": ["Walk ahead.", "  ", "Go."]},
        {**entry, "path_id": 2, "instructions": []},
    ]
    path = tmp_path / "R2R_x.json"
    path.write_text(json.dumps(data))
    with caplog.at_level(logging.WARNING):
        dataset = load_dataset(path)
    assert "1 instruction(s) are blank (1_1)" in caplog.text
    assert "1 path(s) have no instructions (path_id 2)" in caplog.text
    assert len(dataset.episodes) == 2  # reported, not dropped


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--width", "0"], r"--width must be in \[1, 8192\] pixels"),
        (["--vfov", "180"], r"--vfov must be in \(0, 180\) degrees"),
        (["--port", "70000"], r"--port must be in \[0, 65535\]"),
        (["--scene", "nope"], "unknown scene id 'nope'"),
        (["--placements", "."], "is a folder; give a JSON file"),
    ],
)
def test_annotate_checks_its_arguments_before_loading_anything(monkeypatch, capsys, argv, message):
    monkeypatch.setattr("havln_mj.scene.scan.load_scan", _must_not_run)
    assert _exit_code(["annotate", "--scene", "proc-0", *argv]) == 2
    assert re.search(message, capsys.readouterr().err)


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--seed", "-1"], r"--seed must be at least 0"),
        (["--frames", "0"], r"--frames must be at least 1"),
        (["--scene", "proc12"], "Did you mean 'proc-12'"),
    ],
)
def test_view_checks_its_arguments_before_opening_anything(monkeypatch, capsys, argv, message):
    monkeypatch.setattr("havln_mj.viewer.run_viewer", _must_not_run)
    assert _exit_code(["view", *argv]) == 2
    assert re.search(message, capsys.readouterr().err)


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--seed", "-1"], r"--seed must be at least 0, got -1"),
        (["--episodes-per-scene", "0"], r"--episodes-per-scene must be at least 1"),
        (["--scenes", "proc-0", "prc-2"], "unknown scene id 'prc-2'"),
        (["--out", "/dev/null"], "is a file; give a folder"),
    ],
)
def test_dataset_build_checks_its_arguments_before_building(monkeypatch, capsys, argv, message):
    monkeypatch.setattr("havln_mj.tasks.procedural.build_split", _must_not_run)
    assert _exit_code(["dataset", "build", "--scenes", "proc-0", "--split", "x", *argv]) == 2
    assert re.search(message, capsys.readouterr().err)


def _exit_code(argv: list[str]) -> int:
    """The exit code of ``havln_mj <argv>`` run in this process."""
    try:
        return cli.main(argv)
    except SystemExit as exc:  # argparse's usage errors
        return int(exc.code)


def _must_not_run(*args, **kwargs):
    raise AssertionError("work started before the arguments were checked")
