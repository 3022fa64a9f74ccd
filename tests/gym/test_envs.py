"""The gymnasium environments: API conformance, rewards, determinism, pickling, vectorising."""

from __future__ import annotations

import functools
import math
import pickle
import subprocess
import sys
import warnings

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

from gymnasium.utils.env_checker import check_env  # noqa: E402

from havln_mj.errors import (  # noqa: E402
    InvalidActionError,
    InvalidArgumentError,
    MissingDataError,
    NotInitializedError,
)
from havln_mj.gym import ENV_IDS, EgoEnv, GraphEnv  # noqa: E402 - registers the ids
from havln_mj.sim.egocentric import EgoAction  # noqa: E402

SMALL = {"width": 32, "height": 32}
BLIND = {"rgb": False}  # nothing rendered: the fastest configuration


def _same(a, b) -> bool:
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    return bool(np.array_equal(a, b))


@pytest.mark.parametrize("env_id", list(ENV_IDS))
def test_check_env_passes_without_warnings(env_id):
    env = gym.make(env_id, render_mode="rgb_array", depth=True, human_mask=True, **SMALL)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped)
    env.close()


def test_ids_are_versioned_and_importable_by_module_prefix():
    assert set(ENV_IDS) == {"HAVLN-Graph-v0", "HAVLN-Ego-v0", "HAVLN-Go1-v0"}
    env = gym.make("havln_mj.gym:HAVLN-Graph-v0", **BLIND)
    assert isinstance(env.unwrapped, GraphEnv)
    assert env.spec.max_episode_steps == 40
    env.close()


def test_spaces():
    env = GraphEnv(width=48, height=32, depth=True, human_mask=True, max_candidates=8)
    space = env.observation_space
    assert space["rgb"].shape == (32, 48, 3) and space["rgb"].dtype == np.uint8
    assert space["depth"].shape == (32, 48, 1) and space["depth"].dtype == np.float32
    assert space["human_mask"].shape == (32, 48)
    assert (
        space["instruction"].shape == (80,)
        and space["instruction"].high.max() == len(env.vocab) - 1
    )
    assert space["candidates"].shape == (9, 4) and space["candidate_mask"].n == 9
    assert env.action_space.n == 9
    assert EgoEnv(**BLIND).action_space.n == 6
    assert "rgb" not in EgoEnv(**BLIND).observation_space.spaces
    assert gym.make("HAVLN-Go1-v0", **BLIND).action_space.n == 4


def test_instruction_tokens_use_the_exposed_vocabulary():
    env = GraphEnv(**BLIND, instruction_length=12)
    obs, info = env.reset(seed=3)
    ids = obs["instruction"]
    assert ids.shape == (12,) and ids.dtype == np.int64
    words = env.vocab.decode(ids)
    assert len(words) == 12 and "<unk>" not in words  # the default vocabulary covers every word
    assert info["instruction"].lower().startswith(words[0])
    assert [env.vocab.tokens[i] for i in ids] == words


def test_reset_seed_is_deterministic():
    env = GraphEnv(**SMALL)
    obs_a, info_a = env.reset(seed=7)
    steps_a = [env.step(int(a)) for a in (1, 2, 1)]
    obs_b, info_b = env.reset(seed=7)
    steps_b = [env.step(int(a)) for a in (1, 2, 1)]
    assert _same(obs_a, obs_b) and info_a == info_b
    for (o1, r1, t1, u1, i1), (o2, r2, t2, u2, i2) in zip(steps_a, steps_b, strict=True):
        assert _same(o1, o2) and r1 == r2 and t1 == t2 and u1 == u2 and i1 == i2
    # Different seeds draw different instructions (over 20 paths × 3 instructions).
    ids = {env.reset(seed=s)[1]["instr_id"] for s in range(10)}
    assert len(ids) > 1
    env.close()


def test_reset_options_choose_the_instruction():
    env = GraphEnv(**BLIND)
    target = env.instructions[4]
    assert env.reset(options={"instr_id": target.instr_id})[1]["instr_id"] == target.instr_id
    assert env.reset(options={"index": 4})[1]["instr_id"] == target.instr_id
    with pytest.raises(InvalidArgumentError, match="nope"):
        env.reset(options={"nope": 1})
    with pytest.raises(InvalidArgumentError, match="out of range"):
        env.reset(options={"index": len(env.instructions)})


