"""Pretraining the view encoder on simulator ground truth (region, people, FORWARD, depth)."""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import torch
from torch import Tensor, nn
from tqdm import tqdm

from havln_mj.agents.vision.encoder import ViewEncoder
from havln_mj.agents.vision.heads import TARGET_KEYS, PretrainHeads, pretrain_loss
from havln_mj.agents.vision.inputs import DEPTH_MAX, check_rgb, device_of, prepare_for
from havln_mj.errors import InvalidArgumentError


@dataclass
class _Rows:
    """The pretraining set: images, depth (or None) and targets, one row per view."""

    rgb: np.ndarray
    depth: np.ndarray | None
    targets: dict[str, np.ndarray]

    def inputs(self, encoder: nn.Module, idx: np.ndarray) -> Tensor:
        return prepare_for(encoder, self.rgb[idx], None if self.depth is None else self.depth[idx])


def _check_targets(
    targets: Mapping[str, np.ndarray], n: int, n_regions: int
) -> dict[str, np.ndarray]:
    unknown = set(targets) - set(TARGET_KEYS)
    if unknown or not targets:
        raise InvalidArgumentError(
            f"pretraining targets {sorted(targets)}; valid: a non-empty subset of "
            f"{', '.join(TARGET_KEYS)}"
        )
    out = {}
    for key, value in targets.items():
        arr = np.asarray(value)
        want_ndim = 3 if key == "depth" else 1
        if arr.ndim != want_ndim or len(arr) != n:
            raise InvalidArgumentError(
                f"target {key!r} must have {n} rows and {want_ndim} dimensions, got "
                f"{tuple(arr.shape)}"
            )
        if key == "region":
            arr = arr.astype(np.int64)
            bad = arr[(arr < -1) | (arr >= n_regions)]
            if bad.size:
                raise InvalidArgumentError(
                    f"region target {int(bad[0])} outside -1 (unknown) … {n_regions - 1}"
                )
        out[key] = arr
    return out


