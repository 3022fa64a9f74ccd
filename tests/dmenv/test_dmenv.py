"""The dm_env adapter: dm_env's own conformance mixin, specs, determinism, episode ends."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

dm_env = pytest.importorskip("dm_env")
absltest = pytest.importorskip("absl.testing.absltest")

from dm_env import test_utils  # noqa: E402

from havln_mj import dmenv  # noqa: E402
from havln_mj.sim.egocentric import EgoAction  # noqa: E402

BLIND = {"rgb": False, "episodes_per_scene": 4}


class GraphConformance(test_utils.EnvironmentTestMixin, absltest.TestCase):
    def make_object_under_test(self):
        return dmenv.load("graph", seed=0, max_steps=6, **BLIND)

    def make_action_sequence(self):
        # Moves, an empty candidate slot (a wait), then STOP: reaches LAST both ways.
        for action in (1, 1, 16, 0, 1, 2, 1, 1, 1, 1, 1, 1, 1):
            yield np.int64(action)


class EgoConformance(test_utils.EnvironmentTestMixin, absltest.TestCase):
    def make_object_under_test(self):
        return dmenv.load("ego", seed=1, width=32, height=24, depth=True, human_mask=True)

    def make_action_sequence(self):
        for action in (EgoAction.FORWARD, EgoAction.TURN_LEFT, EgoAction.LOOK_UP, EgoAction.STOP):
            yield np.int64(action)


def _rollout(seed: int, actions) -> list:
    env = dmenv.load("graph", seed=seed, **BLIND)
    steps = [env.reset()]
    steps += [env.step(a) for a in actions]
    env.close()
    return steps


def test_observations_match_their_specs_and_are_finite():
    env = dmenv.load("ego", seed=0, width=32, height=24, depth=True, human_mask=True)
    spec = env.observation_spec()
    ts = env.reset()
    for _ in range(8):
        assert set(ts.observation) == set(spec)
        for name, value in ts.observation.items():
            spec[name].validate(value)
            assert np.all(np.isfinite(np.asarray(value, float))), name
        ts = env.step(EgoAction.FORWARD)
    env.close()


def test_same_seed_same_rollout_and_no_shared_memory():
    actions = [1, 2, 1, 3, 1]
    a, b = _rollout(5, actions), _rollout(5, actions)
    for x, y in zip(a, b, strict=True):
        assert x.step_type == y.step_type and x.reward == y.reward
        for k in x.observation:
            np.testing.assert_array_equal(x.observation[k], y.observation[k])
    for x, y in itertools.pairwise(a):
        for k, v in x.observation.items():
            if isinstance(v, np.ndarray):
                assert not np.shares_memory(v, y.observation[k]), k


def test_stop_terminates_and_the_limit_truncates():
    env = dmenv.load("graph", seed=0, max_steps=2, **BLIND)
    env.reset()
    last = env.step(0)
    assert last.last() and last.discount == 0.0 and env.info["stopped"]
    assert env.step(1).first()  # a new episode
    env.step(16)
    cut = env.step(16)
    assert cut.last() and cut.discount == 1.0 and not env.info["stopped"]
    env.close()


def test_bad_arguments_name_what_is_valid():
    from havln_mj.errors import InvalidArgumentError

    with pytest.raises(InvalidArgumentError, match="valid: graph, ego, robot"):
        dmenv.load("walk")
    with pytest.raises(InvalidArgumentError, match="max_steps"):
        dmenv.load("graph", max_steps=0, **BLIND)
