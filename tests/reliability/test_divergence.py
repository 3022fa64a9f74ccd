"""Defect 4: diverged GO1 physics is reported and ends the episode, in every interface.

The fault is made the way diverging physics shows itself to MuJoCo: a non-finite velocity in
the robot's state. MuJoCo then warns and resets the state, which would put the robot back at
its model's origin.
"""

from __future__ import annotations

import numpy as np
import pytest

from havln_mj.sim.simulator import Simulator

SCENE = "proc-0"


def _diverge(sim) -> None:
    _, data = sim.draw(0)  # the element's own physics state
    data.qvel[:] = np.nan


@pytest.fixture
def go1(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # MuJoCo logs its warnings to ./MUJOCO_LOG.TXT
    sim = Simulator(humans=False, body="go1")
    sim.setRenderingEnabled(False)
    sim.initialize()
    yield sim
    sim.close()


def test_the_state_reports_divergence_and_the_robot_stays_put(go1):
    graph = go1.graph(SCENE)
    start = graph.nodes[0]
    go1.newEpisode([SCENE], [start], [0.0], [0.0])
    before = go1.getState()[0]
    assert not before.diverged and not before.fell
    _diverge(go1)
    go1.makeRobotAction(["forward"])
    after = go1.getState()[0]
    assert after.diverged and after.fell
    assert np.linalg.norm(after.pose[:2] - before.pose[:2]) < 0.5  # not teleported
    go1.makeRobotAction(["forward"])  # the episode has ended: nothing moves
    assert np.array_equal(go1.getState()[0].pose, after.pose)


def test_the_gym_episode_terminates(tmp_path, monkeypatch):
    gym = pytest.importorskip("gymnasium")
    import havln_mj.gym  # noqa: F401 - registers the ids

    monkeypatch.chdir(tmp_path)
    env = gym.make("HAVLN-Go1-v0", scenes=[SCENE], episodes_per_scene=2, humans=False)
    env.reset(seed=0)
    _diverge(env.unwrapped.core.sim)
    _, _, terminated, truncated, info = env.step(1)  # forward
    assert terminated and not truncated and info["fell"]
    env.close()


def test_the_dm_env_episode_ends(tmp_path, monkeypatch):
    pytest.importorskip("dm_env")
    from havln_mj.dmenv import load

    monkeypatch.chdir(tmp_path)
    env = load("robot", scenes=[SCENE], episodes_per_scene=2, humans=False, seed=0)
    env.reset()
    _diverge(env.core.sim)
    step = env.step(1)
    assert step.last() and step.discount == 0.0 and env.info["fell"]
    env.close()
