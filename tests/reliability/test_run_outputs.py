"""Defect 3: a run folder never mixes runs, and an interrupted run leaves it as it was."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from havln_mj.render.video import probe

RUN = ["havln_mj.run", "--scene", "proc-0", "--width", "64", "--height", "48", "--fps", "4"]


def _staging(out: Path) -> list[Path]:
    return [p for p in out.iterdir() if p.name.startswith(".havln-staging-")]


@pytest.fixture(scope="module")
def earlier_run(tmp_path_factory) -> Path:
    """A finished run's folder, as a template for each test to copy."""
    out = tmp_path_factory.mktemp("runs") / "earlier"
    _run_once(out)
    return out


def _run_once(out: Path, *extra: str) -> None:
    """A one-episode run into ``out`` that must finish."""
    proc = subprocess.run(
        [sys.executable, "-m", *RUN, "--episodes", "1", "--out", str(out), *extra],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]


def _copy(folder: Path, to: Path) -> dict[str, bytes]:
    to.mkdir()
    files = {p.name: p.read_bytes() for p in folder.iterdir() if p.is_file()}
    for name, data in files.items():
        (to / name).write_bytes(data)
    return files


def _start_rerun(out: Path, *extra: str) -> subprocess.Popen:
    return subprocess.Popen(
        # Many episodes: the run must still be going when the test interrupts it.
        [sys.executable, "-m", *RUN, "--episodes", "20", "--out", str(out), *extra],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )


def _wait_for_video_in_staging(proc: subprocess.Popen, out: Path) -> None:
    deadline = time.monotonic() + 300
    while not any((s / "egocentric.mp4").is_file() for s in _staging(out)):
        assert proc.poll() is None, "the run ended before it was interrupted"
        assert time.monotonic() < deadline
        time.sleep(0.02)
    time.sleep(0.5)  # some frames into the video


def test_a_finished_run_lists_only_its_own_files(earlier_run, tmp_path):
    out = tmp_path / "out"
    _copy(earlier_run, out)
    (out / "go1.mp4").write_bytes(b"an earlier --robot go1 run's video")
    _run_once(out, "--seed", "3")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["seed"] == 3
    assert not (out / "go1.mp4").exists()
    assert sorted(Path(f).name for f in summary["files"].values()) == sorted(
        p.name for p in out.iterdir() if p.name != "summary.json"
    )
    assert probe(out / "egocentric.mp4")["frames"] == summary["frames"]


def test_an_interrupted_rerun_leaves_the_earlier_run_whole(earlier_run, tmp_path):
    out = tmp_path / "out"
    before = _copy(earlier_run, out)
    proc = _start_rerun(out, "--seed", "5")
    _wait_for_video_in_staging(proc, out)
    proc.send_signal(signal.SIGINT)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130, stderr[-2000:]
    assert "Traceback" not in stderr
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


@pytest.mark.slow
def test_a_killed_runs_staging_is_cleaned_by_the_next_run(earlier_run, tmp_path):
    out = tmp_path / "out"
    _copy(earlier_run, out)
    proc = _start_rerun(out)
    _wait_for_video_in_staging(proc, out)
    os.kill(proc.pid, signal.SIGKILL)
    proc.communicate(timeout=60)
    assert _staging(out)
    _run_once(out)
    assert not _staging(out)
