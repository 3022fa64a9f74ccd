"""VLN-DT's training data: returns-to-go, windows sampled from demos, and the loss."""

from __future__ import annotations

from collections.abc import Sequence
from typing import overload

import numpy as np
import torch
from torch.nn import functional as F  # noqa: N812 - torch's convention

from havln_mj.agents.demos import Demo
from havln_mj.agents.vln_dt.model import FORWARD_KEYS, DecisionTransformer, DTConfig
from havln_mj.errors import InvalidArgumentError
from havln_mj.tasks.rewards import RewardFn


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

    A plain sequence of demos works with :func:`~.sample_windows` too, but then the returns of
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


def _checked(
    demos: Sequence[Demo], cfg: DTConfig, batch_size: int, rtg_scale: float | None
) -> tuple[DTDataset, float]:
    """The demos as a :class:`DTDataset` and the scale; raises on what sampling rejects."""
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
    return data, scale


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
            :class:`~.DTPolicy` divides by ``cfg.rtg_scale``).

    Returns:
        CPU tensors, the :meth:`~.DecisionTransformer.forward` arguments ``instruction (B, L)``,
        ``obs (B, K, D)``, ``actions (B, K)``, ``rtg (B, K)``, ``timesteps (B, K)``,
        ``step_mask (B, K)``, ``action_mask (B, K, n_actions)``, plus ``targets (B, K)`` (the
        logged actions, 0 at padding) and ``loss_mask (B, K)`` (the real steps).

    Raises:
        InvalidArgumentError: No demos, ``batch_size < 1``, an observation size other than
            ``cfg.obs_dim``, a demo longer than ``cfg.max_timestep``, or a bad scale.
    """
    data, scale = _checked(demos, cfg, batch_size, rtg_scale)
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
        batch: From :func:`~.sample_windows` (on the model's device).

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
