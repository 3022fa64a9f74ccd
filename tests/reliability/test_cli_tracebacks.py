"""Defect 5: every command-line call of the defect list, as a user runs it: no tracebacks.

Each call runs in a subprocess; it must end with the expected exit code, a message naming the
bad value and what is valid, and no Python traceback on stderr.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time

import pytest

RUN = ["havln_mj.run", "--scene", "proc-0", "--width", "64", "--height", "48"]
DATASET = ["havln_mj.cli", "dataset", "build", "--scenes", "proc-0", "--split", "x"]

# (arguments, exit code, what stderr says)
CALLS = {
    "run --vfov 200": ([*RUN, "--vfov", "200"], 2, r"--vfov must be in \(0, 180\) degrees"),
    "run --seed -1": ([*RUN, "--seed", "-1"], 2, "--seed must be ≥ 0, got -1"),
    "run --width 0": ([*RUN, "--width", "0"], 2, r"--width must be in \[1, 8192\]"),
    "run --width -64": ([*RUN, "--width", "-64"], 2, r"--width must be in \[1, 8192\]"),
    "run --width 9000": ([*RUN, "--width", "9000"], 2, r"--width must be in \[1, 8192\]"),
    "run --vfov 0": ([*RUN, "--vfov", "0"], 2, r"--vfov must be in \(0, 180\)"),
    "run --go1-camera-height -5": (
        [*RUN, "--robot", "go1", "--go1-camera-height", "-5"],
        2,
        r"--go1-camera-height must be in \[0.1, 3\] m",
    ),
    "run --scene ''": (["havln_mj.run", "--scene", ""], 2, "--scene must name a scene"),
    "run --human-placements missing": (
        [*RUN, "--human-placements", "missing.json"],
        2,
        "--human-placements missing.json does not exist",
    ),
    "dataset build --seed -1": ([*DATASET, "--seed", "-1"], 2, "--seed must be at least 0"),
    "annotate --width 0": (
        ["havln_mj.cli", "annotate", "--scene", "proc-0", "--width", "0"],
        2,
        r"--width must be in \[1, 8192\] pixels",
    ),
    "eval --seed -1": (
        ["havln_mj.eval", "--scenes", "proc-0", "--seed", "-1", "--out", "ev"],
        2,
        "seed",
    ),
}


@pytest.mark.parametrize("name", list(CALLS))
def test_a_bad_flag_is_refused_without_a_traceback(cli, name):
    args, code, message = CALLS[name]
    proc = cli(args, timeout=120)
    assert "Traceback" not in proc.stderr, proc.stderr[-3000:]
    assert proc.returncode == code, proc.stderr[-3000:]
    assert re.search(message, proc.stderr), proc.stderr[-3000:]


DEGENERATE = {
    "noEdges0000": lambda d: [e.update(unobstructed=[False] * len(d)) for e in d],
    "oneViewpnt0": lambda d: (
        d.__delitem__(slice(1, None)),
        d[0].update(visible=[False], unobstructed=[False]),
    ),
    "onePoint000": lambda d: [e["pose"].__setitem__(k, 1.0) for e in d for k in (3, 7, 11)],
    "farAway0000": lambda d: d[3]["pose"].__setitem__(3, 1e12),
    "zeroPoses00": lambda d: [e.update(pose=[0.0] * 16) for e in d],
    "negHeight00": lambda d: d[2].update(height=-1.5),
}


def test_degenerate_graphs_fail_alone_in_a_scenes_build_batch(
    cli, fresh_cache, graph_dir, small_scan
):
    good = json.loads((graph_dir / f"{small_scan}_connectivity.json").read_text())
    for scan_id, damage in DEGENERATE.items():
        data = json.loads(json.dumps(good))
        damage(data)
        (graph_dir / f"{scan_id}_connectivity.json").write_text(json.dumps(data))
    build = ["havln_mj.cli", "scenes", "build", "--all-connectivity", "--collision", "boxes"]
    proc = cli([*build, "--connectivity-dir", str(graph_dir)], timeout=600)
    assert "Traceback" not in proc.stderr, proc.stderr[-3000:]
    assert proc.returncode == 1
    assert f"built 1 of {len(DEGENERATE) + 1} scenes" in proc.stdout
    assert f"{small_scan}: graph proxy" in proc.stdout
    for scan_id in DEGENERATE:
        assert re.search(f"{scan_id}: FAILED: .*{scan_id}_connectivity.json", proc.stdout)


def test_scenes_build_caps_its_workers_with_a_note(cli, fresh_cache):
    proc = cli(["havln_mj.cli", "scenes", "build", "proc-0", "--workers", "100000"])
    assert "Traceback" not in proc.stderr, proc.stderr[-3000:]
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "using 1 worker process, not 100000" in proc.stderr


def test_a_cache_path_that_is_a_file_is_reported_and_the_build_goes_on(cli, tmp_path):
    blocker = tmp_path / "cache-file"
    blocker.write_text("")
    proc = cli(["havln_mj.cli", "scenes", "build", "proc-0"], env={"HAVLN_CACHE": str(blocker)})
    assert "Traceback" not in proc.stderr, proc.stderr[-3000:]
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert proc.stderr.count("cannot be written") == 1
    assert str(blocker) in proc.stderr and "HAVLN_CACHE" in proc.stderr


@pytest.mark.skipif(bool(os.environ.get("DISPLAY")), reason="a display is available")
def test_view_without_a_display_says_how_to_get_one(cli):
    proc = cli(["havln_mj.cli", "view", "--frames", "1"], timeout=120)
    assert "Traceback" not in proc.stderr
    assert proc.returncode == 2 and "xvfb-run" in proc.stderr


TRAIN = ["havln_mj.agents.train", "--config", "vln_cm_smoke", "--threads", "1"]


@pytest.mark.slow
@pytest.mark.parametrize(
    "args, message",
    [
        (["--set", "model.nonexistent=3"], "nonexistent"),
        (["--resume", "--out", "no-run-here"], "checkpoint"),
    ],
)
def test_train_refuses_a_bad_setting_without_a_traceback(cli, args, message):
    pytest.importorskip("torch")
    proc = cli([*TRAIN, *args], timeout=120)
    assert "Traceback" not in proc.stderr
    assert proc.returncode == 2 and message in proc.stderr


def test_an_interrupted_scenes_build_exits_130_and_leaves_no_staging(fresh_cache):
    scans = fresh_cache / "scans"
    cmd = [sys.executable, "-m", "havln_mj.cli", "scenes", "build", "proc-11", "proc-12"]
    # A terminal's Ctrl-C reaches the whole process group: the workers too.
    proc = subprocess.Popen(
        cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True
    )
    deadline = time.monotonic() + 120
    while not (scans.is_dir() and any(scans.iterdir())):
        assert proc.poll() is None and time.monotonic() < deadline
        time.sleep(0.01)
    os.killpg(proc.pid, signal.SIGINT)
    _, stderr = proc.communicate(timeout=120)
    assert "Traceback" not in stderr, stderr[-3000:]
    assert proc.returncode == 130 and "interrupted" in stderr
    assert not [p for p in scans.iterdir() if p.name.startswith(".")]
