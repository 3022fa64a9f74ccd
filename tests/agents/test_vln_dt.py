"""VLN-DT: shapes, masking, causality, padding, return-to-go bookkeeping, training, round trip."""

from __future__ import annotations

import json
from dataclasses import asdict

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from havln_mj.agents.demos import Demo  # noqa: E402
from havln_mj.agents.vln_dt import (  # noqa: E402
    FORWARD_KEYS,
    DecisionTransformer,
    DTConfig,
    DTDataset,
    DTPolicy,
    dt_loss,
    returns_to_go,
    sample_windows,
)
from havln_mj.errors import InvalidArgumentError, MissingDataError  # noqa: E402

D = 8
TEXT = {"d_model": 16, "n_layers": 1, "n_heads": 2, "max_len": 12}


def small_config(**kw) -> DTConfig:
    base = dict(
        vocab_size=20,
        obs_dim=D,
        d_model=16,
        n_layers=2,
        n_heads=2,
        dropout=0.0,
        context=4,
        max_timestep=16,
        text=TEXT,
    )
    return DTConfig(**(base | kw))


def make_model(seed: int = 0, **kw) -> DecisionTransformer:
    torch.manual_seed(seed)
    return DecisionTransformer(small_config(**kw)).eval()


def make_demo(rng: np.random.Generator, t: int, k: int) -> Demo:
    masks = rng.random((t, 6)) < 0.6
    actions = rng.integers(1, 6, size=t)
    actions[-1] = 0
    masks[np.arange(t), actions] = True
    delta = rng.choice([-1.0, 0.0, 0.5], size=t).astype(np.float32)
    distance = (5.0 + np.cumsum(delta)).astype(np.float32)
    n_words = int(rng.integers(3, 9))
    instruction = np.zeros(10, np.int64)
    instruction[:n_words] = rng.integers(1, 20, size=n_words)
    instruction[0] = k + 1  # unique first word: a window's row tells its demo
    return Demo(
        instr_id=f"p{k}_0",
        source="random",
        instruction=instruction,
        obs=rng.normal(size=(t, D)).astype(np.float32),
        actions=actions.astype(np.int64),
        masks=masks,
        distance=distance,
        delta=delta,
        collided=rng.random(t) < 0.2,
    )


def make_demos(n: int = 6, seed: int = 0) -> list[Demo]:
    rng = np.random.default_rng(seed)
    return [make_demo(rng, int(rng.integers(1, 9)), k) for k in range(n)]


def random_inputs(cfg: DTConfig, b: int, k: int, seed: int = 0) -> dict[str, torch.Tensor]:
    g = torch.Generator().manual_seed(seed)
    instruction = torch.randint(1, cfg.vocab_size, (b, 7), generator=g)
    instruction[:, 5:] = 0
    action_mask = torch.rand(b, k, 6, generator=g) < 0.5
    action_mask[..., 1] = True
    return {
        "instruction": instruction,
        "obs": torch.randn(b, k, cfg.obs_dim, generator=g),
        "actions": torch.randint(0, 6, (b, k), generator=g),
        "rtg": torch.randn(b, k, generator=g) * 3,
        "timesteps": torch.arange(k).repeat(b, 1) + 2,
        "step_mask": torch.ones(b, k, dtype=torch.bool),
        "action_mask": action_mask,
    }


# -- config


def test_config_round_trips_through_json() -> None:
    cfg = small_config(fusion="concat", reward="strategy_2")
    again = DTConfig(**json.loads(json.dumps(asdict(cfg))))
    assert again == cfg
    assert DTConfig(vocab_size=5, obs_dim=3).context == 15
    assert DTConfig(vocab_size=5, obs_dim=3).target_return == 5.0


@pytest.mark.parametrize(
    ("field", "value"),
    [("context", 0), ("fusion", "sum"), ("reward", "papr"), ("d_model", 15), ("rtg_scale", 0.0)],
)
def test_config_rejects_bad_values(field: str, value: object) -> None:
    with pytest.raises(InvalidArgumentError, match=field if field != "reward" else "paper"):
        small_config(**{field: value})


# -- model


