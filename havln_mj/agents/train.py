"""``python -m havln_mj.agents.train --agent {vln_cm,vln_dt} --config FILE``: train an agent.

The run reads a JSON config (``agents/configs/*.json``; ``--set key=value`` overrides a key,
the value read as JSON), builds the feature set it needs (pretraining the view encoder the
first time; both are cached), records demos, and trains:

* **VLN-CM** on the human-aware egocentric expert: teacher forcing on the expert's demos
  (``feedback: "teacher"``), student forcing, where the agent's own sampled actions drive the
  simulator and the expert labels every state it reaches (``"sample"``, HA3D's choice), or
  both in alternate iterations (``"mixed"``). ``random_fraction`` of the training items are
  random-walk demos instead (the paper's 0 / 3 / 25 / 50 / 100 % experiment), imitated as
  recorded.
* **VLN-DT** on ``random_walks`` random walks of at most 30 steps (the paper: 10⁴), windows of
  ``context`` steps with returns-to-go under the model's ``reward``.

Writes to ``--out``: ``checkpoint.pt`` (latest, for ``--resume``), ``best.pt`` (best val SR
when a val split is given, else the last), ``train.log`` (plain text), ``history.json`` and
``loss.png``. The same seed gives the same run; an interrupted run resumes where its last
checkpoint left off.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
import math
import sys
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
from tqdm import tqdm

from havln_mj.agents.checkpoint import AGENTS, AgentBundle, build_model
from havln_mj.agents.data import instructions_of, scans_of, split_episodes
from havln_mj.agents.demos import Demo
from havln_mj.agents.features import FeatureStore
from havln_mj.agents.featurize import FeatureSpec, build_features, load_encoder, save_encoder
from havln_mj.agents.observations import PROPRIO_DIM
from havln_mj.agents.policy import make_policy
from havln_mj.agents.rollouts import EgoRollouts, collect_demos, make_simulator
from havln_mj.agents.vision import ViewEncoder
from havln_mj.agents.vln_cm import START, VLNCM, sequence_loss
from havln_mj.cache import atomic_write_bytes, atomic_write_json
from havln_mj.errors import HavlnError, InvalidArgumentError, MissingDataError
from havln_mj.paths import cache_dir, project_home
from havln_mj.tasks.episodes import Instruction
from havln_mj.tasks.rewards import SUCCESS_DISTANCE, StepOutcome, get_reward, step_reward
from havln_mj.tasks.vocab import Vocabulary

FEEDBACKS = ("teacher", "sample", "mixed")


@dataclass
class TrainConfig:
    """A training run (the JSON config's keys).

    Attributes:
        agent: ``"vln_cm"`` or ``"vln_dt"``.
        train: The training split (see :mod:`havln_mj.agents.data`).
        val: A split evaluated every ``eval_every`` iterations (None: none).
        people_seed: Seed of the people (and of procedural episodes).
        seed: Seed of initialisation, sampling and data order.
        features: :class:`~havln_mj.agents.featurize.FeatureSpec` settings.
        model: Model settings (``CMConfig`` / ``DTConfig`` fields but the sizes set by data).
        iterations: Optimisation steps.
        batch_size: Items per step.
        lr: Learning rate.
        weight_decay: Weight decay (AdamW).
        grad_clip: Gradient norm clip.
        feedback: VLN-CM: ``"teacher"``, ``"sample"`` or ``"mixed"``.
        random_fraction: VLN-CM: share of random-walk demos among the training items.
        random_walks: VLN-DT: random walks recorded (VLN-CM draws its random share from as
            many).
        max_steps: Step cap of rollouts.
        rollout_batch: Episodes stepped at once while recording demos and evaluating.
        eval_every: Iterations between val evaluations (and checkpoints).
        eval_instructions: Val instructions evaluated each time (the first ones).
        log_every: Iterations between log lines.
        connectivity_dir: Navigation graphs of real scans.
        human_placements: HA3D placement file for real scans.
        data_dir: Where R2R / HA-R2R split names are looked up.
    """

    agent: str
    train: dict
    val: dict | None = None
    people_seed: int = 0
    seed: int = 0
    features: dict = field(default_factory=dict)
    model: dict = field(default_factory=dict)
    iterations: int = 2000
    batch_size: int = 32
    lr: float = 1e-3
    weight_decay: float = 5e-4
    grad_clip: float = 5.0
    feedback: str = "sample"
    random_fraction: float = 0.0
    random_walks: int = 10_000
    max_steps: int = 30
    rollout_batch: int = 32
    eval_every: int = 250
    eval_instructions: int = 300
    log_every: int = 25
    connectivity_dir: str | None = None
    human_placements: str | None = None
    data_dir: str | None = None

    def __post_init__(self) -> None:
        if self.agent not in AGENTS:
            raise InvalidArgumentError(f"agent {self.agent!r} unknown; valid: {', '.join(AGENTS)}")
        if self.feedback not in FEEDBACKS:
            raise InvalidArgumentError(
                f"feedback {self.feedback!r} unknown; valid: {', '.join(FEEDBACKS)}"
            )
        if not 0.0 <= self.random_fraction <= 1.0:
            raise InvalidArgumentError(
                f"random_fraction must be in [0, 1], got {self.random_fraction!r}"
            )
        for name in ("iterations", "batch_size", "max_steps", "rollout_batch", "eval_every"):
            value = getattr(self, name)
            if not isinstance(value, int) or value < 1:
                raise InvalidArgumentError(f"{name} must be a positive integer, got {value!r}")

    @classmethod
    def from_dict(cls, d: dict) -> TrainConfig:
        """From a config dict, naming unknown keys."""
        unknown = set(d) - {f.name for f in dataclasses.fields(cls)}
        if unknown:
            raise InvalidArgumentError(
                f"unknown config keys {sorted(unknown)}; valid: "
                f"{sorted(f.name for f in dataclasses.fields(cls))}"
            )
        return cls(**d)


def read_config(path: Path, agent: str | None, overrides: Sequence[str]) -> TrainConfig:
    """A config file (or a built-in config's name) with ``key=value`` overrides.

    Override values are parsed as JSON when they parse, else taken as strings.

    Raises:
        MissingDataError: No such file.
        InvalidArgumentError: Bad JSON, an override without ``=``, or an agent mismatch.
    """
    path = Path(path).expanduser()
    if not path.is_file() and len(path.parts) == 1:  # a built-in config by name
        builtin = project_home() / "agents" / "configs" / path.with_suffix(".json").name
        path = builtin if builtin.is_file() else path
    if not path.is_file():
        raise MissingDataError(
            f"config file {path} does not exist; give a file or a name from agents/configs/ "
            "(vln_cm, vln_dt, vln_cm_smoke, vln_dt_smoke, ...)"
        )
    try:
        d = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise InvalidArgumentError(f"config {path} is not valid JSON: {exc}") from None
    for item in overrides:
        key, sep, value = item.partition("=")
        if not sep:
            raise InvalidArgumentError(f"override {item!r} is not key=value")
        try:
            parsed = json.loads(value)
        except json.JSONDecodeError:
            parsed = value
        target = d
        *parents, last = key.split(".")
        for p in parents:
            target = target.setdefault(p, {})
        target[last] = parsed
    if agent is not None:
        if d.get("agent", agent) != agent:
            raise InvalidArgumentError(
                f"--agent {agent} but the config {path} is for {d['agent']!r}"
            )
        d["agent"] = agent
    return TrainConfig.from_dict(d)


# ---------------------------------------------------------------------- data


def _encoder_for(
    cfg: TrainConfig, spec: FeatureSpec, scenes: list[str], progress: bool
) -> tuple[ViewEncoder, FeatureStore]:
    """The view encoder (pretrained once per spec and scenes, cached) and the feature set."""
    render = {"connectivity_dir": cfg.connectivity_dir, "human_placements": cfg.human_placements}
    if spec.resnet152 is not None:
        return build_features(scenes, spec, progress=progress, **render)
    pretrain_on = scenes[: spec.pretrain_scenes]
    key = json.dumps({"spec": asdict(spec), "scenes": pretrain_on}, sort_keys=True, default=str)
    path = cache_dir("agents", "encoders") / f"{hashlib.sha1(key.encode()).hexdigest()[:16]}.pt"
    encoder = load_encoder(path) if path.is_file() else None
    encoder, store = build_features(
        scenes, spec, encoder=encoder, pretrain_on=pretrain_on, progress=progress, **render
    )
    if not path.is_file():
        save_encoder(encoder, path)
    return encoder, store


@dataclass
class RunData:
    """Everything a run trains and validates on."""

    train: list[Instruction]
    val: list[Instruction]
    vocab: Vocabulary
    encoder: ViewEncoder
    spec: FeatureSpec
    store: FeatureStore


def prepare_data(cfg: TrainConfig, progress: bool = True) -> RunData:
    """Episodes, vocabulary and features of a run."""
    where = {"connectivity_dir": cfg.connectivity_dir, "data_dir": cfg.data_dir}
    train_eps = split_episodes(cfg.train, cfg.people_seed, **where)
    val_eps = split_episodes(cfg.val, cfg.people_seed, **where) if cfg.val else []
    train = instructions_of(train_eps)
    val = instructions_of(val_eps)[: cfg.eval_instructions]
    vocab = Vocabulary.from_texts(i.text for i in train)
    spec = FeatureSpec.from_dict({**cfg.features, "seed": cfg.people_seed})
    scenes = scans_of(train_eps) + [s for s in scans_of(val_eps) if s not in scans_of(train_eps)]
    encoder, store = _encoder_for(cfg, spec, scenes, progress)
    return RunData(train, val, vocab, encoder, spec, store)


# ---------------------------------------------------------------------- evaluation


def evaluate(
    bundle: AgentBundle,
    rollouts: EgoRollouts,
    instructions: Sequence[Instruction],
    reward: str = "paper",
) -> dict[str, float]:
    """Greedy rollouts of the bundle's policy: SR, NE (geodesic), collisions per episode."""
    fn = get_reward(reward)
    results = []
    bsz = rollouts.batch_size
    for first in range(0, len(instructions), bsz):
        chunk = list(instructions[first : first + bsz])
        rollouts.start(chunk)
        policies = [make_policy(bundle) for _ in chunk]
        for policy, ids in zip(policies, rollouts.encoded_instructions(), strict=True):
            policy.reset(ids)
        last: list[float | None] = [None] * len(chunk)
        hits = np.zeros(len(chunk))
        final = np.zeros(len(chunk))
        while not rollouts.done[: len(chunk)].all():
            obs, masks = rollouts.observe()
            actions = np.zeros(bsz, np.int64)
            running = ~rollouts.done[: len(chunk)]
            for i in np.flatnonzero(running):
                actions[i] = policies[i].act(obs[i], masks[i], last[i])
            r = rollouts.step(actions)
            for i in np.flatnonzero(running):
                out = StepOutcome(
                    bool(r.stopped[i]), float(r.distance[i]), float(r.delta[i]), bool(r.collided[i])
                )
                last[i] = step_reward(fn, out)
                hits[i] += r.collided[i]
                final[i] = r.distance[i]
        results += [(f < SUCCESS_DISTANCE, f, h) for f, h in zip(final, hits, strict=True)]
    a = np.array(results, float)
    return {
        "sr": float(a[:, 0].mean()),
        "ne": float(a[:, 1].mean()),
        "collisions": float(a[:, 2].mean()),
    }


# ---------------------------------------------------------------------- VLN-CM


def _pad_demos(demos: Sequence[Demo]) -> dict[str, torch.Tensor]:
    """Teacher-forcing tensors of demos, padded to the longest."""
    b, t = len(demos), max(len(d) for d in demos)
    dim = demos[0].obs.shape[1]
    obs = np.zeros((b, t, dim), np.float32)
    prev = np.full((b, t), START, np.int64)
    targets = np.zeros((b, t), np.int64)
    masks = np.ones((b, t, 6), bool)
    valid = np.zeros((b, t), bool)
    for i, d in enumerate(demos):
        n = len(d)
        obs[i, :n], targets[i, :n], masks[i, :n], valid[i, :n] = d.obs, d.actions, d.masks, True
        prev[i, 1:n] = d.actions[: n - 1]
    return {
        "instruction": torch.as_tensor(np.stack([d.instruction for d in demos])),
        "obs": torch.as_tensor(obs),
        "prev": torch.as_tensor(prev),
        "masks": torch.as_tensor(masks),
        "targets": torch.as_tensor(targets),
        "valid": torch.as_tensor(valid),
    }


def teacher_loss(model: VLNCM, demos: Sequence[Demo]) -> tuple[torch.Tensor, int]:
    """Teacher-forced cross-entropy on demos; the number of steps it covers."""
    b = _pad_demos(demos)
    logits = model(b["instruction"], b["obs"], b["prev"], b["masks"])
    return sequence_loss(logits, b["targets"], b["valid"]), int(b["valid"].sum())


def student_loss(
    model: VLNCM, rollouts: EgoRollouts, instructions: Sequence[Instruction], gen: torch.Generator
) -> tuple[torch.Tensor, int]:
    """Student forcing: sample the agent's actions, learn the expert's at every state reached."""
    n = len(instructions)
    rollouts.start(instructions)
    ctx, pad, state = model.encode(torch.as_tensor(rollouts.encoded_instructions()))
    prev = torch.full((n,), START, dtype=torch.long)
    total, steps = torch.zeros(()), 0
    while not rollouts.done[:n].all():
        obs, masks = rollouts.observe()
        targets = torch.as_tensor(rollouts.expert_actions()[:n])
        running = torch.as_tensor(~rollouts.done[:n])
        logits, state, _ = model.step(
            torch.as_tensor(obs[:n]), prev, state, ctx, pad, torch.as_tensor(masks[:n])
        )
        ce = torch.nn.functional.cross_entropy(logits, targets, reduction="none")
        total = total + (ce * running).sum()
        steps += int(running.sum())
        probs = torch.softmax(logits.detach(), dim=1)
        sampled = torch.multinomial(probs, 1, generator=gen).squeeze(1)
        actions = np.zeros(rollouts.batch_size, np.int64)
        actions[:n] = sampled.numpy()
        rollouts.step(actions)
        prev = sampled
    return total / max(steps, 1), steps


# ---------------------------------------------------------------------- the run


class Trainer:
    """One training run (see the module docstring).

    Args:
        cfg: The configuration.
        out: Output folder.
        progress: Show progress bars.
    """

    def __init__(self, cfg: TrainConfig, out: Path, progress: bool = True) -> None:
        self.cfg, self.out, self.progress = cfg, Path(out), progress
        self.out.mkdir(parents=True, exist_ok=True)
        torch.manual_seed(cfg.seed)
        self.rng = np.random.default_rng([cfg.seed, 11])
        self.gen = torch.Generator().manual_seed(cfg.seed)
        self.data = prepare_data(cfg, progress)
        dims = {"vocab_size": len(self.data.vocab), "obs_dim": self.data.store.dim + PROPRIO_DIM}
        self.model_config = {**cfg.model, **dims}
        text = self.model_config.get("text") or {}
        if "bert" in text:  # BERT reads words: the model keeps the vocabulary
            self.model_config["text"] = {**text, "vocab": list(self.data.vocab.tokens)}
        self.model = build_model(cfg.agent, self.model_config)
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

    def resume(self) -> bool:
        """Loads ``checkpoint.pt`` from the output folder if there is one."""
        path = self.out / "checkpoint.pt"
        if not path.is_file():
            return False
        saved = AgentBundle.load(path)
        ours = {**asdict(self.cfg), "iterations": None}
        if {**saved.state.get("config", {}), "iterations": None} != ours:
            raise InvalidArgumentError(
                f"{path} was written by a run with another config; use another --out"
            )
        self.model.load_state_dict(saved.model.state_dict())
        self.optimizer.load_state_dict(saved.state["optimizer"])
        self.rng.bit_generator.state = saved.state["numpy_rng"]
        self.gen.set_state(saved.state["torch_gen"])
        torch.set_rng_state(saved.state["torch_rng"])
        self.iteration = saved.state["iteration"]
        self.history = saved.state["history"]
        self.best = saved.state["best"]
        return True

    def log(self, line: str) -> None:
        """Appends a line to ``train.log`` (and the progress bar)."""
        with open(self.out / "train.log", "a", encoding="utf-8") as f:
            f.write(line + "\n")
        if self.progress:
            tqdm.write(line)

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
            loss, k = teacher_loss(self.model, [randoms[int(i)] for i in picks])
            losses.append(loss * k)
            steps.append(k)
        if n_expert:
            sample = cfg.feedback == "sample" or (cfg.feedback == "mixed" and self.iteration % 2)
            picks = self.rng.integers(len(expert), size=n_expert)
            if sample:
                chunk = [self.data.train[int(i)] for i in picks][: self.rollouts.batch_size]
                loss, k = student_loss(self.model, self.rollouts, chunk, self.gen)
            else:
                loss, k = teacher_loss(self.model, [expert[int(i)] for i in picks])
            losses.append(loss * k)
            steps.append(k)
        loss = torch.stack(losses).sum() / max(sum(steps), 1)
        self._optimise(loss)
        return {"loss": loss.item(), "steps": sum(steps)}

    def _dt_step(self) -> dict[str, float]:
        from havln_mj.agents.vln_dt import dt_loss, sample_windows

        batch = sample_windows(
            self._dt_data, self.model.cfg, self.cfg.batch_size, self.rng, self.model.cfg.reward
        )
        loss = dt_loss(self.model, batch)
        self._optimise(loss)
        return {"loss": loss.item(), "steps": int(batch["loss_mask"].sum())}

    def _optimise(self, loss: torch.Tensor) -> None:
        self.optimizer.zero_grad()
        loss.backward()
        torch.nn.utils.clip_grad_norm_(self.model.parameters(), self.cfg.grad_clip)
        self.optimizer.step()

    # -- loop

    def run(self, resume: bool = False) -> dict[str, Any]:
        """Trains to ``iterations``; returns the last history entry."""
        cfg = self.cfg
        if resume and self.resume():
            self.log(f"resumed at iteration {self.iteration}")
        t0 = time.perf_counter()
        expert, randoms = self._demos()
        if cfg.agent == "vln_dt":
            from havln_mj.agents.vln_dt import DTDataset

            self._dt_data = DTDataset(randoms)
            ok = sum(d.success for d in randoms)
            self.log(f"{len(randoms)} random walks, {ok} successful ({ok / len(randoms):.1%})")
        else:
            self.log(f"{len(expert)} expert demos, {len(randoms)} random-walk demos")
        self.log(f"data ready in {time.perf_counter() - t0:.1f} s")
        bar = tqdm(
            total=cfg.iterations,
            initial=self.iteration,
            desc=cfg.agent,
            unit="it",
            disable=not self.progress,
        )
        window: list[dict[str, float]] = []
        t_train = time.perf_counter()
        while self.iteration < cfg.iterations:
            self.model.train()
            stats = self._cm_step(expert, randoms) if cfg.agent == "vln_cm" else self._dt_step()
            self.iteration += 1
            window.append(stats)
            bar.update()
            if self.iteration % cfg.log_every == 0 or self.iteration == cfg.iterations:
                entry = {
                    "iteration": self.iteration,
                    "loss": float(np.mean([w["loss"] for w in window])),
                    "seconds": round(time.perf_counter() - t_train, 1),
                }
                window = []
                if self.iteration % cfg.eval_every == 0 or self.iteration == cfg.iterations:
                    entry.update(self._validate())
                self.history.append(entry)
                self.log(json.dumps(entry))
                if self.iteration % cfg.eval_every == 0 or self.iteration == cfg.iterations:
                    self._save(entry)
        bar.close()
        self._plot()
        return self.history[-1] if self.history else {}

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
        atomic_write_json(self.out / "history.json", self.history, indent=1)

    def _plot(self) -> None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        if not self.history:
            return
        it = [h["iteration"] for h in self.history]
        fig, ax = plt.subplots(figsize=(6, 3.5))
        ax.plot(it, [h["loss"] for h in self.history], label="training loss")
        ax.set_xlabel("iteration")
        ax.set_ylabel("cross-entropy")
        val = [(h["iteration"], h["val_sr"]) for h in self.history if "val_sr" in h]
        if val:
            ax2 = ax.twinx()
            ax2.plot(*zip(*val, strict=True), "o-", color="tab:green", label="val SR")
            ax2.set_ylabel("val SR")
            ax2.set_ylim(0, 1)
        ax.set_title(f"{self.cfg.agent} ({self.out.name})")
        fig.tight_layout()
        import io

        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=100)
        plt.close(fig)
        atomic_write_bytes(self.out / "loss.png", buf.getvalue())


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit code."""
    p = argparse.ArgumentParser(
        prog="python -m havln_mj.agents.train", description=__doc__.splitlines()[0]
    )
    p.add_argument("--agent", choices=AGENTS, default=None)
    p.add_argument(
        "--config", type=Path, required=True, help="JSON file, or a name in agents/configs/"
    )
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    p.add_argument("--out", type=Path, default=None, help="output folder (default runs/<agent>)")
    p.add_argument("--resume", action="store_true", help="continue from OUT/checkpoint.pt")
    p.add_argument("--no-progress", action="store_true")
    p.add_argument(
        "--threads",
        type=int,
        default=None,
        help="torch threads (default: torch's; 1 on a busy machine)",
    )
    args = p.parse_args(argv)
    if args.threads is not None:
        torch.set_num_threads(max(1, args.threads))
    try:
        cfg = read_config(args.config, args.agent, args.overrides)
        out = (args.out or Path("runs") / cfg.agent).expanduser().resolve()
        trainer = Trainer(cfg, out, progress=not args.no_progress)
        last = trainer.run(resume=args.resume)
    except HavlnError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(json.dumps({"out": str(out), **last}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
