"""The learned GO1 controller: its policy file, its residual on the terrain gait, its walks."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import mujoco
import numpy as np
import pytest

from havln_mj.errors import InvalidArgumentError, MalformedDataError, MissingDataError
from havln_mj.robot.go1 import Go1Body, add_go1, flat_floor_spec
from havln_mj.robot.go1.constants import CONTROLLERS
from havln_mj.robot.go1.courses import START_X, stairs_spec
from havln_mj.robot.go1.learned import FORMAT_VERSION, LearnedPolicy, PolicySpec, load_policy


def _body(spec: mujoco.MjSpec, **kw) -> Go1Body:
    add_go1(spec)
    model = spec.compile()
    return Go1Body(model, mujoco.MjData(model), **kw)


def test_shipped_policy_loads_and_gives_the_same_action_for_the_same_observation() -> None:
    policy = load_policy()
    assert "learned" in CONTROLLERS
    spec = policy.spec
    assert spec.decimation == 10 and spec.action == "residual"
    obs = np.random.default_rng(0).normal(size=spec.obs_size)
    a = policy.act(obs)
    assert a.shape == (12,) and np.all(np.isfinite(a))
    assert np.array_equal(a, policy.act(obs.copy()))
    assert np.array_equal(a, load_policy().act(obs))  # a second load: the same network
    assert not np.array_equal(a, policy.act(obs + 1.0))  # and it does read its input
    assert np.all(np.abs(a) <= spec.clip_actions)


def test_policy_round_trips_through_its_file(tmp_path: Path) -> None:
    policy = load_policy()
    policy.save(tmp_path / "p.npz")
    again = load_policy(tmp_path / "p.npz")
    assert again.spec == policy.spec
    obs = np.linspace(-1, 1, policy.spec.obs_size)
    np.testing.assert_allclose(again.act(obs), policy.act(obs), rtol=1e-6, atol=1e-6)


def test_bad_policy_files_raise_specific_errors(tmp_path: Path) -> None:
    with pytest.raises(MissingDataError, match="not found"):
        load_policy(tmp_path / "absent.npz")
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"not a zip file")
    with pytest.raises(MalformedDataError, match="not a GO1 policy"):
        load_policy(junk)
    raw = dict(np.load(policy_path(), allow_pickle=False))
    for change, match in (
        ({"format_version": np.array(FORMAT_VERSION + 1)}, "format version"),
        ({"obs_mean": np.zeros(3)}, "normalisation"),
        ({"w0": np.zeros((4, 5))}, "layer 0"),
    ):
        path = tmp_path / "bad.npz"
        np.savez(path, **(raw | change))
        with pytest.raises(MalformedDataError, match=match):
            load_policy(path)
    del raw["spec"]
    np.savez(tmp_path / "nospec.npz", **raw)
    with pytest.raises(MalformedDataError, match="lacks"):
        load_policy(tmp_path / "nospec.npz")


def policy_path() -> Path:
    from havln_mj.paths import asset_path

    return asset_path("robots", "go1", "policy.npz")


def test_a_zero_residual_walks_exactly_as_the_terrain_gait() -> None:
    policy = load_policy()
    zero = replace(
        policy,
        weights=tuple(0.0 * w for w in policy.weights),
        biases=tuple(0.0 * b for b in policy.biases),
    )
    poses = []
    for controller, p in (("terrain", None), ("learned", zero)):
        body = _body(flat_floor_spec(), controller=controller, policy=p)
        body.reset(0.0, 0.0, 0.0, math.pi / 2)
        body.forward(0.3)
        poses.append(body.true_pose())
    assert poses[0] == poses[1]


def test_policy_rate_must_fit_the_gait() -> None:
    policy = load_policy()
    odd = replace(policy, spec=replace(policy.spec, decimation=7))
    with pytest.raises(InvalidArgumentError, match="multiple"):
        _body(flat_floor_spec(), controller="learned", policy=odd)


def test_learned_controller_walks_and_turns_on_a_flat_floor() -> None:
    body = _body(flat_floor_spec(), controller="learned")
    assert isinstance(body.policy, LearnedPolicy)
    body.reset(0.0, 0.0, 0.0, math.pi / 2)
    res = body.forward(0.5)
    assert not res.fell and not res.timed_out
    assert res.distance == pytest.approx(0.5, abs=0.05)
    res = body.turn(math.pi / 2)
    assert not res.fell
    assert res.heading_change == pytest.approx(math.pi / 2, abs=math.radians(5))


def _stair_walk(down: bool) -> tuple[bool, float]:
    spec, course = stairs_spec(riser=0.17, tread=0.28, risers=4)
    body = _body(spec, controller="learned")
    start, goal = (course.top_x, START_X) if down else (START_X, course.top_x)
    body.reset(start, 0.0, course.rise if down else 0.0, -math.pi / 2 if down else math.pi / 2)
    res = body.forward(abs(goal - start))
    p = body.true_pose()
    floor = 0.0 if down else course.rise
    arrived = abs(p.x - goal) < 0.3 and abs(p.z - floor - 0.27) < 0.15 and not res.fell
    return arrived, p.x


@pytest.mark.xfail(
    strict=True,
    reason="measured with the shipped policy: it falls at the first 0.17 m riser going up and "
    "one tread below the top edge going down, as the terrain gait under it does (on the second "
    "tread going up, at the top edge going down)",
)
@pytest.mark.parametrize("down", [False, True], ids=["up", "down"])
def test_controller_climbs_and_descends_a_short_stair(down: bool) -> None:
    arrived, x = _stair_walk(down)
    assert arrived, f"ended at x = {x:.2f} m"


def test_default_spec_layout() -> None:
    spec = PolicySpec()
    assert spec.obs_size == 3 + 3 + 3 + 12 * 4 + 2 + len(spec.scan_x) * len(spec.scan_y)
    assert spec.scan_points().shape == (len(spec.scan_x) * len(spec.scan_y), 2)
    assert PolicySpec.from_json(spec.to_json()) == spec
    with pytest.raises(MalformedDataError, match="unknown"):
        PolicySpec.from_json(spec.to_json() | {"colour": 1})