@pytest.mark.parametrize("fusion", ["attention", "concat"])
def test_forward_shapes_and_masking(fusion: str) -> None:
    model = make_model(fusion=fusion)
    x = random_inputs(model.cfg, b=3, k=4)
    logits = model(**x)
    assert logits.shape == (3, 4, 6)
    mask = x["action_mask"]
    assert torch.isneginf(logits[~mask]).all()
    assert torch.isfinite(logits[mask]).all()
    assert mask.gather(2, logits.argmax(-1, keepdim=True)).all()


def test_forward_rejects_bad_inputs() -> None:
    model = make_model()
    x = random_inputs(model.cfg, b=2, k=3)
    with pytest.raises(InvalidArgumentError, match="obs_dim=8"):
        model(**(x | {"obs": torch.zeros(2, 3, D + 1)}))
    with pytest.raises(InvalidArgumentError, match="context of 4"):
        model(**random_inputs(model.cfg, b=2, k=5))
    with pytest.raises(InvalidArgumentError, match="max_timestep"):
        model(**(x | {"timesteps": torch.full((2, 3), 16)}))
    with pytest.raises(InvalidArgumentError, match="no valid action"):
        model(**(x | {"action_mask": torch.zeros(2, 3, 6, dtype=torch.bool)}))


def test_causal_logits_never_see_the_future() -> None:
    model = make_model(fusion="attention")
    x = random_inputs(model.cfg, b=2, k=4)
    base = model(**x)
    t = 1
    changed = {name: value.clone() for name, value in x.items()}
    changed["obs"][:, t + 1 :] += 5.0
    changed["rtg"][:, t + 1 :] -= 7.0
    changed["actions"][:, t:] = (changed["actions"][:, t:] + 1) % 6  # a_t too
    changed["timesteps"][:, t + 1 :] += 3
    out = model(**changed)
    torch.testing.assert_close(out[:, : t + 1], base[:, : t + 1], rtol=0, atol=1e-6)
    assert not torch.allclose(out[:, t + 1 :], base[:, t + 1 :])


@pytest.mark.parametrize("side", ["right", "left"])
def test_padded_steps_influence_no_real_step(side: str) -> None:
    model = make_model()
    x = random_inputs(model.cfg, b=2, k=2)
    base = model(**x)
    garbage = random_inputs(model.cfg, b=2, k=2, seed=1)
    garbage["action_mask"][:] = False  # padding may hold anything, even no valid action
    garbage["timesteps"][:] = 999
    parts = (x, garbage) if side == "right" else (garbage, x)
    padded = {
        name: torch.cat([parts[0][name], parts[1][name]], dim=1)
        for name in FORWARD_KEYS
        if name != "instruction"
    }
    real = slice(0, 2) if side == "right" else slice(2, 4)
    padded["step_mask"] = torch.zeros(2, 4, dtype=torch.bool)
    padded["step_mask"][:, real] = True
    # Trailing instruction padding changes nothing either.
    instruction = torch.cat([x["instruction"], torch.zeros(2, 3, dtype=torch.long)], dim=1)
    out = model(instruction, **padded)
    torch.testing.assert_close(out[:, real], base, rtol=0, atol=1e-5)
    assert torch.isfinite(out).any(-1).all()  # padded rows are numbers, not NaN


# -- returns and policy


def test_returns_to_go_are_suffix_sums() -> None:
    out = returns_to_go(np.array([-0.1, 1.0, 1.0, 5.0]))
    assert out.dtype == np.float32
    np.testing.assert_allclose(out, [6.9, 7.0, 6.0, 5.0], rtol=1e-6)
    with pytest.raises(InvalidArgumentError, match="one-dimensional"):
        returns_to_go(np.zeros((2, 2)))


