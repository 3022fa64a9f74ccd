"""The VLN-DT network: its configuration, transformer blocks and the decision transformer."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F  # noqa: N812 - torch's convention

from havln_mj.agents.demos import N_ACTIONS
from havln_mj.agents.text import BertTextEncoder, TextTransformer
from havln_mj.errors import InvalidArgumentError
from havln_mj.tasks.rewards import get_reward

FUSIONS = ("attention", "concat")
# The forward arguments, in order: a batch from :func:`~.sample_windows` holds these plus
# ``targets`` and ``loss_mask``.
FORWARD_KEYS = ("instruction", "obs", "actions", "rtg", "timesteps", "step_mask", "action_mask")


def _default_text() -> dict[str, Any]:
    return {"d_model": 128, "n_layers": 2, "n_heads": 4, "max_len": 80}


@dataclass
class DTConfig:
    """VLN-DT's sizes and training target (``asdict``/JSON round-trips).

    Attributes:
        vocab_size: Instruction vocabulary size (id 0 is padding).
        obs_dim: Observation size ``D``.
        n_actions: Number of actions (the six egocentric actions).
        d_model: Transformer width.
        n_layers: Causal transformer blocks.
        n_heads: Attention heads (also of the cross-attention fusion).
        dropout: Dropout in the transformer, the fusion and the text encoder (unless ``text``
            sets its own).
        context: Window length in steps (three tokens each).
        max_timestep: Size of the timestep embedding; rollouts must be at most this long.
        text: Keyword arguments of :class:`~havln_mj.agents.text.TextTransformer` (``d_model``,
            ``n_layers``, ``n_heads``, ``max_len``, optionally ``dropout``); or, to read
            instructions with a BERT from local weights instead, ``bert`` (its folder),
            ``vocab`` (the vocabulary's tokens; the trainer fills it), ``d_model`` (the size
            BERT's outputs are projected to) and ``max_len``.
        fusion: ``"attention"`` (the observation queries the instruction tokens) or
            ``"concat"`` (pooled instruction ⊕ observation).
        target_return: Return-to-go the policy starts from.
        reward: Reward of :mod:`havln_mj.tasks.rewards` the returns are computed with.
        rtg_scale: Returns-to-go are divided by this before they enter the model, both in
            :func:`~.sample_windows` and in :class:`~.DTPolicy`.
    """

    vocab_size: int
    obs_dim: int
    n_actions: int = N_ACTIONS
    d_model: int = 128
    n_layers: int = 3
    n_heads: int = 4
    dropout: float = 0.1
    context: int = 15
    max_timestep: int = 64
    text: dict[str, Any] = field(default_factory=_default_text)
    fusion: str = "attention"
    target_return: float = 5.0
    reward: str = "paper"
    rtg_scale: float = 1.0

    def __post_init__(self) -> None:
        names = ("vocab_size", "obs_dim", "n_actions", "d_model", "n_layers", "n_heads")
        for name in (*names, "context", "max_timestep"):
            value = getattr(self, name)
            if not isinstance(value, int) or isinstance(value, bool) or value < 1:
                raise InvalidArgumentError(f"DTConfig.{name} must be a positive int, got {value!r}")
        if self.d_model % self.n_heads:
            raise InvalidArgumentError(
                f"DTConfig.d_model ({self.d_model}) must be divisible by n_heads ({self.n_heads})"
            )
        if not 0.0 <= self.dropout < 1.0:
            raise InvalidArgumentError(f"DTConfig.dropout must be in [0, 1), got {self.dropout!r}")
        if self.fusion not in FUSIONS:
            raise InvalidArgumentError(
                f"DTConfig.fusion must be one of {', '.join(FUSIONS)}, got {self.fusion!r}"
            )
        if not np.isfinite(self.rtg_scale) or self.rtg_scale <= 0:
            raise InvalidArgumentError(
                f"DTConfig.rtg_scale must be a positive number, got {self.rtg_scale!r}"
            )
        if not np.isfinite(self.target_return):
            raise InvalidArgumentError(
                f"DTConfig.target_return must be finite, got {self.target_return!r}"
            )
        get_reward(self.reward)  # raises on an unknown name
        self.text = dict(self.text)  # a private copy: configs share no mutable state


class _Block(nn.Module):
    """Pre-norm transformer block; attention takes a per-sample boolean mask."""

    def __init__(self, d: int, n_heads: int, dropout: float) -> None:
        super().__init__()
        self.n_heads = n_heads
        self.dropout = dropout
        self.ln1 = nn.LayerNorm(d)
        self.qkv = nn.Linear(d, 3 * d)
        self.proj = nn.Linear(d, d)
        self.ln2 = nn.LayerNorm(d)
        self.mlp = nn.Sequential(
            nn.Linear(d, 4 * d), nn.GELU(), nn.Linear(4 * d, d), nn.Dropout(dropout)
        )
        self.drop = nn.Dropout(dropout)

    def forward(self, x: torch.Tensor, bias: torch.Tensor) -> torch.Tensor:
        """``x (B, S, d)``; ``bias (B, 1, S, S)``: 0 where query i may see key j, else -inf."""
        b, s, d = x.shape
        q, k, v = self.qkv(self.ln1(x)).split(d, dim=2)
        q, k, v = (t.view(b, s, self.n_heads, d // self.n_heads).transpose(1, 2) for t in (q, k, v))
        p = self.dropout if self.training else 0.0
        y = F.scaled_dot_product_attention(q, k, v, attn_mask=bias, dropout_p=p)
        x = x + self.drop(self.proj(y.transpose(1, 2).reshape(b, s, d)))
        return x + self.mlp(self.ln2(x))


class DecisionTransformer(nn.Module):
    """The VLN-DT network.

    Args:
        cfg: Sizes (see :class:`~.DTConfig`).
    """

    def __init__(self, cfg: DTConfig) -> None:
        super().__init__()
        self.cfg = cfg
        d = cfg.d_model
        text = dict(cfg.text)
        bert, words = text.pop("bert", None), text.pop("vocab", None)
        d_text = int(text.get("d_model", 128))
        self.text: TextTransformer | None = None
        self._bert: BertTextEncoder | None = None
        if bert is None:
            self.text = TextTransformer(cfg.vocab_size, **{"dropout": cfg.dropout, **text})
        else:
            if not words or len(words) != cfg.vocab_size:
                raise InvalidArgumentError(
                    "DTConfig.text['bert'] needs text['vocab'], the instruction vocabulary's "
                    f"{cfg.vocab_size} tokens, to turn token ids back into words"
                )
            # Frozen and loaded from the user's folder: kept out of the state_dict.
            object.__setattr__(self, "_bert", BertTextEncoder(bert, int(text.get("max_len", 80))))
            self._words = list(words)
            self.bert_proj = nn.Linear(self._bert.out_dim, d_text)
        # Features and proprioceptive inputs come on different scales: normalise first.
        self.obs_proj = nn.Sequential(nn.LayerNorm(cfg.obs_dim), nn.Linear(cfg.obs_dim, d))
        if cfg.fusion == "attention":
            self.cross = nn.MultiheadAttention(
                d, cfg.n_heads, dropout=cfg.dropout, kdim=d_text, vdim=d_text, batch_first=True
            )
        else:
            self.text_proj = nn.Linear(d_text, d)
        self.fuse = nn.Sequential(
            nn.Linear(2 * d, d), nn.GELU(), nn.Dropout(cfg.dropout), nn.Linear(d, d)
        )
        self.rtg_embed = nn.Linear(1, d)
        self.action_embed = nn.Embedding(cfg.n_actions, d)
        self.time_embed = nn.Embedding(cfg.max_timestep, d)
        self.embed_ln = nn.LayerNorm(d)
        self.drop = nn.Dropout(cfg.dropout)
        self.blocks = nn.ModuleList(
            _Block(d, cfg.n_heads, cfg.dropout) for _ in range(cfg.n_layers)
        )
        self.ln_f = nn.LayerNorm(d)
        self.head = nn.Linear(d, cfg.n_actions)

    def encode_instruction(self, instruction: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Encodes ``instruction (B, L)`` token ids: ``(tokens (B, L, d_text), pad (B, L))``."""
        if instruction.dim() != 2:
            raise InvalidArgumentError(
                f"instruction must be (B, L) token ids, got shape {tuple(instruction.shape)}"
            )
        if self._bert is None:
            return self.text(instruction.long())
        texts = [" ".join(self._words[i] for i in row if i > 0) for row in instruction.tolist()]
        tokens, pad = self._bert(texts)
        return self.bert_proj(tokens), pad

    def _states(self, obs: torch.Tensor, tokens: torch.Tensor, pad: torch.Tensor) -> torch.Tensor:
        view = self.obs_proj(obs)  # (B, K, d)
        if self.cfg.fusion == "attention":
            # An all-padding instruction would leave the softmax nothing to attend to: let
            # such rows see their first token instead of producing NaN.
            pad = pad & pad.logical_not().any(dim=1, keepdim=True)
            lang, _ = self.cross(view, tokens, tokens, key_padding_mask=pad, need_weights=False)
        else:
            pooled = self.text_proj(TextTransformer.pooled(tokens, pad))  # (B, d)
            lang = pooled.unsqueeze(1).expand_as(view)
        return self.fuse(torch.cat([view, lang], dim=-1))

    def forward(
        self,
        instruction: torch.Tensor,
        obs: torch.Tensor,
        actions: torch.Tensor,
        rtg: torch.Tensor,
        timesteps: torch.Tensor,
        step_mask: torch.Tensor,
        action_mask: torch.Tensor,
        *,
        encoded: tuple[torch.Tensor, torch.Tensor] | None = None,
    ) -> torch.Tensor:
        """Action logits for every step of a window.

        Args:
            instruction: ``(B, L)`` int64 token ids, 0 = padding.
            obs: ``(B, K, D)`` float observation before each step's action.
            actions: ``(B, K)`` int64 action of each step (``a_t``'s input token; the logits at
                step ``t`` never see it, so at the current step any valid id will do).
            rtg: ``(B, K)`` float return-to-go (already divided by ``cfg.rtg_scale``).
            timesteps: ``(B, K)`` int64 step index within the rollout, ``< cfg.max_timestep``.
            step_mask: ``(B, K)`` bool, True at real steps; padded steps (anywhere) influence
                no real step.
            action_mask: ``(B, K, n_actions)`` bool, True for valid actions.
            encoded: ``encode_instruction(instruction)`` when already computed (the policy
                encodes the instruction once per episode).

        Returns:
            ``(B, K, n_actions)`` logits; invalid actions of real steps are ``-inf``.

        Raises:
            InvalidArgumentError: Shapes that disagree with each other or the config, a window
                longer than ``cfg.context``, a timestep out of range, or a real step with no
                valid action.
        """
        cfg = self.cfg
        self._check_window(instruction, obs, actions, rtg, timesteps, step_mask, action_mask)
        step_mask, action_mask = step_mask.bool(), action_mask.bool()
        # Padded steps may hold anything: make their ids and timesteps valid, never read.
        timesteps = timesteps.masked_fill(~step_mask, 0).clamp(0, cfg.max_timestep - 1)
        actions = actions.masked_fill(~step_mask, 0).clamp(0, cfg.n_actions - 1)
        tokens, pad = self.encode_instruction(instruction) if encoded is None else encoded
        time = self.time_embed(timesteps)
        b, k = step_mask.shape
        seq = torch.stack(
            [
                self.rtg_embed(rtg.unsqueeze(-1).to(time.dtype)) + time,
                self._states(obs.to(time.dtype), tokens, pad) + time,
                self.action_embed(actions) + time,
            ],
            dim=2,
        ).reshape(b, 3 * k, cfg.d_model)  # R_1, s_1, a_1, R_2, ...
        x = self.drop(self.embed_ln(seq))
        bias = _attention_bias(step_mask, x.dtype)
        for block in self.blocks:
            x = block(x, bias)
        logits = self.head(self.ln_f(x[:, 1::3]))  # from the state tokens
        # Padded steps keep finite logits, so a loss over them cannot turn NaN.
        valid = action_mask | ~step_mask.unsqueeze(-1)
        return logits.masked_fill(~valid, float("-inf"))

    def _check_window(
        self,
        instruction: torch.Tensor,
        obs: torch.Tensor,
        actions: torch.Tensor,
        rtg: torch.Tensor,
        timesteps: torch.Tensor,
        step_mask: torch.Tensor,
        action_mask: torch.Tensor,
    ) -> None:
        """Raises InvalidArgumentError on the bad inputs :meth:`forward` lists."""
        cfg = self.cfg
        if step_mask.dim() != 2:
            raise InvalidArgumentError(
                f"step_mask must be (B, K) bool, got shape {tuple(step_mask.shape)}"
            )
        b, k = step_mask.shape
        expected = {
            "obs": (obs, (b, k, cfg.obs_dim)),
            "actions": (actions, (b, k)),
            "rtg": (rtg, (b, k)),
            "timesteps": (timesteps, (b, k)),
            "action_mask": (action_mask, (b, k, cfg.n_actions)),
        }
        for name, (tensor, shape) in expected.items():
            if tuple(tensor.shape) != shape:
                raise InvalidArgumentError(
                    f"{name} has shape {tuple(tensor.shape)}, expected {shape} (B={b}, K={k} "
                    f"from step_mask, obs_dim={cfg.obs_dim}, n_actions={cfg.n_actions})"
                )
        if k > cfg.context:
            raise InvalidArgumentError(
                f"window of {k} steps is longer than the context of {cfg.context} steps"
            )
        if instruction.shape[0] != b:
            raise InvalidArgumentError(
                f"instruction has batch size {instruction.shape[0]}, the steps have {b}"
            )
        real_times = timesteps[step_mask.bool()]
        if real_times.numel() and (real_times.min() < 0 or real_times.max() >= cfg.max_timestep):
            raise InvalidArgumentError(
                f"timesteps must be in [0, {cfg.max_timestep}) (cfg.max_timestep), got "
                f"{int(real_times.min())}..{int(real_times.max())}"
            )
        if (step_mask.bool() & ~action_mask.bool().any(dim=-1)).any():
            raise InvalidArgumentError("a real step has no valid action in action_mask")


def _attention_bias(step_mask: torch.Tensor, dtype: torch.dtype) -> torch.Tensor:
    """``(B, 1, 3K, 3K)`` additive mask: causal, no padded key, every token sees itself.

    Seeing itself keeps padded queries finite; an additive mask runs faster than a boolean
    one in CPU attention.
    """
    s = 3 * step_mask.shape[1]
    device = step_mask.device
    causal = torch.ones(s, s, dtype=torch.bool, device=device).tril()
    real = step_mask.repeat_interleave(3, dim=1)  # (B, 3K)
    eye = torch.eye(s, dtype=torch.bool, device=device)
    allowed = ((causal & real[:, None, :]) | eye).unsqueeze(1)
    bias = torch.zeros(allowed.shape, dtype=dtype, device=device)
    return bias.masked_fill(~allowed, float("-inf"))
