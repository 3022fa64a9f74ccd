"""One training run: the model, its optimiser, the data, the loop, checkpoints and resuming."""

from __future__ import annotations

import json
import math
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn
from tqdm import tqdm

from havln_mj.agents.checkpoint import AgentBundle, build_model
from havln_mj.agents.demos import Demo
from havln_mj.agents.observations import PROPRIO_DIM
from havln_mj.agents.rollouts import EgoRollouts, collect_demos, make_simulator
from havln_mj.agents.train.config import TrainConfig
from havln_mj.agents.train.evaluation import evaluate
from havln_mj.agents.train.losses import student_loss, teacher_loss
from havln_mj.agents.train.prepare import prepare_data
from havln_mj.agents.train.records import RunRecords
from havln_mj.errors import InvalidArgumentError, MissingDataError

DEVICES = ("cpu", "cuda", "cuda:N")


def resolve_device(name: str) -> torch.device:
    """``"cpu"``, ``"cuda"`` (every visible GPU) or ``"cuda:N"`` (one) as a torch device.

    Raises:
        InvalidArgumentError: Another name, or a CUDA device torch cannot see.
    """
    try:
        device = torch.device(name)
    except (RuntimeError, TypeError):
        device = None
    if device is None or device.type not in ("cpu", "cuda"):
        raise InvalidArgumentError(f"device {name!r} unknown; valid: {', '.join(DEVICES)}")
    if device.type == "cuda":
        if not torch.cuda.is_available():
            build = torch.version.cuda or "none: a CPU build"
            raise InvalidArgumentError(
                f"device {name!r}: torch {torch.__version__} sees no CUDA device (its CUDA: "
                f"{build}); use --device cpu, or install a CUDA build of torch"
            )
        count = torch.cuda.device_count()
        if device.index is not None and device.index >= count:
            raise InvalidArgumentError(
                f"device {name!r}: torch sees {count} GPU(s); valid: cuda:0 … cuda:{count - 1}"
            )
    return device


def data_parallel(model: nn.Module, device: torch.device) -> nn.Module:
    """What computes a batch's forward pass.

    ``model`` itself, or on ``"cuda"`` with several GPUs a :class:`torch.nn.DataParallel`
    splitting the batch over all of them (it shares ``model``'s parameters).
    """
    if device.type == "cuda" and device.index is None and torch.cuda.device_count() > 1:
        return nn.DataParallel(model)
    return model


def checkpoint_to_resume(out: Path) -> Path:
    """The checkpoint a run in ``out`` resumes from.

    Raises:
        MissingDataError: There is none.
    """
    path = Path(out) / "checkpoint.pt"
    if not path.is_file():
        raise MissingDataError(
            f"--resume: no checkpoint to resume from at {path}; run without --resume to "
            "start this run, or give the --out of the run to continue"
        )
    return path


