"""Instruction encoders in plain torch: a small transformer, or a user's local BERT.

Word ids come from :class:`havln_mj.tasks.vocab.Vocabulary` (id 0 = padding, 1 = unknown);
:func:`encode_texts` batches them. :class:`TextTransformer` is trained with the agent.
:class:`BertTextEncoder` wraps a frozen Hugging Face model the user already has on disk
(HA3D's VLN-DT used BART-base's first token); it needs ``transformers`` and never downloads.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import Tensor, nn

from havln_mj.errors import DependencyNotInstalledError, InvalidArgumentError, MissingDataError
from havln_mj.tasks.vocab import Vocabulary


def encode_texts(vocab: Vocabulary, texts: Sequence[str], length: int) -> Tensor:
    """``(B, length)`` int64 ids of ``texts`` (cut or 0-padded), for :class:`TextTransformer`."""
    if not texts:
        return torch.zeros((0, length), dtype=torch.long)
    return torch.from_numpy(np.stack([vocab.encode(t, length) for t in texts]))


class TextTransformer(nn.Module):
    """Token + learned position embeddings, then a pre-norm ``nn.TransformerEncoder``.

    Padding (id 0) is excluded from attention through ``src_key_padding_mask``, so the outputs
    at real tokens do not depend on how much padding follows them. A row of padding only
    (an empty instruction) lets its first position attend to itself (a fully masked softmax
    would be NaN); its mask still marks every position as padding.

    Attributes:
        out_dim: ``d_model``.
        max_len: Longest sequence accepted.
    """

    def __init__(
        self,
        vocab_size: int,
        d_model: int = 128,
        n_layers: int = 2,
        n_heads: int = 4,
        max_len: int = 80,
        dropout: float = 0.1,
    ) -> None:
        """Builds the encoder (feed-forward width ``4 · d_model``, GELU).

        Raises:
            InvalidArgumentError: Non-positive sizes, ``d_model`` not divisible by ``n_heads``,
                or ``dropout`` outside ``[0, 1)``.
        """
        super().__init__()
        if min(vocab_size, d_model, n_layers, n_heads, max_len) < 1:
            raise InvalidArgumentError(
                f"vocab_size={vocab_size}, d_model={d_model}, n_layers={n_layers}, "
                f"n_heads={n_heads}, max_len={max_len}: all must be ≥ 1"
            )
        if d_model % n_heads:
            raise InvalidArgumentError(f"d_model {d_model} is not divisible by n_heads {n_heads}")
        if not 0.0 <= dropout < 1.0:
            raise InvalidArgumentError(f"dropout {dropout!r}; valid: 0 ≤ p < 1")
        self.vocab_size, self.d_model, self.n_layers = int(vocab_size), int(d_model), int(n_layers)
        self.n_heads, self.max_len, self.dropout = int(n_heads), int(max_len), float(dropout)
        self.out_dim = self.d_model
        self.tokens = nn.Embedding(vocab_size, d_model, padding_idx=0)
        self.positions = nn.Embedding(max_len, d_model)
        self.embed_dropout = nn.Dropout(dropout)
        layer = nn.TransformerEncoderLayer(
            d_model,
            n_heads,
            dim_feedforward=4 * d_model,
            dropout=dropout,
            activation="gelu",
            batch_first=True,
            norm_first=True,  # pre-norm: stable without warm-up at small scale
        )
        # Nested tensors are off: they are incompatible with pre-norm and would zero the
        # outputs at padding, which callers may pool themselves.
        self.encoder = nn.TransformerEncoder(
            layer, n_layers, norm=nn.LayerNorm(d_model), enable_nested_tensor=False
        )
        nn.init.normal_(self.tokens.weight, std=0.02)
        nn.init.normal_(self.positions.weight, std=0.02)
        with torch.no_grad():
            self.tokens.weight[0].zero_()

    def config(self) -> dict[str, Any]:
        """The constructor arguments (JSON-serialisable), for checkpoints."""
        return {
            "vocab_size": self.vocab_size,
            "d_model": self.d_model,
            "n_layers": self.n_layers,
            "n_heads": self.n_heads,
            "max_len": self.max_len,
            "dropout": self.dropout,
        }

    @classmethod
    def from_config(cls, cfg: Mapping[str, Any]) -> TextTransformer:
        """A fresh encoder built from :meth:`config`'s output (weights are not included)."""
        return cls(**cfg)

    def forward(self, ids: Tensor) -> tuple[Tensor, Tensor]:
        """Encodes token ids.

        Args:
            ids: ``(B, L)`` int64 token ids, 0 = padding, ``L ≤ max_len``.

        Returns:
            ``(B, L, d_model)`` token features and the ``(B, L)`` bool mask, True at padding.

        Raises:
            InvalidArgumentError: Wrong shape, ``L > max_len`` or ids outside the vocabulary.
        """
        if ids.ndim != 2 or ids.dtype not in (torch.int64, torch.int32):
            raise InvalidArgumentError(
                f"ids must be (B, L) integers, got {ids.dtype} {tuple(ids.shape)}"
            )
        length = ids.shape[1]
        if length > self.max_len:
            raise InvalidArgumentError(f"sequence length {length} exceeds max_len {self.max_len}")
        if ids.numel() and (int(ids.min()) < 0 or int(ids.max()) >= self.vocab_size):
            raise InvalidArgumentError(
                f"token ids {int(ids.min())}…{int(ids.max())} outside 0…{self.vocab_size - 1}"
            )
        ids = ids.long()
        pad_mask = ids == 0
        pos = torch.arange(length, device=ids.device)
        x = self.embed_dropout(self.tokens(ids) + self.positions(pos))
        attn_mask = pad_mask.clone()
        if length:
            attn_mask[:, 0] &= ~pad_mask.all(dim=1)  # all-padding rows: see class docstring
        return self.encoder(x, src_key_padding_mask=attn_mask), pad_mask

    @staticmethod
    def pooled(tokens: Tensor, pad_mask: Tensor) -> Tensor:
        """Mean of ``tokens`` ``(B, L, D)`` over real positions (``pad_mask`` False).

        Rows without a real token give zeros.
        """
        keep = (~pad_mask).unsqueeze(-1).to(tokens.dtype)
        return (tokens * keep).sum(dim=1) / keep.sum(dim=1).clamp(min=1.0)


