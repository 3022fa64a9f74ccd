"""VLN-CM: shapes, masking, teacher forcing against step-by-step decoding, learning, checkpoints."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from havln_mj.agents.checkpoint import AgentBundle  # noqa: E402
from havln_mj.agents.featurize import FeatureSpec  # noqa: E402
from havln_mj.agents.vision import ViewEncoder  # noqa: E402
from havln_mj.agents.vln_cm import START, VLNCM, CMConfig, CMPolicy, sequence_loss  # noqa: E402
from havln_mj.errors import InvalidArgumentError, MalformedDataError, MissingDataError  # noqa: E402
from havln_mj.tasks.vocab import Vocabulary  # noqa: E402

B, L, T, D = 3, 7, 5, 10


def _model(dropout=0.0, seed=0):
    torch.manual_seed(seed)
    return VLNCM(
        CMConfig(vocab_size=20, obs_dim=D, word_dim=8, hidden=16, action_dim=4, dropout=dropout)
    )


def _batch(seed=0):
    g = torch.Generator().manual_seed(seed)
    ids = torch.randint(2, 20, (B, L), generator=g)
    ids[1, 4:] = 0  # a shorter instruction
    obs = torch.randn(B, T, D, generator=g)
    targets = torch.randint(0, 6, (B, T), generator=g)
    prev = torch.cat([torch.full((B, 1), START), targets[:, :-1]], dim=1)
    masks = torch.ones(B, T, 6, dtype=torch.bool)
    masks[0, :, 1] = False  # no FORWARD for the first sequence
    targets[0][targets[0] == 1] = 0
    return ids, obs, prev, masks, targets


def test_shapes_and_masking():
    model = _model().eval()
    ids, obs, prev, masks, _ = _batch()
    logits = model(ids, obs, prev, masks)
    assert logits.shape == (B, T, 6)
    assert (logits[0, :, 1] < -1e8).all() and (logits[1:] > -1e8).all()
    assert (logits[0].argmax(-1) != 1).all()
    _, _, state = model.encode(ids)
    assert state[0].shape == (B, 16)
    _, _, att = model.step(obs[:, 0], prev[:, 0], state, *model.encode(ids)[:2], masks[:, 0])
    np.testing.assert_allclose(att["words"].sum(1).detach(), 1.0, rtol=1e-6)
    assert (att["words"][1, 4:] < 1e-6).all()  # padding gets no attention
    np.testing.assert_allclose(att["gate"].sum(1).detach(), 1.0, rtol=1e-6)


def test_padding_does_not_change_the_encoding():
    model = _model().eval()
    ids = torch.tensor([[3, 4, 5, 0, 0]])
    longer = torch.tensor([[3, 4, 5, 0, 0, 0, 0, 0]])
    ctx_a, _, (h_a, _) = model.encode(ids)
    ctx_b, _, (h_b, _) = model.encode(longer)
    torch.testing.assert_close(h_a, h_b)
    torch.testing.assert_close(ctx_a[:, :3], ctx_b[:, :3])
    # An empty instruction (HA-R2R has some) still gives a finite encoding and actions.
    ctx, pad, (h, _) = model.encode(torch.zeros(1, 4, dtype=torch.long))
    assert torch.isfinite(ctx).all() and torch.isfinite(h).all()
    assert pad.tolist() == [[False, True, True, True]]
    policy = CMPolicy(model)
    policy.reset(np.zeros(4, np.int64))
    assert 0 <= policy.act(np.zeros(D, np.float32), np.ones(6, bool)) < 6


def test_policy_decodes_like_teacher_forcing():
    model = _model().eval()
    ids, obs, _, masks, _ = _batch()
    policy = CMPolicy(model)
    policy.reset(ids[2].numpy())
    actions = [policy.act(obs[2, t].numpy(), masks[2, t].numpy()) for t in range(T)]
    prev = torch.tensor([[START, *actions[:-1]]])
    logits = model(ids[2:], obs[2:], prev, masks[2:])
    assert actions == logits[0].argmax(-1).tolist()


def test_one_step_lowers_the_loss_on_a_fixed_batch():
    model = _model(dropout=0.0)
    ids, obs, prev, masks, targets = _batch()
    valid = torch.ones(B, T, dtype=torch.bool)
    valid[1, 3:] = False
    opt = torch.optim.Adam(model.parameters(), lr=1e-2)
    before = sequence_loss(model(ids, obs, prev, masks), targets, valid)
    opt.zero_grad()
    before.backward()
    opt.step()
    after = sequence_loss(model(ids, obs, prev, masks), targets, valid)
    assert after.item() < before.item()


def test_checkpoint_round_trip_gives_the_same_actions(tmp_path):
    model = _model().eval()
    vocab = Vocabulary(["go", "left"] + [f"w{i}" for i in range(16)])
    encoder = ViewEncoder(widths=(4, 8), blocks=(1, 1), out_dim=4)
    bundle = AgentBundle("vln_cm", model, model.cfg.__dict__, vocab, encoder, FeatureSpec())
    bundle.save(tmp_path / "a.pt")
    loaded = AgentBundle.load(tmp_path / "a.pt")
    assert loaded.agent == "vln_cm" and loaded.vocab == vocab
    ids, obs, _, masks, _ = _batch(seed=3)
    runs = []
    for m in (model, loaded.model):
        policy = CMPolicy(m)
        policy.reset(ids[0].numpy())
        runs.append([policy.act(obs[0, t].numpy(), masks[0, t].numpy()) for t in range(T)])
    assert runs[0] == runs[1]
    for a, b in zip(
        encoder.state_dict().values(), loaded.encoder.state_dict().values(), strict=True
    ):
        torch.testing.assert_close(a, b)
    with pytest.raises(MissingDataError, match="train one"):
        AgentBundle.load(tmp_path / "none.pt")
    (tmp_path / "bad.pt").write_bytes(b"junk")
    with pytest.raises(MalformedDataError):
        AgentBundle.load(tmp_path / "bad.pt")


def test_config_checks():
    with pytest.raises(InvalidArgumentError, match="hidden"):
        CMConfig(vocab_size=5, obs_dim=3, hidden=0)
    with pytest.raises(InvalidArgumentError, match="dropout"):
        CMConfig(vocab_size=5, obs_dim=3, dropout=1.0)
    with pytest.raises(InvalidArgumentError, match="before reset"):
        CMPolicy(_model()).act(np.zeros(D), np.ones(6, bool))


def test_a_users_resnet152_is_referenced_not_copied(tmp_path):
    from havln_mj.agents.vision import ResNetFeatures, resnet152

    weights = tmp_path / "resnet152.pth"
    torch.save(resnet152().state_dict(), weights)
    spec = FeatureSpec(resnet152=str(weights), resnet_input=(64, 64))
    encoder = spec.fixed_encoder()
    assert isinstance(encoder, ResNetFeatures) and encoder.out_dim == 2048
    model = _model().eval()
    vocab = Vocabulary([f"w{i}" for i in range(18)])
    AgentBundle("vln_cm", model, model.cfg.__dict__, vocab, encoder, spec).save(tmp_path / "a.pt")
    assert (tmp_path / "a.pt").stat().st_size < weights.stat().st_size / 20
    loaded = AgentBundle.load(tmp_path / "a.pt")
    assert isinstance(loaded.encoder, ResNetFeatures) and loaded.features.resnet152 == str(weights)
    weights.unlink()
    with pytest.raises(MissingDataError, match=r"resnet152\.pth"):
        AgentBundle.load(tmp_path / "a.pt")
