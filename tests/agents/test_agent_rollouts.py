"""Batch rollouts, demos of the expert and of random walks, observations and masks."""

from __future__ import annotations

import numpy as np
import pytest

from havln_mj.agents.data import instructions_of, split_episodes
from havln_mj.agents.demos import Demo
from havln_mj.agents.features import FeatureStore
from havln_mj.agents.observations import PROPRIO_DIM
from havln_mj.agents.rollouts import EgoRollouts, collect_demos, make_simulator
from havln_mj.agents.views import ViewConfig
from havln_mj.errors import InvalidArgumentError, UnknownSceneError
from havln_mj.scene.ids import expand_scene_ranges
from havln_mj.sim.egocentric import EgoAction
from havln_mj.tasks.vocab import Vocabulary

SCENES = ["proc-3", "proc-4"]


@pytest.fixture(scope="module")
def setup(tmp_path_factory):
    episodes = split_episodes({"scenes": SCENES, "per_scene": 3}, seed=0)
    instructions = instructions_of(episodes)
    sim = make_simulator(8, seed=0)
    store = FeatureStore(tmp_path_factory.mktemp("f"), ViewConfig(slots=2), dim=6)
    rng = np.random.default_rng(0)
    for scan in SCENES:
        vps = list(sim.graph(scan).nodes)
        store.put(scan, vps, rng.normal(size=(len(vps), 36, 2, 6)))
    vocab = Vocabulary.from_texts(i.text for i in instructions)
    return instructions, EgoRollouts(sim, store, vocab, max_steps=40)


def test_split_specs():
    assert expand_scene_ranges(["proc-2:5", "x"]) == ["proc-2", "proc-3", "proc-4", "x"]
    with pytest.raises(UnknownSceneError, match="empty"):
        expand_scene_ranges(["proc-5:5"])
    with pytest.raises(InvalidArgumentError, match="valid"):
        split_episodes({"scenes": ["proc-3"], "episodes": 2}, seed=0)
    # skip: new paths in the same houses, the same people.
    train = split_episodes({"scenes": ["proc-3"], "per_scene": 2}, seed=0)
    val = split_episodes({"scenes": ["proc-3"], "per_scene": 2, "skip": 2}, seed=0)
    both = split_episodes({"scenes": ["proc-3"], "per_scene": 4}, seed=0)
    assert [e.path for e in both] == [e.path for e in train + val]
    assert [e.instructions for e in both[2:]] == [e.instructions for e in val]
    assert not {e.path for e in train} & {e.path for e in val}


def test_expert_demos_reach_the_goal_with_valid_actions(setup):
    instructions, rollouts = setup
    demos = collect_demos(rollouts, instructions, "expert", progress=False)
    assert [d.instr_id for d in demos] == [i.instr_id for i in instructions]
    for d in demos:
        assert d.source == "expert" and d.stopped and d.success and d.distance[-1] == 0.0
        assert d.obs.shape == (len(d), 6 + PROPRIO_DIM)
        assert d.masks[np.arange(len(d)), d.actions].all()
        assert d.instruction.shape == (80,) and d.instruction[0] > 0
        # Proprioception: one-hot camera level and the forward flag agree with the mask.
        np.testing.assert_array_equal(d.obs[:, 6:9].sum(1), 1.0)
        np.testing.assert_array_equal(d.obs[:, 9], d.masks[:, EgoAction.FORWARD])
        np.testing.assert_allclose(
            np.cumsum(d.delta)[-1], d.distance[-1] - (d.distance[0] - d.delta[0])
        )


def test_random_walks_are_seeded_capped_and_valid(setup):
    instructions, rollouts = setup
    a = collect_demos(rollouts, instructions, "random", np.random.default_rng(5), progress=False)
    b = collect_demos(rollouts, instructions, "random", np.random.default_rng(5), progress=False)
    assert [d.actions.tolist() for d in a] == [d.actions.tolist() for d in b]
    for d in a:
        assert len(d) <= 30 and d.stopped  # STOP at the latest on the 30th action
        assert set(d.actions.tolist()) <= {0, 1, 2, 3}
        assert d.masks[np.arange(len(d)), d.actions].all()
    lengths = [len(d) for d in a]
    assert min(lengths) < max(lengths)


def test_demo_rewards_and_checks():
    demo = Demo(
        "1_0",
        "random",
        np.array([5, 0]),
        np.zeros((3, 2), np.float32),
        np.array([1, 2, 0]),
        np.ones((3, 6), bool),
        np.array([4.0, 4.0, 4.0], np.float32),
        np.array([-1.5, 0.0, 0.0], np.float32),
        np.array([True, False, False]),
    )
    np.testing.assert_allclose(demo.rewards("paper"), [1.0 - 2.0, -0.1, -5.0])
    np.testing.assert_allclose(demo.rewards("strategy_1"), [0.0, 0.0, -5.0])
    assert demo.stopped and not demo.success
    with pytest.raises(InvalidArgumentError, match="forbids"):
        Demo("x", "expert", demo.instruction, demo.obs, demo.actions, np.zeros((3, 6), bool),
             demo.distance, demo.delta, demo.collided)  # fmt: skip
    with pytest.raises(InvalidArgumentError, match="shape"):
        Demo("x", "expert", demo.instruction, demo.obs[:2], demo.actions, demo.masks,
             demo.distance, demo.delta, demo.collided)  # fmt: skip


def test_rollout_errors(setup):
    instructions, rollouts = setup
    with pytest.raises(InvalidArgumentError, match="valid: 1–8"):
        rollouts.start(instructions[:9])
    rollouts.start(instructions[:2])
    assert rollouts.done.tolist() == [False, False] + [True] * 6
    with pytest.raises(InvalidArgumentError, match="action indices"):
        rollouts.step(np.full(8, 7))
    with pytest.raises(InvalidArgumentError, match="'expert', 'random'"):
        collect_demos(rollouts, instructions, "oracle")
