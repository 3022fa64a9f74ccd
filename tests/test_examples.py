"""Every script in examples/ runs as a user runs it (from another folder), small and fast."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _run(name: str, cwd: Path, *args: str) -> str:
    """Runs ``examples/<name>.py`` in ``cwd``; returns its output, failing with it on error."""
    done = subprocess.run(
        [sys.executable, str(EXAMPLES / f"{name}.py"), *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, f"{name} failed:\n{done.stdout}\n{done.stderr}"
    return done.stdout


def _needs(module: str) -> None:
    if importlib.util.find_spec(module) is None:
        pytest.skip(f"{module} is not installed (an optional extra)")


def test_mattersim_loop(tmp_path):
    out = _run("mattersim_loop", tmp_path, "--steps", "6")
    steps = re.findall(r"^step +(\d+) +at (\w+)", out, re.M)
    assert [int(s) for s, _ in steps] == list(range(1, 7))
    assert len({vp for _, vp in steps}) > 1  # it moved


def test_people_and_collisions(tmp_path):
    out = _run("people_and_collisions", tmp_path, "--steps", "4")
    assert re.search(r"person 0: .+ \(region \w\)", out)
    rows = re.findall(r"nearest person +([\d.]+|inf) m +isCrushed (\d) +by \[([\d, ]*)\]", out)
    assert len(rows) == 4
    for distance, flag, by in rows:  # the flag, the distance and the people agree
        assert (flag == "1") == (by != "")
        if abs(float(distance) - 1.0) > 0.01:  # printed to the centimetre
            assert (flag == "1") == (float(distance) < 1.0)
    # The walk heads for the viewpoint closest to someone: it comes within 1 m of them.
    flags = [int(flag) for _, flag, _ in rows]
    assert any(flags) and f"{sum(flags)} of 4 actions came within 1 m" in out


def test_render_rgbd(tmp_path):
    _run("render_rgbd", tmp_path, "--width", "96", "--height", "72", "--out", "renders")
    rgb = cv2.imread(str(tmp_path / "renders/rgb.png"), cv2.IMREAD_UNCHANGED)
    depth = cv2.imread(str(tmp_path / "renders/depth.png"), cv2.IMREAD_UNCHANGED)
    mask = cv2.imread(str(tmp_path / "renders/human_mask.png"), cv2.IMREAD_UNCHANGED)
    assert rgb.shape == (72, 96, 3) and rgb.dtype == np.uint8 and rgb.std() > 5
    assert depth.shape == (72, 96) and depth.dtype == np.uint16 and depth.max() > 4000  # > 1 m
    assert mask.shape == (72, 96) and 0 < (mask > 0).mean() < 0.5  # a person, seen
    assert depth[mask > 0].mean() < depth[mask == 0].mean()  # in front of the room


def test_go1_walk(tmp_path):
    out = _run("go1_walk", tmp_path, "--edges", "2")
    rows = re.findall(
        r"^(.{16}) arrived (True|False) +at (\w+) .* t = +([\d.]+) s +fell (\w+)", out, re.M
    )
    moves = [move.strip() for move, *_ in rows]
    assert moves[:3] == ["start", moves[1], moves[2]] and moves[1].startswith("to ")
    for move, arrived, at, _, _ in rows[1:3]:  # a graph move that arrives stands at its target
        assert arrived == "False" or move.strip() == f"to {at}"
    times = [float(t) for *_, t, _ in rows]
    assert times == sorted(times) and times[1] > 0  # physics time, never back
    fell = [f == "True" for *_, f in rows]
    if any(fell):  # the state says so, and the episode ends there
        assert fell.index(True) == len(rows) - 1 and "episode is over" in out
    else:
        assert moves[3:] == ["turn_left", "forward", "forward"]
    assert "geodesic distance back to the start" in out


def test_gym_rollout(tmp_path):
    _needs("gymnasium")
    out = _run("gym_rollout", tmp_path, "--size", "32", "--episodes", "1", "--max-steps", "3")
    assert "rgb (32, 32, 3)" in out
    assert re.search(r"3 steps, return -?[\d.]+, \d+ collisions, goal [\d.]+ m away", out)


def test_dm_env_rollout(tmp_path):
    _needs("dm_env")
    out = _run("dm_env_rollout", tmp_path, "--steps", "3")
    assert "FIRST:" in out
    assert re.search(r"LAST: return -?[\d.]+, discount 0\.0", out)  # STOP ends with discount 0


def test_expert_metrics(tmp_path):
    out = _run("expert_metrics", tmp_path, "--episodes", "1")
    rows = {line.split()[0]: line.split()[1:] for line in out.splitlines()[1:3]}
    shortest = [float(v) for v in rows["shortest_graph"]]
    assert shortest[:5] == [0.0, 1.0, 1.0, 1.0, 1.0]  # NE, SR, OSR, SPL, nDTW of the optimum
    assert "human_aware_local" in rows


def test_film_walk(tmp_path):
    out = _run("film_walk", tmp_path, "--width", "64", "--height", "48", "--edges", "1")
    frames, seconds = re.search(r"(\d+) frames over ([\d.]+) simulated seconds", out).groups()
    assert int(frames) == pytest.approx(10 * float(seconds) + 1, abs=2)  # 10 fps, start frame
    video = cv2.VideoCapture(str(tmp_path / "walk.mp4"))
    assert int(video.get(cv2.CAP_PROP_FRAME_COUNT)) == int(frames)
    assert int(video.get(cv2.CAP_PROP_FRAME_WIDTH)) == 64
    assert "arrived True" in out


def test_every_example_is_run_here():
    tested = {name[len("test_") :] for name in globals() if name.startswith("test_")}
    assert {p.stem for p in EXAMPLES.glob("*.py")} <= tested
