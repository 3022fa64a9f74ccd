"""The training loop: rollouts, PPO updates, the log, checkpoints (atomic), resume, export.

A run folder holds ``config.json``, ``log.jsonl`` (one line per iteration), ``checkpoint.pt``
(the latest, every ``checkpoint_every`` iterations and at the end), ``policy.npz`` (the
actor exported for :mod:`havln_mj.robot.go1.learned`, written with each checkpoint),
``policies/`` (each checkpoint's policy by iteration) and ``curriculum.png``. Everything
random draws from one ``numpy.random.Generator`` and one ``torch.Generator``, both seeded
from the config and saved in the checkpoint.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import numpy as np
import torch

from havln_mj.errors import InvalidArgumentError, MalformedDataError
from havln_mj.robot.go1.learned import LearnedPolicy, PolicySpec
from havln_mj.train_go1.config import TrainConfig, config_from_json
from havln_mj.train_go1.env import Go1Envs
from havln_mj.train_go1.plot import plot_curriculum
from havln_mj.train_go1.ppo import PPO, ActorCritic, Storage

CHECKPOINT, POLICY, LOG, CONFIG, PLOT = (
    "checkpoint.pt",
    "policy.npz",
    "log.jsonl",
    "config.json",
    "curriculum.png",
)


class Trainer:
    """One training run in a folder.

    Args:
        cfg: The configuration (ignored on resume: the run's own ``config.json`` holds).
        out: The run folder.
        resume: Continue from ``out/checkpoint.pt``.
        device: ``"cpu"`` or ``"cuda"`` (networks and the update; the physics is on the CPU).
    """

    def __init__(
        self, cfg: TrainConfig, out: str | Path, resume: bool = False, device: str = "cpu"
    ) -> None:
        self.out = Path(out)
        self.device = device
        ckpt = None
        if resume:
            path = self.out / CHECKPOINT
            if not path.is_file():
                raise InvalidArgumentError(f"--resume: no checkpoint at {path}")
            ckpt = torch.load(path, map_location="cpu", weights_only=False)  # RNG states: CPU
            cfg = config_from_json(ckpt["config"], str(path))
        elif (self.out / CHECKPOINT).exists():
            raise InvalidArgumentError(
                f"{self.out} already holds a run; pass --resume to continue it, or another --out"
            )
        self.cfg = cfg
        self.out.mkdir(parents=True, exist_ok=True)
        _write_atomic(self.out / CONFIG, json.dumps(cfg.to_json(), indent=1).encode())
        self.rng = np.random.default_rng(cfg.seed)
        self.gen = torch.Generator().manual_seed(cfg.seed)
        torch.manual_seed(cfg.seed)
        self.spec = PolicySpec()
        self.iteration, self.env_steps = 0, 0
        if ckpt is not None:
            self.rng.bit_generator.state = ckpt["numpy_rng"]
            self.gen.set_state(ckpt["torch_rng"])
        self.envs = Go1Envs(cfg, self.rng, self.spec, ckpt["levels"] if ckpt else None)
        self.ac = ActorCritic(
            self.spec.obs_size, self.spec.action_size, cfg.ppo, self.spec.clip_obs
        ).to(device)
        self.ppo = PPO(self.ac, cfg.ppo, self.gen)
        if ckpt is not None:
            self.ac.load_state_dict(ckpt["model"])
            self.ppo.opt.load_state_dict(ckpt["optimizer"])
            self.ppo.lr = ckpt["learning_rate"]
            self.iteration, self.env_steps = ckpt["iteration"], ckpt["env_steps"]

    def train(self, iterations: int | None = None) -> None:
        """Runs until ``iterations`` in all (default: the config's), checkpointing as it goes."""
        total = self.cfg.iterations if iterations is None else iterations
        c, n = self.cfg.ppo, self.envs.num_envs
        st = Storage(c.steps_per_env, n, self.spec.obs_size, self.spec.action_size, self.device)
        obs = torch.as_tensor(self.envs.observations(), dtype=torch.float32, device=self.device)
        while self.iteration < total:
            t0 = time.perf_counter()
            ret = self._rollout(st, obs)
            obs, rewards = ret
            t1 = time.perf_counter()
            losses = self.ppo.update(st)
            # New statistics after the update, so that a rollout and its update see the same.
            self.ac.norm.update(st.obs.reshape(-1, st.obs.shape[-1]))
            t2 = time.perf_counter()
            self.iteration += 1
            self.env_steps += c.steps_per_env * n
            self._log(rewards, losses, t1 - t0, t2 - t1)
            if self.iteration % self.cfg.checkpoint_every == 0 or self.iteration == total:
                self.save()

    def _rollout(self, st: Storage, obs: torch.Tensor) -> tuple[torch.Tensor, float]:
        c = self.cfg.ppo
        total = 0.0
        for t in range(c.steps_per_env):
            with torch.no_grad():
                dist = self.ac.dist(obs)
                action = dist.mean + dist.stddev * torch.randn(
                    dist.mean.shape, generator=self.gen
                ).to(self.device)
                value = self.ac.value(obs)
            st.obs[t], st.actions[t], st.values[t] = obs, action, value
            st.log_probs[t] = dist.log_prob(action).sum(-1)
            st.mu[t], st.sigma[t] = dist.mean, dist.stddev
            nxt, rew, done, timeout = self.envs.step(action.cpu().numpy().astype(np.float64))
            rew_t = torch.as_tensor(rew, dtype=torch.float32, device=self.device)
            total += float(rew.mean())
            # A time-out is not an end of the task: bootstrap it with the value it had.
            rew_t += c.gamma * value * torch.as_tensor(timeout, device=self.device)
            st.rewards[t] = rew_t
            st.dones[t] = torch.as_tensor(done, dtype=torch.float32, device=self.device)
            obs = torch.as_tensor(nxt, dtype=torch.float32, device=self.device)
        with torch.no_grad():
            st.gae(self.ac.value(obs), c.gamma, c.lam)
        return obs, total / c.steps_per_env

    def _log(self, reward: float, losses: dict, t_collect: float, t_learn: float) -> None:
        eps, terms = self.envs.drain()
        walks = [e for e in eps if not e["turning"]]
        n = self.cfg.ppo.steps_per_env * self.envs.num_envs
        row = {
            "iteration": self.iteration,
            "env_steps": self.env_steps,
            "mean_reward": round(reward, 5),
            "mean_level": round(self.envs.curriculum.mean, 3),
            "episodes": len(walks),
            "success": round(float(np.mean([e["success"] for e in walks])), 3) if walks else None,
            "falls": round(float(np.mean([e["fell"] for e in walks])), 3) if walks else None,
            "success_by_level": _by_level(walks),
            "steps_per_s": round(n / max(t_collect, 1e-9), 1),
            "collect_s": round(t_collect, 2),
            "learn_s": round(t_learn, 2),
            "action_std": round(self.ac.log_std.exp().mean().item(), 4),
            "reward_terms": {k: round(v, 6) for k, v in terms.items()},
        } | {k: round(v, 6) for k, v in losses.items()}
        with open(self.out / LOG, "a") as f:
            f.write(json.dumps(row) + "\n")

    def save(self) -> None:
        """Writes the checkpoint, the exported policy and the curriculum plot (atomically)."""
        state = {
            "config": self.cfg.to_json(),
            "model": self.ac.state_dict(),
            "optimizer": self.ppo.opt.state_dict(),
            "learning_rate": self.ppo.lr,
            "iteration": self.iteration,
            "env_steps": self.env_steps,
            "levels": self.envs.curriculum.level.copy(),
            "numpy_rng": self.rng.bit_generator.state,
            "torch_rng": self.gen.get_state(),
        }
        tmp = self.out / (CHECKPOINT + ".tmp")
        torch.save(state, tmp)
        os.replace(tmp, self.out / CHECKPOINT)
        export(self.ac, self.spec, self.cfg, self.out / POLICY)
        export(self.ac, self.spec, self.cfg, self.out / "policies" / f"{self.iteration:06d}.npz")
        plot_curriculum(self.out / LOG, self.out / PLOT)


def export(ac: ActorCritic, spec: PolicySpec, cfg: TrainConfig, path: str | Path) -> LearnedPolicy:
    """Writes the actor (mean) and the normalisation as a numpy policy file."""
    linears = [m for m in ac.actor if isinstance(m, torch.nn.Linear)]
    policy = LearnedPolicy(
        spec=spec,
        weights=tuple(m.weight.detach().cpu().double().numpy() for m in linears),
        biases=tuple(m.bias.detach().cpu().double().numpy() for m in linears),
        obs_mean=ac.norm.mean.detach().cpu().numpy(),
        obs_std=ac.norm.std.detach().cpu().numpy(),
        train_config=cfg.to_json(),
    )
    policy.save(path)
    return policy


def export_checkpoint(checkpoint: str | Path, path: str | Path) -> LearnedPolicy:
    """Exports a checkpoint file's actor as a numpy policy file."""
    try:
        ckpt = torch.load(checkpoint, map_location="cpu", weights_only=False)
        cfg = config_from_json(ckpt["config"], str(checkpoint))
        spec = PolicySpec()
        ac = ActorCritic(spec.obs_size, spec.action_size, cfg.ppo, spec.clip_obs)
        ac.load_state_dict(ckpt["model"])
    except (KeyError, RuntimeError, OSError) as err:
        raise MalformedDataError(f"{checkpoint} is not a GO1 training checkpoint: {err}") from err
    return export(ac, spec, cfg, path)


def _by_level(walks: list[dict]) -> dict[str, list]:
    """Per terrain level: [walks, successes]."""
    out: dict[str, list] = {}
    for e in walks:
        cell = out.setdefault(f"{e['kind']}{e['level']}", [0, 0])
        cell[0] += 1
        cell[1] += int(e["success"])
    return dict(sorted(out.items()))


def _write_atomic(path: Path, data: bytes) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_bytes(data)
    os.replace(tmp, path)