class Trainer:
    """One training run (see :mod:`havln_mj.agents.train`).

    The model is initialised from ``cfg.seed`` alone (the torch generator is seeded right
    before it is built), so a run gives the same weights whether its view encoder was
    pretrained now or read from the cache.

    Args:
        cfg: The configuration.
        out: Output folder.
        progress: Show progress bars.
        device: ``"cpu"``, ``"cuda"`` (data-parallel over every visible GPU) or ``"cuda:N"``.
        tensorboard: Write TensorBoard events beside ``history.json``.
    """

    def __init__(
        self,
        cfg: TrainConfig,
        out: Path,
        progress: bool = True,
        *,
        device: str = "cpu",
        tensorboard: bool = True,
    ) -> None:
        self.cfg, self.out, self.progress = cfg, Path(out), progress
        self.device = resolve_device(device)
        self.out.mkdir(parents=True, exist_ok=True)
        self.records = RunRecords(self.out, progress, tensorboard)
        self.rng = np.random.default_rng([cfg.seed, 11])
        self.gen = torch.Generator().manual_seed(cfg.seed)
        self.data = prepare_data(cfg, progress)
        dims = {"vocab_size": len(self.data.vocab), "obs_dim": self.data.store.dim + PROPRIO_DIM}
        self.model_config = {**cfg.model, **dims}
        text = self.model_config.get("text") or {}
        if "bert" in text:  # BERT reads words: the model keeps the vocabulary
            self.model_config["text"] = {**text, "vocab": list(self.data.vocab.tokens)}
        torch.manual_seed(cfg.seed)
        self.model = build_model(cfg.agent, self.model_config).to(self.device)
        self.forward = data_parallel(self.model, self.device)
        self.optimizer = torch.optim.AdamW(
            self.model.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay
        )
        self.sim = make_simulator(
            cfg.rollout_batch,
            cfg.people_seed,
            connectivity_dir=cfg.connectivity_dir,
            human_placements=cfg.human_placements,
        )
        self.rollouts = EgoRollouts(self.sim, self.data.store, self.data.vocab, cfg.max_steps)
        self.iteration = 0
        self.history: list[dict[str, Any]] = []
        self.best = -math.inf
        self._dt_data = None

    # -- persistence

    def bundle(self) -> AgentBundle:
        """The current model as a checkpoint bundle, with the training state."""
        state = {
            "config": asdict(self.cfg),
            "iteration": self.iteration,
            "optimizer": self.optimizer.state_dict(),
            "numpy_rng": self.rng.bit_generator.state,
            "torch_gen": self.gen.get_state(),
            "torch_rng": torch.get_rng_state(),
            "cuda_rng": torch.cuda.get_rng_state_all() if self.device.type == "cuda" else None,
            "history": self.history,
            "best": self.best,
        }
        return AgentBundle(
            self.cfg.agent,
            self.model,
            self.model_config,
            self.data.vocab,
            self.data.encoder,
            self.data.spec,
            state,
        )

    def resume(self) -> None:
        """Loads ``checkpoint.pt`` from the output folder.

        Raises:
            MissingDataError: There is none.
            InvalidArgumentError: It was written by a run with another configuration (other
                than its ``iterations``).
        """
        path = checkpoint_to_resume(self.out)
        saved = AgentBundle.load(path)
        try:
            theirs = TrainConfig.from_dict(saved.state.get("config", {})).resolved()
        except InvalidArgumentError:
            theirs = None
        if theirs is None or {**theirs, "iterations": None} != {
            **self.cfg.resolved(),
            "iterations": None,
        }:
            raise InvalidArgumentError(
                f"{path} was written by a run with another config; use another --out"
            )
        self.model.load_state_dict(saved.model.state_dict())
        self.optimizer.load_state_dict(saved.state["optimizer"])
        self.rng.bit_generator.state = saved.state["numpy_rng"]
        self.gen.set_state(saved.state["torch_gen"])
        torch.set_rng_state(saved.state["torch_rng"])
        if saved.state.get("cuda_rng") is not None and self.device.type == "cuda":
            torch.cuda.set_rng_state_all(saved.state["cuda_rng"])
        self.iteration = saved.state["iteration"]
        self.history = saved.state["history"]
        self.best = saved.state["best"]

    # -- data

    def _demos(self) -> tuple[list[Demo], list[Demo]]:
        cfg = self.cfg
        expert: list[Demo] = []
        if cfg.agent == "vln_cm" and cfg.random_fraction < 1.0:
            expert = collect_demos(self.rollouts, self.data.train, "expert", progress=self.progress)
        randoms: list[Demo] = []
        walks = (
            cfg.random_walks
            if cfg.agent == "vln_dt"
            else round(cfg.random_fraction * len(self.data.train))
        )
        if walks:
            walk_rng = np.random.default_rng([cfg.seed, 13])
            picks = walk_rng.integers(len(self.data.train), size=walks)
            chosen = [self.data.train[int(i)] for i in picks]
            randoms = collect_demos(
                self.rollouts, chosen, "random", walk_rng, progress=self.progress
            )
        return expert, randoms

    # -- steps

    def _cm_step(self, expert: list[Demo], randoms: list[Demo]) -> dict[str, float]:
        cfg = self.cfg
        n_random = int(self.rng.binomial(cfg.batch_size, cfg.random_fraction))
        n_expert = cfg.batch_size - n_random
        losses, steps = [], []
        if n_random:
            picks = self.rng.integers(len(randoms), size=n_random)
            loss, k = teacher_loss(self.model, [randoms[int(i)] for i in picks], self.forward)
            losses.append(loss * k)
            steps.append(k)
        if n_expert:
            sample = cfg.feedback == "sample" or (cfg.feedback == "mixed" and self.iteration % 2)
            picks = self.rng.integers(len(expert), size=n_expert)
            if sample:
                chunk = [self.data.train[int(i)] for i in picks][: self.rollouts.batch_size]
                loss, k = student_loss(self.model, self.rollouts, chunk, self.gen)
            else:
                loss, k = teacher_loss(self.model, [expert[int(i)] for i in picks], self.forward)
            losses.append(loss * k)
            steps.append(k)
        loss = torch.stack(losses).sum() / max(sum(steps), 1)
        self._optimise(loss)
        return {"loss": loss.item(), "steps": sum(steps)}

    def _dt_step(self) -> dict[str, float]:
        from havln_mj.agents.vln_dt import dt_loss, sample_windows

        cfg = self.model.cfg
        batch = sample_windows(self._dt_data, cfg, self.cfg.batch_size, self.rng, cfg.reward)
        batch = {k: v.to(self.device) for k, v in batch.items()}
        loss = dt_loss(self.forward, batch)
        self._optimise(loss)
        return {"loss": loss.item(), "steps": int(batch["loss_mask"].sum())}

    def _optimise(self, loss: torch.Tensor) -> None:
        self.optimizer.zero_grad()
        loss.backward()
        torch.nn.utils.clip_grad_norm_(self.model.parameters(), self.cfg.grad_clip)
        self.optimizer.step()

    # -- loop

    def _prepare_demos(self) -> tuple[list[Demo], list[Demo]]:
        t0 = time.perf_counter()
        expert, randoms = self._demos()
        if self.cfg.agent == "vln_dt":
            from havln_mj.agents.vln_dt import DTDataset

            self._dt_data = DTDataset(randoms)
            ok = sum(d.success for d in randoms)
            self.records.log(
                f"{len(randoms)} random walks, {ok} successful ({ok / len(randoms):.1%})"
            )
        else:
            self.records.log(f"{len(expert)} expert demos, {len(randoms)} random-walk demos")
        self.records.log(f"data ready in {time.perf_counter() - t0:.1f} s")
        return expert, randoms

    def run(self, resume: bool = False) -> dict[str, Any]:
        """Trains to ``iterations``; returns the last history entry.

        Raises:
            MissingDataError: ``resume`` without a checkpoint in the output folder.
        """
        cfg = self.cfg
        if resume:
            self.resume()
            self.records.log(f"resumed at iteration {self.iteration}")
        self.records.write_config(cfg.resolved())
        self.records.log(f"training on {self.device}")
        expert, randoms = self._prepare_demos()
        self.records.start(self.iteration)
        bar = tqdm(
            total=cfg.iterations,
            initial=self.iteration,
            desc=cfg.agent,
            unit="it",
            disable=not self.progress,
        )
        window: list[dict[str, float]] = []
        t_train = time.perf_counter()
        try:
            while self.iteration < cfg.iterations:
                self.model.train()
                is_cm = cfg.agent == "vln_cm"
                window.append(self._cm_step(expert, randoms) if is_cm else self._dt_step())
                self.iteration += 1
                bar.update()
                if self.iteration % cfg.log_every == 0 or self.iteration == cfg.iterations:
                    self._log_entry(window, time.perf_counter() - t_train)
                    window = []
        finally:
            bar.close()
            self.records.close()
        self.records.plot(self.history, f"{cfg.agent} ({self.out.name})")
        return self.history[-1] if self.history else {}

    def _log_entry(self, window: list[dict[str, float]], seconds: float) -> None:
        """Logs the window's mean loss; validates and saves on evaluation iterations."""
        cfg = self.cfg
        entry = {
            "iteration": self.iteration,
            "loss": float(np.mean([w["loss"] for w in window])),
            "seconds": round(seconds, 1),
        }
        evaluating = self.iteration % cfg.eval_every == 0 or self.iteration == cfg.iterations
        if evaluating:
            entry.update(self._validate())
        self.history.append(entry)
        self.records.log(json.dumps(entry))
        self.records.scalars(entry)
        if evaluating:
            self._save(entry)

    def _validate(self) -> dict[str, float]:
        if not self.data.val:
            return {}
        self.model.eval()
        reward = self.model_config.get("reward", "paper")
        scores = evaluate(self.bundle(), self.rollouts, self.data.val, reward)
        return {f"val_{k}": round(v, 4) for k, v in scores.items()}

    def _save(self, entry: dict[str, Any]) -> None:
        score = entry.get("val_sr", entry["iteration"])
        improved = score > self.best
        if improved:
            self.best = score
        bundle = self.bundle()
        bundle.save(self.out / "checkpoint.pt")
        if improved:
            bundle.save(self.out / "best.pt")
        self.records.history(self.history)