def test_policy_return_to_go_bookkeeping_and_window() -> None:
    model = make_model(context=3)
    policy = DTPolicy(model)
    rng = np.random.default_rng(0)
    policy.reset(np.array([3, 4, 5, 0, 0]))
    rewards = [None, -0.1, 1.0, 1.0, 5.0]
    obs = rng.normal(size=(5, D)).astype(np.float32)
    mask = np.ones(6, bool)
    for t in range(4):
        policy.act(obs[t], mask, rewards[t])
    np.testing.assert_allclose(policy.returns_to_go[-3:], [5.1, 4.1, 3.1], rtol=1e-6)
    assert policy.timesteps == [1, 2, 3]  # only the last `context` steps
    action = policy.act(obs[4], mask, rewards[4])
    np.testing.assert_allclose(policy.returns_to_go, [4.1, 3.1, -1.9], rtol=1e-6)
    assert policy.timesteps == [2, 3, 4]

    # The policy feeds exactly that window to the network.
    chosen = policy.actions
    logits = model(
        torch.tensor([[3, 4, 5, 0, 0]]),
        torch.from_numpy(obs[2:5])[None],
        torch.tensor([chosen]),
        torch.tensor([[4.1, 3.1, -1.9]]),
        torch.tensor([[2, 3, 4]]),
        torch.ones(1, 3, dtype=torch.bool),
        torch.ones(1, 3, 6, dtype=torch.bool),
    )
    assert action == int(logits[0, -1].argmax())

    policy.reset(np.array([3, 4, 5]))  # a new episode starts from the target again
    policy.act(obs[0], mask, None)
    assert policy.returns_to_go == [5.0] and policy.timesteps == [0]


def test_policy_target_and_scale() -> None:
    model = make_model(rtg_scale=2.0, target_return=3.0)
    policy = DTPolicy(model, target_return=4.0)
    policy.reset(np.array([1, 2]))
    policy.act(np.zeros(D, np.float32), np.ones(6, bool), None)
    assert policy.returns_to_go == [4.0]  # reward units; the network sees 4 / 2


def test_policy_respects_masks_and_checks_inputs() -> None:
    model = make_model()
    policy = DTPolicy(model)
    with pytest.raises(InvalidArgumentError, match="reset"):
        policy.act(np.zeros(D), np.ones(6, bool), None)
    policy.reset(np.array([1, 2, 3]))
    rng = np.random.default_rng(0)
    with pytest.raises(InvalidArgumentError, match="first step"):
        policy.act(np.zeros(D), np.ones(6, bool), 1.0)
    with pytest.raises(InvalidArgumentError, match=r"\(8,\)"):
        policy.act(np.zeros(D + 1), np.ones(6, bool), None)
    with pytest.raises(InvalidArgumentError, match="rng"):
        policy.act(np.zeros(D), np.ones(6, bool), None, greedy=False)
    seen = set()
    for t in range(40):
        mask = np.zeros(6, bool)
        mask[[t % 6, (t + 3) % 6]] = True
        if t % 5 == 0:
            policy.reset(np.array([1, 2, 3]))
        reward = None if t % 5 == 0 else -0.1
        a = policy.act(rng.normal(size=D), mask, reward, greedy=t % 2 == 0, rng=rng)
        assert mask[a]
        seen.add(a)
    assert len(seen) > 2
    with pytest.raises(InvalidArgumentError, match="a number after"):
        policy.act(np.zeros(D), np.ones(6, bool), None)


# -- data and training


def test_sample_windows_match_the_demos() -> None:
    demos = make_demos(6)
    cfg = small_config()
    batch = sample_windows(demos, cfg, 32, np.random.default_rng(0), reward="strategy_2")
    assert set(batch) == {*FORWARD_KEYS, "targets", "loss_mask"}
    b, k = batch["actions"].shape
    assert b == 32 and 1 <= k <= cfg.context
    assert batch["obs"].shape == (32, k, D) and batch["action_mask"].shape == (32, k, 6)
    assert batch["instruction"].shape == (32, 10)
    assert batch["instruction"].dtype == batch["actions"].dtype == torch.int64
    assert batch["step_mask"].dtype == batch["loss_mask"].dtype == torch.bool
    assert torch.equal(batch["loss_mask"], batch["step_mask"])
    assert torch.equal(batch["targets"], batch["actions"])
    ends = set()
    for row in range(b):
        demo = demos[int(batch["instruction"][row, 0]) - 1]
        n = int(batch["step_mask"][row].sum())
        assert batch["step_mask"][row, :n].all()  # right-padded
        s = int(batch["timesteps"][row, 0])
        e = s + n
        assert n == min(cfg.context, e)  # reaches back `context` steps or to the start
        ends.add((demo.instr_id, e - 1))
        np.testing.assert_array_equal(batch["obs"][row, :n], demo.obs[s:e])
        np.testing.assert_array_equal(batch["actions"][row, :n], demo.actions[s:e])
        np.testing.assert_array_equal(batch["action_mask"][row, :n], demo.masks[s:e])
        np.testing.assert_array_equal(batch["timesteps"][row, :n], np.arange(s, e))
        rtg = np.cumsum(demo.rewards("strategy_2")[::-1])[::-1][s:e]
        np.testing.assert_allclose(batch["rtg"][row, :n], rtg, rtol=1e-6)
        assert batch["action_mask"][row, n:].all() and not batch["rtg"][row, n:].any()
    assert len(ends) > 10  # windows end at many different steps


