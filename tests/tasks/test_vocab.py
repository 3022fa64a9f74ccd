"""The gymnasium environments' instruction vocabulary."""

from __future__ import annotations

import numpy as np
import pytest

from havln_mj.errors import InvalidArgumentError, MissingDataError
from havln_mj.tasks.vocab import PAD, UNK, Vocabulary


def test_from_texts_orders_by_frequency_then_alphabetically():
    vocab = Vocabulary.from_texts(["Go left, then go right.", "go up"])
    assert vocab.tokens[:2] == (PAD, UNK)
    assert vocab.tokens[2:] == ("go", ",", ".", "left", "right", "then", "up")


def test_encode_pads_cuts_and_maps_unknown_words():
    vocab = Vocabulary(["go", "left"])
    ids = vocab.encode("Go LEFT now", 5)
    assert ids.dtype == np.int64 and ids.tolist() == [2, 3, 1, 0, 0]
    assert vocab.encode("go go go", 2).tolist() == [2, 2]
    assert vocab.decode(ids) == ["go", "left", UNK]
    with pytest.raises(InvalidArgumentError, match="at least 1"):
        vocab.encode("go", 0)
    with pytest.raises(InvalidArgumentError, match="out of range 0–3"):
        vocab.decode([4])


def test_from_file_reads_vocab_files(tmp_path):
    path = tmp_path / "vocab_train.txt"
    path.write_text("walk\t10\nstairs\t3\nhall\n", encoding="utf-8")
    assert Vocabulary.from_file(path).tokens == (PAD, UNK, "walk", "stairs", "hall")
    with pytest.raises(MissingDataError, match=r"nope\.txt"):
        Vocabulary.from_file(tmp_path / "nope.txt")


def test_repeated_tokens_raise():
    with pytest.raises(InvalidArgumentError, match="repeats tokens: a"):
        Vocabulary(["a", "b", "a"])