def test_reward_terms_sum_to_the_reward_and_weights_apply():
    env = GraphEnv(**BLIND)
    weighted = GraphEnv(**BLIND, reward_weights={"distance": 0.5, "target": 2.0})
    for e in (env, weighted):
        e.reset(seed=0)
        e.action_space.seed(0)
    seen = set()
    for _ in range(200):
        a = int(env.action_space.sample())
        outs = [e.step(a) for e in (env, weighted)]
        for _, reward, *_rest, info in outs:
            assert set(info["reward_terms"]) == {"target", "distance", "human"}
            assert reward == pytest.approx(sum(info["reward_terms"].values()))
        plain, half = outs[0][4]["reward_terms"], outs[1][4]["reward_terms"]
        assert half["distance"] == pytest.approx(0.5 * plain["distance"])
        assert half["target"] == pytest.approx(2.0 * plain["target"])
        seen |= {k for k, v in plain.items() if v}
        if outs[0][2]:
            assert abs(plain["target"]) == 5.0 and plain["distance"] == 0.0
            assert outs[0][4]["success"] == (plain["target"] > 0)
            for e in (env, weighted):
                e.reset()
    assert {"target", "distance"} <= seen


def test_bad_reward_weights_and_arguments_raise():
    with pytest.raises(InvalidArgumentError, match=r"'speed'.*target"):
        GraphEnv(**BLIND, reward_weights={"speed": 1.0})
    with pytest.raises(InvalidArgumentError, match="render_mode 'human'"):
        GraphEnv(render_mode="human")
    with pytest.raises(InvalidArgumentError, match="width"):
        GraphEnv(width=0)
    with pytest.raises(InvalidArgumentError, match="unknown reward"):
        GraphEnv(reward="nope")


def test_step_errors():
    env = GraphEnv(**BLIND)
    with pytest.raises(NotInitializedError, match="reset"):
        env.step(0)
    env.reset(seed=0)
    with pytest.raises(InvalidActionError, match="valid 0–16"):
        env.step(17)
    with pytest.raises(InvalidActionError, match="integer"):
        env.step(1.5)
    _, _, terminated, _, _ = env.step(0)  # STOP
    assert terminated
    with pytest.raises(NotInitializedError):
        env.step(1)


def test_graph_actions_move_to_candidates_and_empty_slots_wait():
    env = GraphEnv(**BLIND)
    obs, _ = env.reset(seed=1)
    assert obs["candidate_mask"][0] == 1 and obs["candidate_mask"][1] == 1
    target = env._sim.getState()[0].navigableLocations[1]
    expected = (float(obs["heading"][0]) + target.rel_heading) % (2 * math.pi)
    obs, _, terminated, _, info = env.step(1)
    assert not terminated and info["viewpoint"] == target.viewpointId
    # The agent turns to face the way it moved.
    assert math.isclose(math.cos(obs["heading"][0] - expected), 1.0, abs_tol=1e-5)
    empty = int(np.flatnonzero(obs["candidate_mask"] == 0)[0])
    _, _, terminated, _, after = env.step(empty)
    assert after["invalid_action"] and after["viewpoint"] == info["viewpoint"] and not terminated
    assert after["time"] == pytest.approx(info["time"] + 1.0)  # a one-second wait
    assert after["reward_terms"]["distance"] == -0.1


def test_ego_stop_and_turns():
    env = EgoEnv(**BLIND)
    obs, _ = env.reset(seed=0)
    h0 = float(obs["heading"][0])
    obs, _, terminated, _, info = env.step(int(EgoAction.TURN_RIGHT))
    assert not terminated
    assert math.isclose((obs["heading"][0] - h0) % (2 * math.pi), math.pi / 6, abs_tol=1e-5)
    assert info["reward_terms"]["distance"] == -0.1
    _, _, terminated, _, info = env.step(int(EgoAction.STOP))
    assert terminated and info["stopped"]


@pytest.mark.parametrize("env_id", ["HAVLN-Graph-v0", "HAVLN-Ego-v0"])
def test_time_limit_truncates(env_id):
    env = gym.make(env_id, max_episode_steps=3, **BLIND)
    env.reset(seed=0)
    turn = int(EgoAction.TURN_LEFT) if env_id == "HAVLN-Ego-v0" else 16  # 16: an empty slot
    outs = [env.step(turn) for _ in range(3)]
    assert [o[3] for o in outs] == [False, False, True]
    assert not any(o[2] for o in outs)