def test_sample_windows_dataset_cache_and_scale() -> None:
    demos = make_demos(6)
    cfg = small_config()
    plain = sample_windows(demos, cfg, 16, np.random.default_rng(3))
    data = DTDataset(demos)
    cached = sample_windows(data, cfg, 16, np.random.default_rng(3))
    again = sample_windows(data, cfg, 16, np.random.default_rng(3))  # from the cache
    scaled = sample_windows(data, cfg, 16, np.random.default_rng(3), rtg_scale=4.0)
    for name in plain:
        assert torch.equal(plain[name], cached[name]) and torch.equal(cached[name], again[name])
    torch.testing.assert_close(scaled["rtg"] * 4.0, plain["rtg"])


def test_sample_windows_rejects_bad_input() -> None:
    cfg = small_config()
    rng = np.random.default_rng(0)
    with pytest.raises(InvalidArgumentError, match="empty"):
        sample_windows([], cfg, 4, rng)
    with pytest.raises(InvalidArgumentError, match="obs_dim=5"):
        sample_windows(make_demos(2), small_config(obs_dim=5), 4, rng)
    with pytest.raises(InvalidArgumentError, match="batch_size"):
        sample_windows(make_demos(2), cfg, 0, rng)
    with pytest.raises(InvalidArgumentError, match="max_timestep=4"):
        sample_windows(make_demos(6), small_config(max_timestep=4), 4, rng)


@pytest.mark.parametrize("fusion", ["attention", "concat"])
def test_one_adamw_step_lowers_the_loss(fusion: str) -> None:
    model = make_model(fusion=fusion).train()
    batch = sample_windows(make_demos(6), model.cfg, 16, np.random.default_rng(1))
    opt = torch.optim.AdamW(model.parameters(), lr=3e-3)
    before = dt_loss(model, batch)
    opt.zero_grad()
    before.backward()
    opt.step()
    with torch.no_grad():
        after = dt_loss(model, batch)
    assert torch.isfinite(before) and after < before


def test_round_trip_gives_identical_logits_and_actions() -> None:
    model = make_model(seed=0)
    cfg = DTConfig(**json.loads(json.dumps(asdict(model.cfg))))
    torch.manual_seed(1)  # a different initialisation, overwritten by the state dict
    clone = DecisionTransformer(cfg).eval()
    clone.load_state_dict(model.state_dict())
    x = random_inputs(model.cfg, b=2, k=4)
    assert torch.equal(model(**x), clone(**x))

    rng = np.random.default_rng(0)
    obs = rng.normal(size=(7, D)).astype(np.float32)
    masks = rng.random((7, 6)) < 0.7
    masks[:, 1] = True
    runs = []
    for net in (model, clone):
        policy = DTPolicy(net)
        policy.reset(np.array([5, 6, 7, 0]))
        runs.append([policy.act(obs[t], masks[t], None if t == 0 else -0.1 * t) for t in range(7)])
    assert runs[0] == runs[1]


def test_bert_text_needs_the_vocabulary_and_the_users_folder(tmp_path):
    with pytest.raises(InvalidArgumentError, match="vocab"):
        DecisionTransformer(small_config(text={"bert": str(tmp_path), "d_model": 16}))
    words = [f"w{i}" for i in range(small_config().vocab_size)]
    with pytest.raises(MissingDataError, match="nope"):
        DecisionTransformer(
            small_config(text={"bert": str(tmp_path / "nope"), "vocab": words, "d_model": 16})
        )
