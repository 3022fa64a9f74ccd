"""Proximal policy optimisation in torch: actor-critic MLPs, rollout storage, the update.

The actor's mean is the policy (a Gaussian with a learned, state-independent std explores);
the critic sees the same observation. Observations are normalised by running statistics kept
beside the networks and exported with them. The learning rate adapts to keep the KL divergence
between old and new policy near ``desired_kl``.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import nn

from havln_mj.train_go1.config import PPOConfig


def mlp(n_in: int, hidden: tuple[int, ...], n_out: int) -> nn.Sequential:
    """ELU MLP; the last layer is linear."""
    layers: list[nn.Module] = []
    for h in hidden:
        layers += [nn.Linear(n_in, h), nn.ELU()]
        n_in = h
    layers.append(nn.Linear(n_in, n_out))
    return nn.Sequential(*layers)


class Normalizer(nn.Module):
    """Running mean and variance of observations (Chan's parallel update)."""

    def __init__(self, size: int) -> None:
        super().__init__()
        self.register_buffer("mean", torch.zeros(size, dtype=torch.float64))
        self.register_buffer("var", torch.ones(size, dtype=torch.float64))
        self.register_buffer("count", torch.tensor(1e-4, dtype=torch.float64))

    def update(self, x: torch.Tensor) -> None:
        """Adds a batch ``(n, size)`` to the statistics."""
        x = x.to(torch.float64)
        n = x.shape[0]
        mean, var = x.mean(0), x.var(0, unbiased=False)
        total = self.count + n
        delta = mean - self.mean
        self.mean += delta * n / total
        self.var = (self.var * self.count + var * n + delta**2 * self.count * n / total) / total
        self.count = total

    @property
    def std(self) -> torch.Tensor:
        """Standard deviation, floored so constant inputs stay finite."""
        return torch.sqrt(self.var).clamp_min(1e-2)

    def forward(self, x: torch.Tensor, clip: float) -> torch.Tensor:
        """Normalised ``x``, clipped to ``±clip``."""
        return ((x - self.mean.float()) / self.std.float()).clamp(-clip, clip)


class ActorCritic(nn.Module):
    """Gaussian actor and value critic on normalised observations."""

    def __init__(self, n_obs: int, n_act: int, cfg: PPOConfig, clip_obs: float) -> None:
        super().__init__()
        self.actor = mlp(n_obs, cfg.hidden, n_act)
        self.critic = mlp(n_obs, cfg.hidden, 1)
        self.log_std = nn.Parameter(torch.full((n_act,), float(np.log(cfg.init_std))))
        self.norm = Normalizer(n_obs)
        self.clip_obs = clip_obs
        with torch.no_grad():  # a residual starts near zero: the terrain gait as it is
            self.actor[-1].weight.mul_(0.01)
            self.actor[-1].bias.zero_()

    def dist(self, obs: torch.Tensor) -> torch.distributions.Normal:
        """The action distribution for raw observations."""
        mean = self.actor(self.norm(obs, self.clip_obs))
        return torch.distributions.Normal(mean, self.log_std.exp().expand_as(mean))

    def value(self, obs: torch.Tensor) -> torch.Tensor:
        """State values for raw observations."""
        return self.critic(self.norm(obs, self.clip_obs)).squeeze(-1)


class Storage:
    """One iteration's transitions, ``(steps, envs, ...)``."""

    def __init__(self, steps: int, envs: int, n_obs: int, n_act: int, device: str) -> None:
        z = lambda *s: torch.zeros(*s, device=device)  # noqa: E731
        self.obs, self.actions = z(steps, envs, n_obs), z(steps, envs, n_act)
        self.log_probs, self.values, self.rewards = z(steps, envs), z(steps, envs), z(steps, envs)
        self.dones = z(steps, envs)
        self.returns, self.advantages = z(steps, envs), z(steps, envs)
        self.mu, self.sigma = z(steps, envs, n_act), z(steps, envs, n_act)

    def gae(self, last_value: torch.Tensor, gamma: float, lam: float) -> None:
        """Returns and normalised advantages (generalised advantage estimation)."""
        adv = torch.zeros_like(last_value)
        steps = self.rewards.shape[0]
        for t in reversed(range(steps)):
            nxt = last_value if t == steps - 1 else self.values[t + 1]
            live = 1.0 - self.dones[t]
            delta = self.rewards[t] + gamma * nxt * live - self.values[t]
            adv = delta + gamma * lam * live * adv
            self.returns[t] = adv + self.values[t]
        a = self.returns - self.values
        self.advantages = (a - a.mean()) / (a.std() + 1e-8)


class PPO:
    """The optimiser of an :class:`ActorCritic`."""

    def __init__(self, ac: ActorCritic, cfg: PPOConfig, generator: torch.Generator) -> None:
        self.ac, self.cfg, self.gen = ac, cfg, generator
        self.lr = cfg.learning_rate
        self.opt = torch.optim.Adam(ac.parameters(), lr=self.lr)

    def update(self, st: Storage) -> dict[str, float]:
        """Runs the epochs of minibatch updates; returns mean losses and the KL."""
        c = self.cfg
        n = st.rewards.numel()
        flat = {
            k: getattr(st, k).reshape(n, *getattr(st, k).shape[2:])
            for k in (
                "obs",
                "actions",
                "log_probs",
                "values",
                "returns",
                "advantages",
                "mu",
                "sigma",
            )
        }
        size = max(n // c.minibatches, 1)
        stats = {"policy_loss": 0.0, "value_loss": 0.0, "entropy": 0.0, "kl": 0.0}
        count = 0
        for _ in range(c.epochs):
            order = torch.randperm(n, generator=self.gen).to(st.obs.device)
            for k in range(0, n - size + 1, size):
                b = {key: v[order[k : k + size]] for key, v in flat.items()}
                stats_b = self._minibatch(b)
                for key in stats:
                    stats[key] += stats_b[key]
                count += 1
        return {k: v / max(count, 1) for k, v in stats.items()} | {"learning_rate": self.lr}

    def _minibatch(self, b: dict[str, torch.Tensor]) -> dict[str, float]:
        c = self.cfg
        dist = self.ac.dist(b["obs"])
        log_p = dist.log_prob(b["actions"]).sum(-1)
        with torch.no_grad():  # KL(old || new) of diagonal Gaussians, for the adaptive rate
            sigma, mu = dist.stddev, dist.mean
            kl = (
                (
                    torch.log(sigma / b["sigma"])
                    + (b["sigma"] ** 2 + (b["mu"] - mu) ** 2) / (2.0 * sigma**2)
                    - 0.5
                )
                .sum(-1)
                .mean()
            )
            if kl > 2.0 * c.desired_kl:
                self.lr = max(1e-5, self.lr / 1.5)
            elif 0.0 < kl < 0.5 * c.desired_kl:
                self.lr = min(1e-2, self.lr * 1.5)
            for group in self.opt.param_groups:
                group["lr"] = self.lr
        ratio = torch.exp(log_p - b["log_probs"])
        adv = b["advantages"]
        surrogate = torch.max(-adv * ratio, -adv * ratio.clamp(1 - c.clip, 1 + c.clip)).mean()
        value = self.ac.value(b["obs"])
        v_clip = b["values"] + (value - b["values"]).clamp(-c.clip, c.clip)
        value_loss = torch.max((value - b["returns"]) ** 2, (v_clip - b["returns"]) ** 2).mean()
        entropy = dist.entropy().sum(-1).mean()
        loss = surrogate + c.value_coef * value_loss - c.entropy_coef * entropy
        self.opt.zero_grad()
        loss.backward()
        nn.utils.clip_grad_norm_(self.ac.parameters(), c.max_grad_norm)
        self.opt.step()
        return {
            "policy_loss": surrogate.item(),
            "value_loss": value_loss.item(),
            "entropy": entropy.item(),
            "kl": float(kl),
        }
