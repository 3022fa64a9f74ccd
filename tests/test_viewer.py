"""``havln_mj view``: the live MuJoCo viewer opens under a virtual display and steps."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time

import pytest

from havln_mj.viewer import EGO_KEYS, ROBOT_KEYS, LiveView


@pytest.fixture(scope="module")
def display():
    """A private Xvfb display for the viewer's window."""
    xvfb = shutil.which("Xvfb")
    if xvfb is None:
        pytest.skip("Xvfb is not installed (apt-get install xvfb)")
    number = 90 + os.getpid() % 9
    proc = subprocess.Popen([xvfb, f":{number}", "-screen", "0", "800x600x24"])
    time.sleep(1.0)
    yield f":{number}"
    proc.terminate()
    proc.wait(timeout=10)


@pytest.mark.parametrize("body", ["point", "go1"])
def test_the_viewer_opens_and_the_keys_move_the_agent(display, body):
    env = {**os.environ, "DISPLAY": display, "MUJOCO_GL": "glfw"}
    cmd = [sys.executable, "-m", "havln_mj.cli", "view", "--scene", "proc-0", "--body", body]
    cmd += ["--frames", "12", "--keys", "up,left,space"]
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "viewer closed after 12 frames" in proc.stdout


def test_the_viewer_opens_a_real_scan_with_its_placements(display, shared_data):
    env = {**os.environ, "DISPLAY": display, "MUJOCO_GL": "glfw"}
    cmd = [sys.executable, "-m", "havln_mj.cli", "view", "--scene", "17DRP5sb8fy", "--frames", "3"]
    cmd += ["--connectivity-dir", str(shared_data / "mp3d_connectivity")]
    cmd += ["--human-placements", str(shared_data / "ha3d" / "human_placements.json")]
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "viewer closed after 3 frames" in proc.stdout


def test_the_viewer_names_a_missing_placement_file(tmp_path):
    cmd = [sys.executable, "-m", "havln_mj.cli", "view", "--human-placements", str(tmp_path / "x")]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and "--human-placements" in proc.stderr


class _FakeSim:
    def __init__(self, robot: bool):
        self.robot_actions = ("forward", "turn_left", "turn_right") if robot else ()
        self.calls = []

    def graph(self, scene):
        return None

    def wait(self, seconds):
        self.calls.append(("wait", seconds[0]))

    def makeEgoAction(self, actions):  # noqa: N802 - the simulator's name
        self.calls.append(("ego", actions[0]))

    def makeRobotAction(self, actions):  # noqa: N802
        self.calls.append(("robot", actions[0]))


@pytest.mark.parametrize("robot", [False, True])
def test_keys_become_the_bodys_actions_and_idle_time_passes(robot):
    sim = _FakeSim(robot)
    live = LiveView(sim, "proc-0")
    up = next(iter(ROBOT_KEYS))
    live.key(up)
    live.act(0.1)
    live.act(0.1)
    expected = ("robot", "forward") if robot else ("ego", EGO_KEYS[up])
    assert sim.calls == [expected, ("wait", 0.1)]
