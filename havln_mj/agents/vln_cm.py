"""VLN-CM: HA-VLN's cross-modal sequence-to-sequence agent (HA3D's R2R seq2seq, refined).

* **Instruction encoder**: word embeddings and an LSTM over the instruction's tokens; its last
  state starts the decoder.
* **Decoder**: an LSTM cell that reads the previous action's embedding and the projected
  observation (the view feature and the agent's own inputs, :mod:`havln_mj.agents.observations`).
* **Cross-modal fusion**: the decoder state attends over the instruction's words (language
  context); the observation gives a visual context; a softmax gate computed from the state and
  both contexts weights language against vision, and the weighted sum with the state makes
  the attended state the action logits are read from. The gate's weights are returned, so an
  analysis can tell when the agent looks and when it reads.
* **Actions**: the six egocentric actions; invalid ones (FORWARD with nothing ahead, looking
  past the elevation limits) are masked.

Training (teacher forcing on demos, student forcing against the human-aware expert) lives in
:mod:`havln_mj.agents.train`; :class:`CMPolicy` runs a trained model one step at a time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F  # noqa: N812 - torch's convention

from havln_mj.agents.demos import N_ACTIONS
from havln_mj.errors import InvalidArgumentError

NEG_INF = -1e9  # logit of a masked action (finite, so a fully masked row stays a number)


@dataclass
class CMConfig:
    """VLN-CM's sizes (HA3D: words 256, hidden 512, action embedding 32, dropout 0.5).

    Attributes:
        vocab_size: Instruction vocabulary size (id 0 is padding).
        obs_dim: Observation size.
        word_dim: Word embedding size.
        hidden: LSTM and attention size.
        action_dim: Previous-action embedding size.
        dropout: Dropout on embeddings and observations.
    """

    vocab_size: int
    obs_dim: int
    word_dim: int = 256
    hidden: int = 512
    action_dim: int = 32
    dropout: float = 0.5

    def __post_init__(self) -> None:
        for name in ("vocab_size", "obs_dim", "word_dim", "hidden", "action_dim"):
            value = getattr(self, name)
            if not isinstance(value, int) or value < 1:
                raise InvalidArgumentError(f"CMConfig.{name} must be a positive int, got {value!r}")
        if not 0.0 <= self.dropout < 1.0:
            raise InvalidArgumentError(f"CMConfig.dropout must be in [0, 1), got {self.dropout!r}")


START = N_ACTIONS
"""The "previous action" token of the first step."""


def masked_logits(logits: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """``logits`` with the actions ``mask`` forbids set to a large negative number."""
    return logits.masked_fill(~mask, NEG_INF)


class VLNCM(nn.Module):
    """The VLN-CM network.

    Args:
        cfg: Sizes.
    """

    def __init__(self, cfg: CMConfig) -> None:
        super().__init__()
        self.cfg = cfg
        h = cfg.hidden
        self.embed = nn.Embedding(cfg.vocab_size, cfg.word_dim, padding_idx=0)
        self.encoder = nn.LSTM(cfg.word_dim, h, batch_first=True)
        self.action_embed = nn.Embedding(N_ACTIONS + 1, cfg.action_dim)
        self.obs_proj = nn.Linear(cfg.obs_dim, h)
        self.decoder = nn.LSTMCell(cfg.action_dim + h, h)
        self.query = nn.Linear(h, h, bias=False)
        self.gate = nn.Linear(3 * h, 2)
        self.attended = nn.Linear(2 * h, h, bias=False)
        self.head = nn.Linear(h, N_ACTIONS)
        self.drop = nn.Dropout(cfg.dropout)

    def encode(
        self, instruction: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor, tuple[torch.Tensor, torch.Tensor]]:
        """Encodes ``(B, L)`` token ids.

        An empty instruction (HA-R2R has a few) is read as one padding token, so the agent
        still acts, on what it sees.

        Returns:
            The word contexts ``(B, L, H)``, the padding mask ``(B, L)`` (True at padding)
            and the decoder's initial state.
        """
        pad = instruction == 0
        pad[pad.all(dim=1), 0] = False
        lengths = (~pad).sum(1)
        packed = nn.utils.rnn.pack_padded_sequence(
            self.drop(self.embed(instruction)),
            lengths.cpu(),
            batch_first=True,
            enforce_sorted=False,
        )
        out, (h, c) = self.encoder(packed)
        ctx, _ = nn.utils.rnn.pad_packed_sequence(
            out, batch_first=True, total_length=instruction.shape[1]
        )
        return ctx, pad, (h[0], c[0])

    def step(
        self,
        obs: torch.Tensor,
        prev_action: torch.Tensor,
        state: tuple[torch.Tensor, torch.Tensor],
        ctx: torch.Tensor,
        pad: torch.Tensor,
        action_mask: torch.Tensor,
    ) -> tuple[torch.Tensor, tuple[torch.Tensor, torch.Tensor], dict[str, torch.Tensor]]:
        """One decoding step for a batch.

        Args:
            obs: ``(B, D)`` observations.
            prev_action: ``(B,)`` previous actions (:data:`START` at the first step).
            state: The decoder's ``(h, c)``.
            ctx: Word contexts from :meth:`encode`.
            pad: Padding mask from :meth:`encode`.
            action_mask: ``(B, 6)`` valid actions.

        Returns:
            Masked logits ``(B, 6)``, the new state, and the attention: ``"words"`` ``(B, L)``
            and ``"gate"`` ``(B, 2)`` (language, vision).
        """
        vis = torch.tanh(self.obs_proj(self.drop(obs)))
        x = torch.cat([self.action_embed(prev_action), vis], dim=1)
        h, c = self.decoder(x, state)
        scores = torch.bmm(ctx, self.query(h).unsqueeze(2)).squeeze(2)
        words = torch.softmax(scores.masked_fill(pad, NEG_INF), dim=1)
        lang = torch.bmm(words.unsqueeze(1), ctx).squeeze(1)
        gate = torch.softmax(self.gate(torch.cat([h, lang, vis], dim=1)), dim=1)
        fused = gate[:, :1] * lang + gate[:, 1:] * vis
        attended = torch.tanh(self.attended(torch.cat([fused, h], dim=1)))
        logits = masked_logits(self.head(self.drop(attended)), action_mask)
        return logits, (h, c), {"words": words, "gate": gate}

    def forward(
        self,
        instruction: torch.Tensor,
        obs: torch.Tensor,
        prev_actions: torch.Tensor,
        action_mask: torch.Tensor,
    ) -> torch.Tensor:
        """Teacher-forced logits ``(B, T, 6)`` for whole sequences.

        Args:
            instruction: ``(B, L)`` token ids.
            obs: ``(B, T, D)`` observations.
            prev_actions: ``(B, T)`` the action before each step (:data:`START` first).
            action_mask: ``(B, T, 6)`` valid actions (padded steps: any valid row).
        """
        ctx, pad, state = self.encode(instruction)
        out = []
        for t in range(obs.shape[1]):
            logits, state, _ = self.step(
                obs[:, t], prev_actions[:, t], state, ctx, pad, action_mask[:, t]
            )
            out.append(logits)
        return torch.stack(out, dim=1)


def sequence_loss(logits: torch.Tensor, targets: torch.Tensor, valid: torch.Tensor) -> torch.Tensor:
    """Mean cross-entropy over the ``valid`` steps of ``(B, T, 6)`` logits."""
    ce = F.cross_entropy(logits.reshape(-1, N_ACTIONS), targets.reshape(-1), reduction="none")
    valid = valid.reshape(-1).float()
    return (ce * valid).sum() / valid.sum().clamp(min=1.0)


class CMPolicy:
    """Runs a trained VLN-CM one step at a time (evaluation).

    Args:
        model: The network (put in eval mode).
    """

    def __init__(self, model: VLNCM) -> None:
        self.model = model.eval()
        self._device = next(model.parameters()).device
        self._ctx: tuple | None = None

    @torch.no_grad()
    def reset(self, instruction: np.ndarray) -> None:
        """Starts an episode with ``(L,)`` token ids."""
        ids = torch.as_tensor(np.asarray(instruction, np.int64), device=self._device)
        ctx, pad, state = self.model.encode(ids.unsqueeze(0))
        self._ctx = (ctx, pad)
        self._state = state
        self._prev = torch.tensor([START], device=self._device)

    @torch.no_grad()
    def act(
        self,
        obs: np.ndarray,
        action_mask: np.ndarray,
        last_reward: float | None = None,
        *,
        greedy: bool = True,
        rng: np.random.Generator | None = None,
    ) -> int:
        """The next action (``last_reward`` is not used by VLN-CM).

        Raises:
            InvalidArgumentError: Called before :meth:`reset`, or sampling without ``rng``.
        """
        if self._ctx is None:
            raise InvalidArgumentError("CMPolicy.act called before reset()")
        dev = self._device
        logits, self._state, _ = self.model.step(
            torch.as_tensor(obs, dtype=torch.float32, device=dev).unsqueeze(0),
            self._prev,
            self._state,
            *self._ctx,
            torch.as_tensor(action_mask, dtype=torch.bool, device=dev).unsqueeze(0),
        )
        action = choose(logits[0].cpu(), greedy, rng)
        self._prev = torch.tensor([action], device=dev)
        return action


def choose(logits: torch.Tensor, greedy: bool, rng: np.random.Generator | None) -> int:
    """The argmax of ``(6,)`` logits, or a sample drawn with ``rng``.

    Raises:
        InvalidArgumentError: Sampling without a generator.
    """
    if greedy:
        return int(torch.argmax(logits))
    if rng is None:
        raise InvalidArgumentError("sampling actions needs a numpy Generator (rng=...)")
    p = torch.softmax(logits.double(), dim=0).numpy()
    return int(rng.choice(len(p), p=p / p.sum()))
