"""Instruction encoders: the small transformer and the optional local BERT."""

from __future__ import annotations

import json
import sys

import pytest

torch = pytest.importorskip("torch")

from havln_mj.agents.text import BertTextEncoder, TextTransformer, encode_texts  # noqa: E402
from havln_mj.errors import (  # noqa: E402
    DependencyNotInstalledError,
    InvalidArgumentError,
    MissingDataError,
)
from havln_mj.tasks.vocab import Vocabulary  # noqa: E402

TEXTS = [
    "Walk past the sofa and stop at the kitchen door.",
    "Turn left.",
    "",
]


@pytest.fixture
def vocab() -> Vocabulary:
    return Vocabulary.from_texts(TEXTS)


def _model(vocab_size: int, **kw) -> TextTransformer:
    torch.manual_seed(0)
    return TextTransformer(vocab_size, d_model=32, n_layers=2, n_heads=4, max_len=24, **kw)


def test_encode_texts_uses_the_vocabulary(vocab):
    ids = encode_texts(vocab, TEXTS, 12)
    assert ids.dtype == torch.int64 and ids.shape == (3, 12)
    assert ids[1, :3].tolist() == [vocab.id("turn"), vocab.id("left"), vocab.id(".")]
    assert ids[1, 3:].eq(0).all() and ids[2].eq(0).all()
    assert encode_texts(vocab, [], 5).shape == (0, 5)


def test_shapes_and_padding_mask(vocab):
    model = _model(len(vocab))
    ids = encode_texts(vocab, TEXTS, 16)
    tokens, pad = model(ids)
    assert tokens.shape == (3, 16, 32) and pad.dtype == torch.bool and pad.shape == (3, 16)
    assert torch.equal(pad, ids == 0)
    assert torch.isfinite(tokens).all()  # also for the empty instruction (all padding)
    assert model.out_dim == 32


def test_appended_padding_does_not_change_real_tokens(vocab):
    model = _model(len(vocab)).eval()
    short = encode_texts(vocab, TEXTS, 12)
    long = torch.cat([short, torch.zeros(3, 10, dtype=torch.long)], dim=1)
    with torch.no_grad():
        a, pad_a = model(short)
        b, pad_b = model(long)
    real = ~pad_a
    torch.testing.assert_close(a[real], b[:, :12][real], rtol=1e-5, atol=1e-5)
    torch.testing.assert_close(model.pooled(a, pad_a), model.pooled(b, pad_b), rtol=1e-5, atol=1e-5)


def test_pooled_is_a_masked_mean():
    tokens = torch.arange(2 * 3 * 2, dtype=torch.float32).view(2, 3, 2)
    pad = torch.tensor([[False, False, True], [True, True, True]])
    pooled = TextTransformer.pooled(tokens, pad)
    assert pooled.tolist() == [[1.0, 2.0], [0.0, 0.0]]  # mean of rows 0–1; empty → 0


def test_gradients_flow_and_pad_embedding_stays_zero(vocab):
    model = _model(len(vocab))
    tokens, pad = model(encode_texts(vocab, TEXTS, 16))
    model.pooled(tokens, pad).pow(2).sum().backward()
    assert model.tokens.weight.grad is not None
    assert model.tokens.weight.grad[0].abs().sum() == 0  # padding_idx gets no gradient
    assert model.tokens.weight[0].abs().sum() == 0


def test_config_round_trip(vocab):
    model = _model(len(vocab), dropout=0.2).eval()
    cfg = json.loads(json.dumps(model.config()))
    assert cfg == {
        "vocab_size": len(vocab), "d_model": 32, "n_layers": 2, "n_heads": 4,
        "max_len": 24, "dropout": 0.2,
    }  # fmt: skip
    clone = TextTransformer.from_config(cfg)
    clone.load_state_dict(model.state_dict())
    clone.eval()
    ids = encode_texts(vocab, TEXTS, 10)
    with torch.no_grad():
        assert torch.equal(clone(ids)[0], model(ids)[0])


def test_bad_input(vocab):
    model = _model(len(vocab))
    with pytest.raises(InvalidArgumentError, match="max_len 24"):
        model(torch.ones(1, 25, dtype=torch.long))
    with pytest.raises(InvalidArgumentError, match="outside 0"):
        model(torch.tensor([[len(vocab)]]))
    with pytest.raises(InvalidArgumentError, match=r"\(B, L\)"):
        model(torch.ones(4, dtype=torch.long))
    with pytest.raises(InvalidArgumentError, match="divisible"):
        TextTransformer(10, d_model=30, n_heads=4)


def test_bert_needs_an_existing_folder(tmp_path):
    missing = tmp_path / "bert-base-uncased"
    with pytest.raises(MissingDataError) as info:
        BertTextEncoder(missing)
    assert str(missing) in str(info.value)


def test_bert_needs_transformers(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "transformers", None)  # import fails even if installed
    with pytest.raises(DependencyNotInstalledError, match="pip install transformers"):
        BertTextEncoder(tmp_path)