def test_pickle_round_trip():
    env = gym.make("HAVLN-Graph-v0", **SMALL)
    first, _ = env.reset(seed=11)
    env.step(1)
    clone = pickle.loads(pickle.dumps(env))
    assert clone.unwrapped._sim is None  # it builds its own simulator
    again, _ = clone.reset(seed=11)
    assert _same(first, again)
    assert clone.unwrapped.vocab == env.unwrapped.vocab
    env.reset(seed=11)
    assert _same(clone.step(1)[0], env.step(1)[0])
    env.close()
    clone.close()


def test_render_rgb_array():
    env = gym.make("HAVLN-Ego-v0", render_mode="rgb_array", rgb=False, width=48, height=32)
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (32, 48, 3) and frame.dtype == np.uint8 and frame.any()
    env.close()
    assert GraphEnv(**BLIND).render() is None


def test_async_vector_env_with_two_workers():
    make = functools.partial(gym.make, "havln_mj.gym:HAVLN-Graph-v0", **SMALL)
    envs = gym.vector.AsyncVectorEnv([make, make], context="spawn")
    obs, info = envs.reset(seed=[0, 1])
    assert obs["rgb"].shape == (2, 32, 32, 3) and obs["instruction"].shape[0] == 2
    envs.action_space.seed(0)
    for _ in range(5):
        obs, reward, terminated, _, info = envs.step(envs.action_space.sample())
        assert terminated.shape == (2,) and len(info["reward_terms"]["target"]) == 2
        assert reward.shape == (2,) and obs["rgb"].shape == (2, 32, 32, 3)
    envs.close()


@pytest.mark.parametrize("env_id", ["HAVLN-Graph-v0", "HAVLN-Ego-v0"])
def test_random_agent_runs_1000_steps(env_id):
    env = gym.make(env_id, **BLIND)
    env.action_space.seed(0)
    obs, _ = env.reset(seed=0)
    episodes = 0
    for _ in range(1000):
        obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        assert obs in env.observation_space and math.isfinite(reward)
        if terminated or truncated:
            obs, _ = env.reset()
            episodes += 1
    assert episodes > 10
    env.close()


def test_go1_random_agent():
    env = gym.make("HAVLN-Go1-v0", **BLIND)
    env.action_space.seed(0)
    env.reset(seed=0)
    for _ in range(50):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        assert obs in env.observation_space
        assert reward == pytest.approx(sum(info["reward_terms"].values()))
        if terminated or truncated:
            env.reset()
    env.close()


def test_simulator_core_does_not_import_gymnasium():
    code = (
        "import sys, havln_mj, havln_mj.sim.simulator, havln_mj.tasks.experts, havln_mj.cli\n"
        "assert 'gymnasium' not in sys.modules, 'core imported gymnasium'\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_protocol_option_sets_the_simulators_rules():
    env = gym.make("HAVLN-Graph-v0", protocol="ha3d", **BLIND)
    env.reset(seed=0)
    sim = env.unwrapped.core.sim
    assert sim.collision_rule.check == "state" and sim.human_clock.kind == "ha3d"
    frame = sim.human_clock_frame
    _, _, _, _, info = env.step(1)
    assert sim.human_clock_frame == sim.human_clock.after_action(frame)  # one action: +32
    assert isinstance(info["collision"], bool)
    env.close()
    strict = GraphEnv(**BLIND)
    strict.reset(seed=0)
    assert strict.core.sim.collision_rule.check == "action"
    strict.close()
    with pytest.raises(InvalidArgumentError, match="protocol"):
        GraphEnv(protocol="lenient", **BLIND)


def test_real_scans_need_their_people(shared_data, monkeypatch):
    monkeypatch.delenv("HAVLN_HA3D_PLACEMENTS", raising=False)
    where = {
        "dataset": shared_data / "r2r" / "R2R_val_seen.json",
        "connectivity_dir": shared_data / "mp3d_connectivity",
        "scenes": ["17DRP5sb8fy"],
        **BLIND,
    }
    env = GraphEnv(**where)
    with pytest.raises(MissingDataError, match="human_placements"):
        env.reset(seed=0)
    env.close()
    placements = shared_data / "ha3d" / "human_placements.json"
    env = GraphEnv(human_placements=placements, **where)
    env.reset(seed=0)
    assert len(env.core.sim.crowd("17DRP5sb8fy")) > 0
    env.close()