def _split(
    n: int, val_fraction: float, rng: np.random.Generator, groups: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """Train and validation row indices; rows of one group stay on one side."""
    if not 0.0 <= val_fraction < 1.0:
        raise InvalidArgumentError(f"val_fraction {val_fraction!r}; valid: 0 ≤ f < 1")
    want = round(n * val_fraction)
    if groups is None:
        perm = rng.permutation(n)
        want = min(want, n - 1)
        return np.sort(perm[want:]), np.sort(perm[:want])
    groups = np.asarray(groups)
    if len(groups) != n:
        raise InvalidArgumentError(f"groups has {len(groups)} rows, the images {n}")
    names, inverse = np.unique(groups, return_inverse=True)
    counts = np.bincount(inverse, minlength=len(names))
    in_val = np.zeros(len(names), bool)
    taken = 0
    for g in rng.permutation(len(names)):
        if taken >= want or taken + counts[g] >= n:
            break
        in_val[g] = True
        taken += counts[g]
    val = in_val[inverse]
    return np.flatnonzero(~val), np.flatnonzero(val)


def _batch_targets(
    targets: Mapping[str, np.ndarray], idx: np.ndarray, device: torch.device
) -> dict[str, Tensor]:
    out = {}
    for key, arr in targets.items():
        dtype = np.int64 if key == "region" else np.float32
        out[key] = torch.from_numpy(np.asarray(arr[idx], dtype=dtype)).to(device)
    return out


@torch.no_grad()
def _evaluate(
    encoder: nn.Module, heads: PretrainHeads, rows: _Rows, idx: np.ndarray, batch_size: int
) -> dict[str, float]:
    """Validation metrics over rows ``idx`` (eval mode)."""
    device = device_of(encoder)
    sums = dict.fromkeys(("region_ok", "region_n", "person", "forward_ok", "depth", "depth_n"), 0.0)
    for start in range(0, len(idx), batch_size):
        b = idx[start : start + batch_size]
        pred = heads(encoder(rows.inputs(encoder, b)))
        t = _batch_targets(rows.targets, b, device)
        if "region" in t:
            known = t["region"] >= 0
            hit = pred["region"].argmax(-1) == t["region"]
            sums["region_ok"] += float((hit & known).sum())
            sums["region_n"] += float(known.sum())
        if "person" in t:
            sums["person"] += float((torch.sigmoid(pred["person"]) - t["person"]).abs().sum())
        if "forward" in t:
            sums["forward_ok"] += float(((pred["forward"] > 0) == (t["forward"] > 0.5)).sum())
        if "depth" in t:
            valid = t["depth"] > 0
            err = (pred["depth"] - t["depth"].clamp(max=DEPTH_MAX)).abs()
            sums["depth"] += float(err[valid].sum())
            sums["depth_n"] += float(valid.sum())
    n = len(idx)
    out = {}
    targets = rows.targets
    if "region" in targets and sums["region_n"]:
        out["val_region_acc"] = sums["region_ok"] / sums["region_n"]
    if "person" in targets:
        out["val_person_mae"] = sums["person"] / n
    if "forward" in targets:
        out["val_forward_acc"] = sums["forward_ok"] / n
    if "depth" in targets and sums["depth_n"]:
        out["val_depth_mae"] = sums["depth"] / sums["depth_n"]
    return out


def pretrain_encoder(
    encoder: ViewEncoder,
    rgb: np.ndarray,
    depth: np.ndarray | None,
    targets: dict[str, np.ndarray],
    *,
    n_regions: int,
    epochs: int = 3,
    batch_size: int = 128,
    lr: float = 1e-3,
    seed: int = 0,
    progress: bool = True,
    val_fraction: float = 0.1,
    weight_decay: float = 1e-4,
    flip: bool = True,
    groups: np.ndarray | None = None,
    loss_weights: Mapping[str, float] | None = None,
) -> list[dict[str, float]]:
    """Trains ``encoder`` (with throw-away :class:`~.PretrainHeads`) on simulator ground truth.

    AdamW with a linear warm-up then cosine decay per step, gradient norm clipped at 5.
    Mini-batches are gathered from the numpy arrays one at a time (memmaps work; nothing is
    converted as a whole). Deterministic given ``seed``: the heads' initialisation uses a forked
    torch RNG seeded with ``seed`` (the caller's global torch RNG is left untouched), and the
    split, shuffling and flips come from ``numpy.random.default_rng(seed)``. Runs on the
    encoder's device.

    Args:
        encoder: The encoder to train in place (left in eval mode).
        rgb: ``(N, H, W, 3)`` uint8 views.
        depth: ``(N, H, W)`` metres (0 = no reading), or None (required for RGB-D encoders).
        targets: Any non-empty subset of ``"region"`` ``(N,)`` int (-1 = unknown),
            ``"person"`` ``(N,)`` fraction, ``"forward"`` ``(N,)`` 0/1, ``"depth"``
            ``(N, rows, cols)`` metres per image cell (0 = no reading).
        n_regions: Region classes.
        epochs: Passes over the training rows.
        batch_size: Views per step.
        lr: Peak learning rate.
        seed: Seed of everything random here.
        progress: Show a tqdm bar per epoch.
        val_fraction: Share of rows held out for the validation metrics (0: none).
        weight_decay: AdamW weight decay.
        flip: Mirror a random half of each batch left-right (the depth grid with it).
        groups: Optional ``(N,)`` labels (e.g. scan or viewpoint ids) kept whole on one side of
            the split, so validation measures unseen places rather than re-rendered ones.
        loss_weights: Per-term weights for :func:`~.pretrain_loss`.

    Returns:
        One dict per epoch, with ``epoch``, ``seconds``, ``train_total`` and ``train_<term>``
        (batch means), and when there are validation rows ``val_region_acc`` (known regions only),
        ``val_person_mae``, ``val_forward_acc``, ``val_depth_mae`` (metres, cells with a
        reading), for the targets given.

    Raises:
        InvalidArgumentError: Mismatched array lengths, bad targets or settings.
    """
    rows = _rows(rgb, depth, targets, n_regions, epochs, batch_size, lr)
    n = len(rows.rgb)
    grid = tuple(rows.targets["depth"].shape[1:]) if "depth" in rows.targets else (6, 8)
    rng = np.random.default_rng(seed)
    train_idx, val_idx = _split(n, val_fraction, rng, groups)
    history: list[dict[str, float]] = []
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(seed)
        heads = PretrainHeads(encoder.out_dim, n_regions, grid).to(device_of(encoder))
        total_steps = _steps_per_epoch(len(train_idx), batch_size) * epochs
        step = _Step.make(encoder, heads, lr, weight_decay, total_steps, flip, loss_weights)
        for epoch in range(epochs):
            desc = f"pretrain {epoch + 1}/{epochs}" if progress else None
            record = _epoch(step, rows, (train_idx, val_idx), batch_size, rng, desc)
            history.append({"epoch": epoch + 1, **record})
    encoder.eval()
    return history


def _epoch(
    step: _Step,
    rows: _Rows,
    split: tuple[np.ndarray, np.ndarray],
    batch_size: int,
    rng: np.random.Generator,
    desc: str | None,
) -> dict[str, float]:
    """One training pass over a shuffled ``split[0]``, then the metrics on ``split[1]``.

    Returns the ``train_<term>`` means, the validation metrics (when there are validation
    rows) and ``seconds``. ``desc``: the progress bar's label (None: no bar).
    """
    train_idx, val_idx = split
    t0 = time.perf_counter()
    bar = tqdm(
        total=_steps_per_epoch(len(train_idx), batch_size),
        desc=desc,
        unit="batch",
        disable=desc is None,
        leave=False,
    )
    step.encoder.train()
    step.heads.train()
    means = _train_epoch(step, rows, rng.permutation(train_idx), batch_size, rng, bar)
    bar.close()
    record = {f"train_{k}": v for k, v in means.items()}
    if len(val_idx):
        step.encoder.eval()
        step.heads.eval()
        record.update(_evaluate(step.encoder, step.heads, rows, val_idx, max(batch_size, 256)))
    return {**record, "seconds": time.perf_counter() - t0}


def _rows(
    rgb: np.ndarray,
    depth: np.ndarray | None,
    targets: Mapping[str, np.ndarray],
    n_regions: int,
    epochs: int,
    batch_size: int,
    lr: float,
) -> _Rows:
    """The checked pretraining set; raises on what :func:`~.pretrain_encoder` rejects."""
    rgb = check_rgb(rgb)
    n = len(rgb)
    if depth is not None and len(depth) != n:
        raise InvalidArgumentError(f"depth has {len(depth)} rows, rgb {n}")
    if n < 2 or epochs < 1 or batch_size < 2 or not lr > 0:
        raise InvalidArgumentError(
            f"need ≥ 2 images (got {n}), epochs ≥ 1 (got {epochs}), batch_size ≥ 2 "
            f"(got {batch_size}) and lr > 0 (got {lr})"
        )
    return _Rows(rgb, depth, _check_targets(targets, n, n_regions))


def _warmup_cosine(
    opt: torch.optim.Optimizer, total_steps: int
) -> torch.optim.lr_scheduler.LambdaLR:
    """Linear warm-up over a tenth of the steps (at most 100), then cosine decay to 0."""
    warmup = max(1, min(100, total_steps // 10))

    def schedule(step: int) -> float:
        if step < warmup:
            return (step + 1) / warmup
        return 0.5 * (1.0 + math.cos(math.pi * (step - warmup) / max(1, total_steps - warmup)))

    return torch.optim.lr_scheduler.LambdaLR(opt, schedule)


@dataclass
class _Step:
    """What one optimisation step needs."""

    encoder: nn.Module
    heads: PretrainHeads
    opt: torch.optim.Optimizer
    sched: torch.optim.lr_scheduler.LambdaLR
    params: list[nn.Parameter]
    flip: bool
    loss_weights: Mapping[str, float] | None

    @classmethod
    def make(
        cls,
        encoder: nn.Module,
        heads: PretrainHeads,
        lr: float,
        weight_decay: float,
        total_steps: int,
        flip: bool,
        loss_weights: Mapping[str, float] | None,
    ) -> _Step:
        """AdamW over the encoder's and heads' parameters, with :func:`_warmup_cosine`."""
        params = list(encoder.parameters()) + list(heads.parameters())
        opt = torch.optim.AdamW(params, lr=lr, weight_decay=weight_decay)
        sched = _warmup_cosine(opt, max(1, total_steps))
        return cls(encoder, heads, opt, sched, params, flip, loss_weights)


def _steps_per_epoch(n_train: int, batch_size: int) -> int:
    """Optimisation steps in one pass (a last batch of one row is skipped)."""
    return sum(n_train - s >= 2 for s in range(0, n_train, batch_size))


def _mirror(x: Tensor, t: dict[str, Tensor], rng: np.random.Generator) -> Tensor:
    """Mirrors a random half of the batch left-right, the depth targets with it (in place)."""
    mirrored = torch.from_numpy(rng.random(len(x)) < 0.5).to(x.device)
    if "depth" in t:
        t["depth"] = torch.where(mirrored.view(-1, 1, 1), t["depth"].flip(-1), t["depth"])
    return torch.where(mirrored.view(-1, 1, 1, 1), x.flip(-1), x)


def _train_epoch(
    step: _Step,
    rows: _Rows,
    order: np.ndarray,
    batch_size: int,
    rng: np.random.Generator,
    bar: tqdm,
) -> dict[str, float]:
    """One pass over ``order`` in mini-batches; the batch means of each loss term."""
    device = device_of(step.encoder)
    sums: dict[str, float] = {}
    counts: dict[str, int] = {}
    for start in range(0, len(order), batch_size):
        b = np.sort(order[start : start + batch_size])  # sorted: faster memmap reads
        if len(b) < 2:  # BatchNorm needs two samples
            continue
        x = rows.inputs(step.encoder, b)
        t = _batch_targets(rows.targets, b, device)
        if step.flip:
            x = _mirror(x, t, rng)
        loss, parts = pretrain_loss(step.heads(step.encoder(x)), t, weights=step.loss_weights)
        step.opt.zero_grad(set_to_none=True)
        loss.backward()
        nn.utils.clip_grad_norm_(step.params, 5.0)
        step.opt.step()
        step.sched.step()
        for k, v in parts.items():
            sums[k] = sums.get(k, 0.0) + v
            counts[k] = counts.get(k, 0) + 1
        bar.set_postfix(loss=f"{parts['total']:.3f}")
        bar.update()
    return {k: sums[k] / counts[k] for k in sums}
