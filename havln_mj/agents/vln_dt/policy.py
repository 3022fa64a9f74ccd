"""VLN-DT acting one step at a time, with the return-to-go bookkeeping."""

from __future__ import annotations

from collections import deque

import numpy as np
import torch

from havln_mj.agents.vln_dt.model import DecisionTransformer
from havln_mj.errors import InvalidArgumentError


class DTPolicy:
    """Runs a trained :class:`~.DecisionTransformer` one step at a time.

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
        obs, mask = self._check_step(obs, action_mask, last_reward, greedy, rng)
        if last_reward is not None:
            self._rtg_now -= float(last_reward)
        self._obs.append(obs)
        self._masks.append(mask)
        self._actions.append(0)  # a placeholder: step t's logits never see a_t
        self._rtg.append(self._rtg_now)
        self._times.append(min(self._t, cfg.max_timestep - 1))

        logits = self._last_logits()
        if greedy:
            action = int(logits.argmax())
        else:
            p = torch.softmax(logits.double(), dim=0).cpu().numpy()
            p[~mask] = 0.0  # exact zeros, and renormalise the float rounding away
            action = int(rng.choice(cfg.n_actions, p=p / p.sum()))
        self._actions[-1] = action
        self._t += 1
        return action

    def _check_step(
        self,
        obs: np.ndarray,
        action_mask: np.ndarray,
        last_reward: float | None,
        greedy: bool,
        rng: np.random.Generator | None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """The observation and mask as arrays; raises on what :meth:`act` rejects."""
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
        if last_reward is not None and not np.isfinite(last_reward):
            raise InvalidArgumentError(f"last_reward must be finite, got {last_reward!r}")
        return obs, mask

    def _last_logits(self) -> torch.Tensor:
        """The model's logits at the newest step of the window (eval mode, no gradients)."""
        dev = self._device()
        k = len(self._obs)
        was_training = self.model.training
        self.model.eval()
        try:
            with torch.no_grad():
                return self.model(
                    self._instruction,
                    torch.as_tensor(np.stack(self._obs), device=dev)[None],
                    torch.tensor([list(self._actions)], dtype=torch.long, device=dev),
                    torch.tensor([list(self._rtg)], dtype=torch.float32, device=dev)
                    / self.cfg.rtg_scale,
                    torch.tensor([list(self._times)], dtype=torch.long, device=dev),
                    torch.ones(1, k, dtype=torch.bool, device=dev),
                    torch.as_tensor(np.stack(self._masks), device=dev)[None],
                    encoded=self._encoded,
                )[0, -1]
        finally:
            self.model.train(was_training)
