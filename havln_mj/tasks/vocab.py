"""The instruction vocabulary of the environments and agents: tokens ↔ fixed-length id arrays.

Tokens are :func:`havln_mj.tasks.instructions.tokenize` units. Id 0 is padding (``<pad>``), id
1 stands for any token not in the vocabulary (``<unk>``); the other tokens follow, most
frequent first (ties alphabetical), as ``vocab_<split>.txt`` files list them.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

from havln_mj.errors import InvalidArgumentError, MissingDataError
from havln_mj.tasks.instructions import tokenize

PAD, UNK = "<pad>", "<unk>"
SPECIALS = (PAD, UNK)


class Vocabulary:
    """A fixed token list with encoding to padded id arrays.

    Attributes:
        tokens: Every token, by id (``tokens[0]`` is ``<pad>``, ``tokens[1]`` is ``<unk>``).
    """

    def __init__(self, tokens: Iterable[str]) -> None:
        """Builds a vocabulary from its words (specials are added in front when missing).

        Raises:
            InvalidArgumentError: A token is repeated or not a non-empty string.
        """
        words = [t for t in tokens if t not in SPECIALS]
        for t in words:
            if not isinstance(t, str) or not t:
                raise InvalidArgumentError(
                    f"vocabulary tokens must be non-empty strings, got {t!r}"
                )
        if len(set(words)) != len(words):
            repeated = sorted({t for t in words if words.count(t) > 1})
            raise InvalidArgumentError(f"vocabulary repeats tokens: {', '.join(repeated[:5])}")
        self.tokens: tuple[str, ...] = (*SPECIALS, *words)
        self._ids = {t: i for i, t in enumerate(self.tokens)}

    @classmethod
    def from_texts(cls, texts: Iterable[str]) -> Vocabulary:
        """The vocabulary of ``texts``: most frequent token first, ties alphabetical."""
        counts: Counter[str] = Counter()
        for text in texts:
            counts.update(tokenize(text))
        return cls(t for t, _ in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0])))

    @classmethod
    def from_file(cls, path: str | Path) -> Vocabulary:
        """Reads a ``vocab_<split>.txt`` file (``token<TAB>count`` lines, or bare tokens).

        Raises:
            MissingDataError: The file does not exist.
        """
        path = Path(path).expanduser()
        if not path.is_file():
            raise MissingDataError(f"vocabulary file {path} does not exist")
        lines = path.read_text(encoding="utf-8").splitlines()
        return cls(line.partition("\t")[0] for line in lines if line.strip())

    def __len__(self) -> int:
        return len(self.tokens)

    def __contains__(self, token: object) -> bool:
        return token in self._ids

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Vocabulary) and self.tokens == other.tokens

    def __hash__(self) -> int:
        return hash(self.tokens)

    def __repr__(self) -> str:
        return f"Vocabulary({len(self)} tokens)"

    def id(self, token: str) -> int:
        """The id of ``token`` (``<unk>``'s id when unknown)."""
        return self._ids.get(token, 1)

    def encode(self, text: str, length: int) -> np.ndarray:
        """``text``'s token ids, cut or padded with 0 to ``length`` (``int64``).

        Raises:
            InvalidArgumentError: ``length`` is below 1.
        """
        if length < 1:
            raise InvalidArgumentError(f"instruction length must be at least 1, got {length}")
        out = np.zeros(length, np.int64)
        ids = [self.id(t) for t in tokenize(text)[:length]]
        out[: len(ids)] = ids
        return out

    def decode(self, ids: Sequence[int] | np.ndarray) -> list[str]:
        """The tokens of ``ids``, padding dropped.

        Raises:
            InvalidArgumentError: An id is outside ``0 … len(self) - 1``.
        """
        out = []
        for i in np.asarray(ids).ravel().tolist():
            if not 0 <= i < len(self.tokens):
                raise InvalidArgumentError(f"token id {i} out of range 0–{len(self.tokens) - 1}")
            if i != 0:
                out.append(self.tokens[i])
        return out
