"""``python -m havln_mj.run`` end to end at small resolution."""

from __future__ import annotations

import contextlib
import json
import signal
import subprocess
import sys

import cv2

from havln_mj.run import main


def _run(out, width, height, fps):
    args = f"--scene proc-2 --episodes 2 --seed 4 --width {width} --height {height} --fps {fps}"
    return main([*args.split(), "--out", str(out)])


def test_cli_writes_video_map_and_summary(tmp_path):
    out = tmp_path / "run"
    assert _run(out, 96, 72, 4) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scene"] == "proc-2" and summary["scene_kind"] == "procedural"
    assert len(summary["episodes"]) == 2
    for ep in summary["episodes"]:
        assert ep["path"][0] == ep["start"] and ep["path"][-1] == ep["goal"]
        assert ep["steps"] == len(ep["path"]) - 1 >= 1
        assert abs(ep["path_length_m"] - ep["geodesic_m"]) < 1e-3  # shortest paths
        assert ep["frames"] >= ep["steps"]
    assert summary["steps"] == sum(ep["steps"] for ep in summary["episodes"])
    video = cv2.VideoCapture(str(out / "egocentric.mp4"))
    n, shape = 0, None
    while True:
        ok, frame = video.read()
        if not ok:
            break
        n, shape = n + 1, frame.shape
    assert n == summary["frames"] and shape == (72, 96, 3)
    topdown = cv2.imread(str(out / "topdown.png"))
    assert topdown is not None and topdown.std() > 5
    frame = cv2.imread(str(out / "frame.png"))
    assert frame.shape == (72, 96, 3) and frame.std() > 1

    # Same seed, same episodes.
    again = tmp_path / "again"
    assert _run(again, 32, 24, 2) == 0
    paths = [e["path"] for e in json.loads((again / "summary.json").read_text())["episodes"]]
    assert paths == [e["path"] for e in summary["episodes"]]


def test_unknown_scene_fails_at_once_with_the_nearest_match(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "havln_mj.run", "--scene", "proc_3", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 2
    assert "proc-<seed>" in proc.stderr and "Did you mean 'proc-3'" in proc.stderr
    assert not list(tmp_path.iterdir())  # nothing written


def test_people_are_counted_and_the_go1_walks_the_episodes(tmp_path):
    out = tmp_path / "go1"
    args = "--scene proc-0 --episodes 1 --seed 0 --width 64 --height 48 --fps 4 --robot go1"
    assert main([*args.split(), "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["people"] and all(p["activity"] and p["region"] for p in summary["people"])
    assert summary["human_collisions"] == sum(e["human_collisions"] for e in summary["episodes"])
    go1 = summary["go1"]
    (episode,) = go1["episodes"]
    assert episode["path"] == summary["episodes"][0]["path"]
    assert episode["reached"] and not episode["fell"] and go1["falls"] == 0
    assert all(s["end_error_m"] < 0.3 and s["arrived"] for s in episode["steps"])
    assert episode["go1_seconds"] > episode["point_body_seconds"] > 0
    video = cv2.VideoCapture(summary["files"]["go1_video"])
    ok, frame = video.read()
    assert ok and frame.shape == (48, 128, 3)  # head camera beside the chase view


def test_a_rerun_replaces_the_whole_folder_and_an_interrupted_one_changes_nothing(
    tmp_path, monkeypatch
):
    out = tmp_path / "run"
    base = f"--scene proc-0 --episodes 1 --seed 0 --width 32 --height 24 --fps 2 --out {out}"
    assert main([*base.split(), "--robot", "go1"]) == 0
    assert (out / "go1.mp4").exists()
    assert main(base.split()) == 0  # no GO1 this time: the old go1.mp4 must go
    summary = json.loads((out / "summary.json").read_text())
    assert not (out / "go1.mp4").exists() and "go1_video" not in summary["files"]
    assert sorted(p.name for p in out.iterdir()) == sorted(
        ["egocentric.mp4", "frame.png", "topdown.png", "summary.json"]
    )
    before = {p.name: p.read_bytes() for p in out.iterdir()}

    from havln_mj import recording

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(recording.Recording, "write_map", interrupted)
    assert main([*base.split(), "--seed", "3"]) == 130
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_a_ctrl_c_a_library_swallowed_still_leaves_the_folder_as_it_was(tmp_path, monkeypatch):
    out = tmp_path / "run"
    base = f"--scene proc-0 --episodes 1 --seed 0 --width 32 --height 24 --fps 2 --out {out}"
    assert main(base.split()) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}

    from havln_mj import recording

    def swallowing(*args, **kwargs):
        # As rtree's loader does with every exception while it loads its library.
        with contextlib.suppress(KeyboardInterrupt):
            signal.raise_signal(signal.SIGINT)

    monkeypatch.setattr(recording.Recording, "write_map", swallowing)
    handler = signal.getsignal(signal.SIGINT)
    assert main([*base.split(), "--seed", "3"]) == 130
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert signal.getsignal(signal.SIGINT) is handler  # the run put the handler back