class BertTextEncoder(nn.Module):
    """A frozen Hugging Face text model loaded from a local folder (no downloads).

    Any ``AutoModel`` folder works (BERT, BART, …); encoder-decoder models contribute their
    encoder. The model stays in eval mode (no dropout) and receives no gradients.

    Attributes:
        out_dim: The model's hidden size.
        max_len: Longest tokenised instruction (longer ones are cut).
    """

    def __init__(self, path: str | Path, max_len: int = 80) -> None:
        """Loads the tokenizer and model from ``path`` with ``local_files_only=True``.

        Raises:
            MissingDataError: ``path`` is not a folder.
            DependencyNotInstalledError: ``transformers`` is not installed.
        """
        super().__init__()
        path = Path(path).expanduser()
        if not path.is_dir():
            raise MissingDataError(
                f"text model folder {path} not found; save one locally with "
                "AutoTokenizer/AutoModel.from_pretrained(name).save_pretrained(folder)"
            )
        try:
            transformers = importlib.import_module("transformers")
        except ImportError as exc:
            raise DependencyNotInstalledError(
                "BertTextEncoder needs Hugging Face transformers: pip install transformers"
            ) from exc
        self.max_len = int(max_len)
        self.tokenizer = transformers.AutoTokenizer.from_pretrained(path, local_files_only=True)
        model = transformers.AutoModel.from_pretrained(path, local_files_only=True)
        if getattr(model.config, "is_encoder_decoder", False):
            model = model.get_encoder()
        self.model = model.eval().requires_grad_(False)
        self.out_dim = int(model.config.hidden_size)

    def train(self, mode: bool = True) -> BertTextEncoder:
        """Keeps the frozen model in eval mode whatever ``mode`` is."""
        super().train(mode)
        self.model.eval()
        return self

    @torch.no_grad()
    def forward(self, texts: list[str]) -> tuple[Tensor, Tensor]:
        """``(B, L, hidden)`` token features of ``texts`` and the mask (True at padding)."""
        batch = self.tokenizer(
            list(texts),
            padding=True,
            truncation=True,
            max_length=self.max_len,
            return_tensors="pt",
        )
        device = next(self.model.parameters()).device
        batch = {k: v.to(device) for k, v in batch.items()}
        out = self.model(input_ids=batch["input_ids"], attention_mask=batch["attention_mask"])
        return out.last_hidden_state, batch["attention_mask"] == 0
