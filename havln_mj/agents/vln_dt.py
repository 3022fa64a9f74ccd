"""VLN-DT: HA-VLN's decision transformer, trained offline on random walks by behaviour cloning.

Each step ``t`` of a rollout gives three tokens, ``R_t, s_t, a_t``:

* ``R_t``, the return-to-go: the sum of the rewards from step ``t`` to the end of the rollout
  (at test time: a target, 5 in the paper, minus the rewards collected so far);
* ``s_t``, the state: the observation (view feature and the agent's own inputs, opaque here)
  fused with the instruction, which a :class:`~havln_mj.agents.text.TextTransformer` encodes
  once per sequence. ``"attention"`` fusion lets the projected observation query the
  instruction's tokens by cross-attention; ``"concat"`` joins it with the pooled instruction;
* ``a_t``, the action taken.

A timestep embedding is added to all three. A causal transformer reads
``R_1, s_1, a_1, R_2, s_2, a_2, …`` and the action ``a_t`` is predicted from the output at
``s_t``, which has seen ``R_{≤t}``, ``s_{≤t}`` and ``a_{<t}``. Training is cross-entropy on
the logged actions over windows of at most ``context`` steps (:func:`sample_windows`,
:func:`dt_loss`); :class:`DTPolicy` acts one step at a time with the return-to-go bookkeeping
``R_{t+1} = R_t − r_t``.

HA3D's VLN-DT (``reference/ha3d_facts.md`` §5, §9) is a 12-layer minGPT over ResNet-152 and
BART features with a 5-step window; the issue fixes the paper's numbers instead: a 15-step
window and an initial return-to-go of 5, on 10⁴ random walks of at most 30 steps.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, overload

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F  # noqa: N812 - torch's convention

from havln_mj.agents.demos import N_ACTIONS, Demo
from havln_mj.agents.text import BertTextEncoder, TextTransformer
from havln_mj.errors import InvalidArgumentError
from havln_mj.tasks.rewards import RewardFn, get_reward

FUSIONS = ("attention", "concat")
# The forward arguments, in order: a batch from :func:`sample_windows` holds these plus
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
            :func:`sample_windows` and in :class:`DTPolicy`.
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
        cfg: Sizes (see :class:`DTConfig`).
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
        step_mask = step_mask.bool()
        action_mask = action_mask.bool()
        real_times = timesteps[step_mask]
        if real_times.numel() and (real_times.min() < 0 or real_times.max() >= cfg.max_timestep):
            raise InvalidArgumentError(
                f"timesteps must be in [0, {cfg.max_timestep}) (cfg.max_timestep), got "
                f"{int(real_times.min())}..{int(real_times.max())}"
            )
        if (step_mask & ~action_mask.any(dim=-1)).any():
            raise InvalidArgumentError("a real step has no valid action in action_mask")
        # Padded steps may hold anything: make their ids and timesteps valid, never read.
        timesteps = timesteps.masked_fill(~step_mask, 0).clamp(0, cfg.max_timestep - 1)
        actions = actions.masked_fill(~step_mask, 0).clamp(0, cfg.n_actions - 1)

        tokens, pad = self.encode_instruction(instruction) if encoded is None else encoded
        time = self.time_embed(timesteps)
        seq = torch.stack(
            [
                self.rtg_embed(rtg.unsqueeze(-1).to(time.dtype)) + time,
                self._states(obs.to(time.dtype), tokens, pad) + time,
                self.action_embed(actions) + time,
            ],
            dim=2,
        ).reshape(b, 3 * k, cfg.d_model)  # R_1, s_1, a_1, R_2, ...
        x = self.drop(self.embed_ln(seq))

        s = 3 * k
        causal = torch.ones(s, s, dtype=torch.bool, device=x.device).tril()
        real = step_mask.repeat_interleave(3, dim=1)  # (B, 3K)
        # Causal, no padded key; every token sees itself so padded queries stay finite.
        eye = torch.eye(s, dtype=torch.bool, device=x.device)
        allowed = ((causal & real[:, None, :]) | eye).unsqueeze(1)  # (B, 1, S, S)
        # An additive mask: CPU attention runs it faster than a boolean one.
        bias = torch.zeros(allowed.shape, dtype=x.dtype, device=x.device)
        bias = bias.masked_fill(~allowed, float("-inf"))
        for block in self.blocks:
            x = block(x, bias)
        logits = self.head(self.ln_f(x[:, 1::3]))  # from the state tokens
        # Padded steps keep finite logits, so a loss over them cannot turn NaN.
        valid = action_mask | ~step_mask.unsqueeze(-1)
        return logits.masked_fill(~valid, float("-inf"))


def returns_to_go(rewards: np.ndarray) -> np.ndarray:
    """Suffix sums of one rollout's rewards: ``out[t] = rewards[t:].sum()``.

    Args:
        rewards: ``(T,)`` rewards.

    Returns:
        ``(T,)`` float32 returns-to-go.

    Raises:
        InvalidArgumentError: ``rewards`` is not one-dimensional.
    """
    r = np.asarray(rewards, dtype=np.float64)
    if r.ndim != 1:
        raise InvalidArgumentError(f"rewards must be one-dimensional (T,), got shape {r.shape}")
    # Accumulate in float64 so long sums of ±0.1 do not drift before the cast.
    return np.cumsum(r[::-1])[::-1].astype(np.float32)


class DTDataset(Sequence[Demo]):
    """Demos with their returns-to-go cached per reward, for cheap window sampling.

    A plain sequence of demos works with :func:`sample_windows` too, but then the returns of
    the sampled demos are recomputed on every call; wrap the training set once in this.
    Observations are not copied (the demos' arrays are sliced per window).

    Args:
        demos: The rollouts; all with the same observation size.

    Raises:
        InvalidArgumentError: No demos, or observation sizes that differ.
    """

    def __init__(self, demos: Sequence[Demo]) -> None:
        self._demos = list(demos)
        if not self._demos:
            raise InvalidArgumentError("no demos to sample windows from (got an empty list)")
        dims = {int(d.obs.shape[1]) for d in self._demos}
        if len(dims) != 1:
            raise InvalidArgumentError(f"demos have different observation sizes {sorted(dims)}")
        self.obs_dim = dims.pop()
        self.lengths = np.array([len(d) for d in self._demos], dtype=np.int64)
        self._rtg: dict[str | RewardFn, list[np.ndarray | None]] = {}

    def __len__(self) -> int:
        return len(self._demos)

    @overload
    def __getitem__(self, i: int) -> Demo: ...

    @overload
    def __getitem__(self, i: slice) -> Sequence[Demo]: ...

    def __getitem__(self, i: int | slice) -> Demo | Sequence[Demo]:
        return self._demos[i]

    def returns(self, i: int, reward: str | RewardFn) -> np.ndarray:
        """``(T,)`` float32 returns-to-go of demo ``i`` under ``reward``, computed once."""
        cache = self._rtg.setdefault(reward, [None] * len(self._demos))
        if cache[i] is None:
            cache[i] = returns_to_go(self._demos[i].rewards(reward))
        return cache[i]


def sample_windows(
    demos: Sequence[Demo],
    cfg: DTConfig,
    batch_size: int,
    rng: np.random.Generator,
    reward: str | RewardFn | None = None,
    rtg_scale: float | None = None,
) -> dict[str, torch.Tensor]:
    """A batch of random windows of at most ``cfg.context`` steps.

    Every step of the dataset is equally likely to end a window: a demo is drawn with
    probability proportional to its length, then the window's last step uniformly among its
    steps, and the window reaches back ``cfg.context`` steps or to the demo's start. So every
    logged action is a target, and long and short rollouts count per step, not per rollout.
    Returns-to-go are those of the whole demo (suffix sums from each step to its end), divided
    by the scale. Windows are right-padded to the longest one in the batch (``K ≤ context``);
    instructions are 0-padded to the longest one.

    Args:
        demos: The rollouts; a :class:`DTDataset` caches their returns between calls.
        cfg: The model's config (``context``, ``obs_dim``, ``max_timestep``, defaults).
        batch_size: Windows per batch.
        rng: Source of the draws.
        reward: Reward name or function; ``cfg.reward`` if None.
        rtg_scale: Divisor of the returns-to-go; ``cfg.rtg_scale`` if None (keep them equal:
            :class:`DTPolicy` divides by ``cfg.rtg_scale``).

    Returns:
        CPU tensors, the :meth:`DecisionTransformer.forward` arguments ``instruction (B, L)``,
        ``obs (B, K, D)``, ``actions (B, K)``, ``rtg (B, K)``, ``timesteps (B, K)``,
        ``step_mask (B, K)``, ``action_mask (B, K, n_actions)``, plus ``targets (B, K)`` (the
        logged actions, 0 at padding) and ``loss_mask (B, K)`` (the real steps).

    Raises:
        InvalidArgumentError: No demos, ``batch_size < 1``, an observation size other than
            ``cfg.obs_dim``, a demo longer than ``cfg.max_timestep``, or a bad scale.
    """
    if batch_size < 1:
        raise InvalidArgumentError(f"batch_size must be at least 1, got {batch_size}")
    scale = cfg.rtg_scale if rtg_scale is None else float(rtg_scale)
    if not np.isfinite(scale) or scale <= 0:
        raise InvalidArgumentError(f"rtg_scale must be a positive number, got {rtg_scale!r}")
    data = demos if isinstance(demos, DTDataset) else DTDataset(demos)
    if data.obs_dim != cfg.obs_dim:
        raise InvalidArgumentError(
            f"demos have observations of size {data.obs_dim}, the config expects "
            f"obs_dim={cfg.obs_dim}"
        )
    longest = int(data.lengths.max())
    if longest > cfg.max_timestep:
        raise InvalidArgumentError(
            f"a demo has {longest} steps, more than cfg.max_timestep={cfg.max_timestep}"
        )
    reward = cfg.reward if reward is None else reward

    idx = rng.choice(len(data), size=batch_size, p=data.lengths / data.lengths.sum())
    ends = rng.integers(0, data.lengths[idx])  # inclusive last step of each window
    starts = np.maximum(ends - cfg.context + 1, 0)
    n = ends - starts + 1
    k = int(n.max())
    n_instr = max(len(data[i].instruction) for i in idx)

    instruction = np.zeros((batch_size, n_instr), np.int64)
    obs = np.zeros((batch_size, k, cfg.obs_dim), np.float32)
    actions = np.zeros((batch_size, k), np.int64)
    rtg = np.zeros((batch_size, k), np.float32)
    timesteps = np.zeros((batch_size, k), np.int64)
    action_mask = np.ones((batch_size, k, cfg.n_actions), bool)  # all valid at padding
    step_mask = np.arange(k)[None, :] < n[:, None]
    for row, (i, s, e) in enumerate(zip(idx, starts, ends + 1, strict=True)):
        demo, m = data[i], e - s
        instruction[row, : len(demo.instruction)] = demo.instruction
        obs[row, :m] = demo.obs[s:e]
        actions[row, :m] = demo.actions[s:e]
        rtg[row, :m] = data.returns(i, reward)[s:e] / scale
        timesteps[row, :m] = np.arange(s, e)
        action_mask[row, :m] = demo.masks[s:e]
    out = {
        "instruction": instruction,
        "obs": obs,
        "actions": actions,
        "rtg": rtg,
        "timesteps": timesteps,
        "step_mask": step_mask,
        "action_mask": action_mask,
        "targets": actions.copy(),
        "loss_mask": step_mask.copy(),
    }
    return {name: torch.from_numpy(array) for name, array in out.items()}


def dt_loss(model: DecisionTransformer, batch: dict[str, torch.Tensor]) -> torch.Tensor:
    """Mean cross-entropy of the logged actions over the real steps of a batch.

    Args:
        model: The network.
        batch: From :func:`sample_windows` (on the model's device).

    Returns:
        Scalar loss.

    Raises:
        InvalidArgumentError: The batch has no step to learn from.
    """
    logits = model(*(batch[name] for name in FORWARD_KEYS))
    keep = batch["loss_mask"].bool()
    if not keep.any():
        raise InvalidArgumentError("the batch's loss_mask selects no step")
    # Select first: padded rows never reach the loss (nor its gradient).
    return F.cross_entropy(logits[keep], batch["targets"][keep].long())


class DTPolicy:
    """Runs a trained :class:`DecisionTransformer` one step at a time.

    The return-to-go starts at the target and drops by each reward received
    (``R_{t+1} = R_t − r_t``); the last ``cfg.context`` steps are fed to the model, with their
    absolute timesteps (capped at ``cfg.max_timestep − 1``). The instruction is encoded once
    per episode. The model is run in eval mode and without gradients; its own mode is restored.

    Args:
        model: The network (its device is used).
        target_return: Initial return-to-go in reward units; ``cfg.target_return`` if None.
    """

    def __init__(self, model: DecisionTransformer, *, target_return: float | None = None) -> None:
        self.model = model
        self.cfg = model.cfg
        self.target_return = float(
            self.cfg.target_return if target_return is None else target_return
        )
        if not np.isfinite(self.target_return):
            raise InvalidArgumentError(f"target_return must be finite, got {target_return!r}")
        self._encoded: tuple[torch.Tensor, torch.Tensor] | None = None
        self._instruction: torch.Tensor | None = None
        c = self.cfg.context
        self._obs: deque[np.ndarray] = deque(maxlen=c)
        self._masks: deque[np.ndarray] = deque(maxlen=c)
        self._actions: deque[int] = deque(maxlen=c)
        self._rtg: deque[float] = deque(maxlen=c)
        self._times: deque[int] = deque(maxlen=c)
        self._t = 0
        self._rtg_now = self.target_return

    @property
    def returns_to_go(self) -> list[float]:
        """Returns-to-go of the steps in the window (reward units), oldest first."""
        return list(self._rtg)

    @property
    def timesteps(self) -> list[int]:
        """Timesteps of the steps in the window, oldest first."""
        return list(self._times)

    @property
    def actions(self) -> list[int]:
        """Actions chosen at the steps in the window, oldest first."""
        return list(self._actions)

    def _device(self) -> torch.device:
        return next(self.model.parameters()).device

    def reset(self, instruction: np.ndarray) -> None:
        """Starts an episode: encodes ``instruction (L,)`` and sets the return to the target."""
        ids = np.asarray(instruction)
        if ids.ndim != 1 or not np.issubdtype(ids.dtype, np.integer):
            raise InvalidArgumentError(
                f"instruction must be (L,) integer token ids, got {ids.dtype} of shape {ids.shape}"
            )
        self._instruction = torch.as_tensor(ids, dtype=torch.long, device=self._device())[None]
        was_training = self.model.training
        self.model.eval()
        try:
            with torch.no_grad():
                self._encoded = self.model.encode_instruction(self._instruction)
        finally:
            self.model.train(was_training)
        for buf in (self._obs, self._masks, self._actions, self._rtg, self._times):
            buf.clear()
        self._t = 0
        self._rtg_now = self.target_return

    def act(
        self,
        obs: np.ndarray,
        action_mask: np.ndarray,
        last_reward: float | None,
        *,
        greedy: bool = True,
        rng: np.random.Generator | None = None,
    ) -> int:
        """Chooses the next action.

        Args:
            obs: ``(D,)`` observation now.
            action_mask: ``(n_actions,)`` bool, the valid actions now.
            last_reward: Reward of the previous action; None at the first step only.
            greedy: Take the most likely action, else sample from the policy.
            rng: Source of the draw when sampling.

        Returns:
            The action, always valid under ``action_mask``.

        Raises:
            InvalidArgumentError: No :meth:`reset`, a wrong shape, no valid action, a missing
                (or premature) ``last_reward``, or sampling without ``rng``.
        """
        cfg = self.cfg
        if self._encoded is None or self._instruction is None:
            raise InvalidArgumentError("DTPolicy.act called before reset(instruction)")
        obs = np.asarray(obs, dtype=np.float32)
        mask = np.asarray(action_mask, dtype=bool)
        if obs.shape != (cfg.obs_dim,):
            raise InvalidArgumentError(
                f"obs has shape {obs.shape}, expected ({cfg.obs_dim},) (cfg.obs_dim)"
            )
        if mask.shape != (cfg.n_actions,) or not mask.any():
            raise InvalidArgumentError(
                f"action_mask must be ({cfg.n_actions},) bool with a valid action, got {mask}"
            )
        if (last_reward is None) != (self._t == 0):
            raise InvalidArgumentError(
                f"last_reward must be None at the first step and a number after, got "
                f"{last_reward!r} at step {self._t}"
            )
        if not greedy and rng is None:
            raise InvalidArgumentError("sampling (greedy=False) needs an rng")
        if last_reward is not None:
            if not np.isfinite(last_reward):
                raise InvalidArgumentError(f"last_reward must be finite, got {last_reward!r}")
            self._rtg_now -= float(last_reward)

        self._obs.append(obs)
        self._masks.append(mask)
        self._actions.append(0)  # a placeholder: step t's logits never see a_t
        self._rtg.append(self._rtg_now)
        self._times.append(min(self._t, cfg.max_timestep - 1))

        dev = self._device()
        k = len(self._obs)
        was_training = self.model.training
        self.model.eval()
        try:
            with torch.no_grad():
                logits = self.model(
                    self._instruction,
                    torch.as_tensor(np.stack(self._obs), device=dev)[None],
                    torch.tensor([list(self._actions)], dtype=torch.long, device=dev),
                    torch.tensor([list(self._rtg)], dtype=torch.float32, device=dev)
                    / cfg.rtg_scale,
                    torch.tensor([list(self._times)], dtype=torch.long, device=dev),
                    torch.ones(1, k, dtype=torch.bool, device=dev),
                    torch.as_tensor(np.stack(self._masks), device=dev)[None],
                    encoded=self._encoded,
                )[0, -1]
        finally:
            self.model.train(was_training)
        if greedy:
            action = int(logits.argmax())
        else:
            p = torch.softmax(logits.double(), dim=0).cpu().numpy()
            p[~mask] = 0.0  # exact zeros, and renormalise the float rounding away
            action = int(rng.choice(cfg.n_actions, p=p / p.sum()))
        self._actions[-1] = action
        self._t += 1
        return action
