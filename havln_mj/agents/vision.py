"""View encoders in plain torch: a small ResNet trained on our renders, or ResNet-152 weights.

HA3D's agents read ImageNet ResNet-152 pool features (2048-d) of 640×480 frames. Neither
torchvision nor downloads are available here, so the default encoder is :class:`ViewEncoder`, a
ResNet-style CNN trained from scratch on the simulator's own renders by multi-task prediction of
simulator ground truth (:func:`pretrain_encoder`): the viewpoint's region, the fraction of the
view showing a person, whether FORWARD would move, and a coarse depth grid. Users who hold
ImageNet ResNet-152 weights can load them with :func:`load_resnet152` instead.

Input conventions (:func:`prepare_views`): RGB ``uint8`` → ``x / 127.5 - 1`` in ``[-1, 1]``;
depth in metres clipped to ``[0, DEPTH_MAX]`` (no reading, NaN or negative → 0; +inf →
``DEPTH_MAX``) → ``2 · d / DEPTH_MAX - 1`` in ``[-1, 1]``, stacked as a fourth channel. The
ResNet-152 path uses ImageNet's per-channel mean and std instead (:func:`prepare_imagenet`).
"""

from __future__ import annotations

import math
import pickle
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F  # noqa: N812 (the usual torch alias)
from torch import Tensor, nn
from tqdm import tqdm

from havln_mj.errors import InvalidArgumentError, MalformedDataError, MissingDataError

DEPTH_MAX = 10.0  # metres; depth inputs and targets are clipped here (views.MAX_DEPTH)
IMAGENET_MEAN = (0.485, 0.456, 0.406)
IMAGENET_STD = (0.229, 0.224, 0.225)
TARGET_KEYS = ("region", "person", "forward", "depth")
# The person fraction is small and its soft-target gradient weak; weighted up so it is learnt
# alongside the others (tuned on a synthetic set where all four are learnable).
DEFAULT_LOSS_WEIGHTS = {"region": 1.0, "person": 10.0, "forward": 1.0, "depth": 1.0}
"""Weights of the view encoder's pretraining loss terms."""

# ---------------------------------------------------------------------- input preparation


def _check_rgb(rgb: np.ndarray) -> np.ndarray:
    rgb = np.asarray(rgb)
    if rgb.ndim != 4 or rgb.shape[-1] != 3 or rgb.dtype != np.uint8:
        raise InvalidArgumentError(
            f"rgb must be uint8 (N, H, W, 3), got {rgb.dtype} {tuple(rgb.shape)}"
        )
    return rgb


def _rgb_tensor(rgb: np.ndarray) -> Tensor:
    """``(N, H, W, 3)`` uint8 → contiguous ``(N, 3, H, W)`` float32 in ``[0, 255]``."""
    # astype copies into a writable array (inputs may be read-only memmaps of the cache).
    return torch.from_numpy(rgb.astype(np.float32)).permute(0, 3, 1, 2).contiguous()


def _depth_metres(depth: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    depth = np.asarray(depth)
    if depth.shape != shape:
        raise InvalidArgumentError(
            f"depth must be (N, H, W) = {shape} to match rgb, got {tuple(depth.shape)}"
        )
    d = depth.astype(np.float32)
    # NaN / negative = no reading (0); +inf = beyond range.
    d = np.nan_to_num(d, nan=0.0, posinf=DEPTH_MAX, neginf=0.0)
    return np.clip(d, 0.0, DEPTH_MAX)


def prepare_views(rgb: np.ndarray, depth: np.ndarray | None) -> Tensor:
    """Turns rendered views into :class:`ViewEncoder` input.

    RGB becomes ``x / 127.5 - 1`` (``[-1, 1]``). Depth (metres, 0 = no reading) is clipped to
    ``[0, DEPTH_MAX]`` (NaN and negative values count as no reading, +inf as ``DEPTH_MAX``) and
    mapped linearly to ``[-1, 1]``, so "no reading" reads as "touching the camera".

    Args:
        rgb: ``(N, H, W, 3)`` uint8.
        depth: ``(N, H, W)`` float depth in metres, or None for RGB only.

    Returns:
        ``(N, 4, H, W)`` float32 (RGB then depth), or ``(N, 3, H, W)`` without depth.

    Raises:
        InvalidArgumentError: Wrong dtype or shapes.
    """
    rgb = _check_rgb(rgb)
    x = _rgb_tensor(rgb).mul_(1.0 / 127.5).sub_(1.0)
    if depth is None:
        return x
    d = torch.from_numpy(_depth_metres(depth, rgb.shape[:3]))
    d = d.mul_(2.0 / DEPTH_MAX).sub_(1.0).unsqueeze(1)
    return torch.cat([x, d], dim=1)


def prepare_imagenet(rgb: np.ndarray, *, size: tuple[int, int] | None = None) -> Tensor:
    """Turns rendered views into ImageNet-normalised ResNet input.

    Args:
        rgb: ``(N, H, W, 3)`` uint8.
        size: Optional ``(height, width)`` to resize to (bilinear, antialiased); None keeps the
            rendered size (HA3D fed its 640×480 frames unresized).

    Returns:
        ``(N, 3, H, W)`` float32, ``(x / 255 - mean) / std`` with ImageNet's per-channel
        mean ``(0.485, 0.456, 0.406)`` and std ``(0.229, 0.224, 0.225)``.

    Raises:
        InvalidArgumentError: Wrong dtype or shape.
    """
    rgb = _check_rgb(rgb)
    x = _rgb_tensor(rgb).mul_(1.0 / 255.0)
    if size is not None and tuple(size) != tuple(x.shape[-2:]):
        x = F.interpolate(x, size=tuple(size), mode="bilinear", align_corners=False, antialias=True)
    mean = torch.tensor(IMAGENET_MEAN).view(1, 3, 1, 1)
    std = torch.tensor(IMAGENET_STD).view(1, 3, 1, 1)
    return (x - mean) / std


# ---------------------------------------------------------------------- our encoder


class _BasicBlock(nn.Module):
    """Two 3×3 conv-BN layers with an identity (or 1×1 projection) shortcut."""

    def __init__(self, cin: int, cout: int, stride: int) -> None:
        super().__init__()
        self.conv1 = nn.Conv2d(cin, cout, 3, stride, 1, bias=False)
        self.bn1 = nn.BatchNorm2d(cout)
        self.conv2 = nn.Conv2d(cout, cout, 3, 1, 1, bias=False)
        self.bn2 = nn.BatchNorm2d(cout)
        self.shortcut: nn.Module = nn.Identity()
        if stride != 1 or cin != cout:
            self.shortcut = nn.Sequential(
                nn.Conv2d(cin, cout, 1, stride, bias=False), nn.BatchNorm2d(cout)
            )

    def forward(self, x: Tensor) -> Tensor:
        """Residual block."""
        y = F.relu(self.bn1(self.conv1(x)), inplace=True)
        y = self.bn2(self.conv2(y))
        return F.relu(y + self.shortcut(x), inplace=True)


class ViewEncoder(nn.Module):
    """A small ResNet (BasicBlocks, BatchNorm) mapping one view to a feature vector.

    Layout: a 3×3 stem conv (stride ``stem_stride``), then one stage per entry of ``widths``
    with ``blocks[i]`` residual blocks each (the first stage keeps the resolution, later ones
    halve it), global average pooling and a linear projection to ``out_dim``. At the default
    64×48 input the last stage sees 8×6 → 4×3 cells; any input of 1 px or more runs, ≥ 32 px
    per side is meaningful.

    Attributes:
        in_channels: 4 for RGB-D (:func:`prepare_views` with depth), 3 for RGB.
        out_dim: Feature size.
    """

    def __init__(
        self,
        in_channels: int = 4,
        widths: tuple[int, ...] = (32, 64, 128, 256),
        blocks: tuple[int, ...] = (1, 1, 1, 1),
        out_dim: int = 256,
        *,
        stem_stride: int = 2,
    ) -> None:
        """Builds the network (Kaiming-initialised, last BN of each block zero-initialised).

        Raises:
            InvalidArgumentError: Non-positive sizes, or ``widths`` and ``blocks`` of different
                lengths.
        """
        super().__init__()
        widths, blocks = tuple(int(w) for w in widths), tuple(int(b) for b in blocks)
        if len(widths) != len(blocks) or not widths:
            raise InvalidArgumentError(
                f"widths {widths} and blocks {blocks} must be non-empty and of equal length"
            )
        sizes = (in_channels, out_dim, stem_stride, *widths, *blocks)
        if min(sizes) < 1:
            raise InvalidArgumentError(
                f"in_channels={in_channels}, out_dim={out_dim}, stem_stride={stem_stride}, "
                f"widths={widths}, blocks={blocks}: all must be ≥ 1"
            )
        self.in_channels = int(in_channels)
        self.widths, self.blocks = widths, blocks
        self.out_dim = int(out_dim)
        self.stem_stride = int(stem_stride)
        self.stem = nn.Sequential(
            nn.Conv2d(in_channels, widths[0], 3, stem_stride, 1, bias=False),
            nn.BatchNorm2d(widths[0]),
            nn.ReLU(inplace=True),
        )
        stages = []
        cin = widths[0]
        for i, (w, n) in enumerate(zip(widths, blocks, strict=True)):
            layers = [
                _BasicBlock(cin if j == 0 else w, w, 2 if i > 0 and j == 0 else 1) for j in range(n)
            ]
            stages.append(nn.Sequential(*layers))
            cin = w
        self.stages = nn.Sequential(*stages)
        self.proj = nn.Linear(widths[-1], out_dim)
        for m in self.modules():
            if isinstance(m, nn.Conv2d):
                nn.init.kaiming_normal_(m.weight, mode="fan_out", nonlinearity="relu")
            elif isinstance(m, nn.BatchNorm2d):
                nn.init.ones_(m.weight)
                nn.init.zeros_(m.bias)
        # Zero-init residual branches: each block starts as the identity (trains faster).
        for m in self.modules():
            if isinstance(m, _BasicBlock):
                nn.init.zeros_(m.bn2.weight)

    def config(self) -> dict[str, Any]:
        """The constructor arguments (JSON-serialisable), for checkpoints."""
        return {
            "in_channels": self.in_channels,
            "widths": list(self.widths),
            "blocks": list(self.blocks),
            "out_dim": self.out_dim,
            "stem_stride": self.stem_stride,
        }

    @classmethod
    def from_config(cls, cfg: Mapping[str, Any]) -> ViewEncoder:
        """A fresh encoder built from :meth:`config`'s output (weights are not included)."""
        cfg = dict(cfg)
        for key in ("widths", "blocks"):
            if key in cfg:
                cfg[key] = tuple(cfg[key])
        return cls(**cfg)

    def prepare(self, rgb: np.ndarray, depth: np.ndarray | None) -> Tensor:
        """:func:`prepare_views` for this encoder's channels (depth is ignored by RGB models).

        Raises:
            InvalidArgumentError: An RGB-D encoder got no depth.
        """
        if self.in_channels == 3:
            return prepare_views(rgb, None)
        if self.in_channels == 4 and depth is None:
            raise InvalidArgumentError("this ViewEncoder takes RGB-D input (4 channels); no depth")
        return prepare_views(rgb, depth)

    def forward(self, x: Tensor) -> Tensor:
        """``(N, in_channels, H, W)`` float32 → ``(N, out_dim)`` features."""
        if x.ndim != 4 or x.shape[1] != self.in_channels:
            raise InvalidArgumentError(
                f"ViewEncoder expects (N, {self.in_channels}, H, W), got {tuple(x.shape)}"
            )
        y = self.stages(self.stem(x))
        return self.proj(torch.flatten(F.adaptive_avg_pool2d(y, 1), 1))


# ---------------------------------------------------------------------- pretraining


class PretrainHeads(nn.Module):
    """Linear read-outs of the simulator ground truth from view features.

    Linear heads keep the information in the features themselves (a linear probe), which is
    what the agents downstream consume.
    """

    def __init__(self, in_dim: int, n_regions: int, depth_grid: tuple[int, int] = (6, 8)) -> None:
        """Builds the heads.

        Args:
            in_dim: Feature size.
            n_regions: Region classes.
            depth_grid: ``(rows, cols)`` of the depth target grid.

        Raises:
            InvalidArgumentError: A size below 1.
        """
        super().__init__()
        if min(in_dim, n_regions, *depth_grid) < 1:
            raise InvalidArgumentError(
                f"in_dim={in_dim}, n_regions={n_regions}, depth_grid={depth_grid}: all ≥ 1"
            )
        self.depth_grid = (int(depth_grid[0]), int(depth_grid[1]))
        self.region = nn.Linear(in_dim, n_regions)
        self.person = nn.Linear(in_dim, 1)
        self.forward_head = nn.Linear(in_dim, 1)
        self.depth = nn.Linear(in_dim, self.depth_grid[0] * self.depth_grid[1])

    def forward(self, features: Tensor) -> dict[str, Tensor]:
        """Predictions from ``(N, in_dim)`` features.

        Returns:
            ``"region"``: ``(N, n_regions)`` logits; ``"person"``: ``(N,)`` logit of the person
            fraction; ``"forward"``: ``(N,)`` logit of FORWARD moving; ``"depth"``:
            ``(N, rows, cols)`` metres in ``(0, DEPTH_MAX)``.
        """
        n = features.shape[0]
        return {
            "region": self.region(features),
            "person": self.person(features).squeeze(-1),
            "forward": self.forward_head(features).squeeze(-1),
            "depth": DEPTH_MAX * torch.sigmoid(self.depth(features)).view(n, *self.depth_grid),
        }


def pretrain_loss(
    pred: dict[str, Tensor],
    targets: dict[str, Tensor],
    *,
    weights: Mapping[str, float] | None = None,
) -> tuple[Tensor, dict[str, float]]:
    """The multi-task loss of :class:`PretrainHeads` predictions.

    Terms (each only when its target is given and has a valid entry in the batch):
    ``region`` cross-entropy over rows with a region ≥ 0 (-1 = unknown is ignored);
    ``person`` binary cross-entropy against the soft fraction minus the fraction's entropy
    (the KL divergence, 0 when exact); ``forward`` binary cross-entropy; ``depth`` smooth-L1
    (β = 0.5 m) in metres over cells with a reading (target > 0), targets clipped to
    ``DEPTH_MAX``.

    Args:
        pred: :meth:`PretrainHeads.forward` output.
        targets: Any of ``"region"`` ``(N,)`` int64, ``"person"`` ``(N,)`` float,
            ``"forward"`` ``(N,)`` float 0/1, ``"depth"`` ``(N, rows, cols)`` float metres.
        weights: Per-term weights overriding :data:`DEFAULT_LOSS_WEIGHTS` (person 10, others 1).

    Returns:
        The weighted total (a differentiable scalar; 0 when no term applies) and each computed
        term's unweighted value plus ``"total"``, as floats.

    Raises:
        InvalidArgumentError: An unknown target or weight name.
    """
    unknown = set(targets) - set(TARGET_KEYS) | set(weights or {}) - set(TARGET_KEYS)
    if unknown:
        raise InvalidArgumentError(
            f"unknown pretraining targets {sorted(unknown)}; valid: {', '.join(TARGET_KEYS)}"
        )
    w = DEFAULT_LOSS_WEIGHTS | dict(weights or {})
    terms: dict[str, Tensor] = {}
    if "region" in targets:
        region = targets["region"].long()
        known = region >= 0
        if bool(known.any()):
            terms["region"] = F.cross_entropy(pred["region"][known], region[known])
    if "person" in targets:
        # Soft-target BCE minus the target's entropy (= KL divergence): same gradient, but 0
        # at a perfect prediction, so the logged term shows progress.
        person = targets["person"].to(pred["person"].dtype).clamp(0.0, 1.0)
        entropy = -(torch.xlogy(person, person) + torch.xlogy(1 - person, 1 - person)).mean()
        bce = F.binary_cross_entropy_with_logits(pred["person"], person)
        terms["person"] = bce - entropy
    if "forward" in targets:
        fwd = targets["forward"].to(pred["forward"].dtype)
        terms["forward"] = F.binary_cross_entropy_with_logits(pred["forward"], fwd)
    if "depth" in targets:
        depth = targets["depth"].to(pred["depth"].dtype)
        valid = depth > 0
        if bool(valid.any()):
            terms["depth"] = F.smooth_l1_loss(
                pred["depth"][valid], depth[valid].clamp(max=DEPTH_MAX), beta=0.5
            )
    total = sum((w[k] * v for k, v in terms.items()), start=pred["person"].sum() * 0.0)
    parts = {k: float(v.detach()) for k, v in terms.items()}
    parts["total"] = float(total.detach())
    return total, parts


def _device(module: nn.Module) -> torch.device:
    param = next(module.parameters(), None)
    return param.device if param is not None else torch.device("cpu")


def _prepare_for(encoder: nn.Module, rgb: np.ndarray, depth: np.ndarray | None) -> Tensor:
    prepare = getattr(encoder, "prepare", None)
    x = prepare(rgb, depth) if prepare is not None else prepare_views(rgb, depth)
    return x.to(_device(encoder))


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
    encoder: nn.Module,
    heads: PretrainHeads,
    rgb: np.ndarray,
    depth: np.ndarray | None,
    targets: Mapping[str, np.ndarray],
    idx: np.ndarray,
    batch_size: int,
) -> dict[str, float]:
    """Validation metrics over rows ``idx`` (eval mode)."""
    device = _device(encoder)
    sums = dict.fromkeys(("region_ok", "region_n", "person", "forward_ok", "depth", "depth_n"), 0.0)
    for start in range(0, len(idx), batch_size):
        b = idx[start : start + batch_size]
        pred = heads(encoder(_prepare_for(encoder, rgb[b], None if depth is None else depth[b])))
        t = _batch_targets(targets, b, device)
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
    """Trains ``encoder`` (with throw-away :class:`PretrainHeads`) on simulator ground truth.

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
        loss_weights: Per-term weights for :func:`pretrain_loss`.

    Returns:
        One dict per epoch, with ``epoch``, ``seconds``, ``train_total`` and ``train_<term>`` (batch
        means), and when there are validation rows ``val_region_acc`` (known regions only),
        ``val_person_mae``, ``val_forward_acc``, ``val_depth_mae`` (metres, cells with a
        reading), for the targets given.

    Raises:
        InvalidArgumentError: Mismatched array lengths, bad targets or settings.
    """
    rgb = _check_rgb(rgb)
    n = len(rgb)
    if depth is not None and len(depth) != n:
        raise InvalidArgumentError(f"depth has {len(depth)} rows, rgb {n}")
    if n < 2 or epochs < 1 or batch_size < 2 or not lr > 0:
        raise InvalidArgumentError(
            f"need ≥ 2 images (got {n}), epochs ≥ 1 (got {epochs}), batch_size ≥ 2 "
            f"(got {batch_size}) and lr > 0 (got {lr})"
        )
    targets = _check_targets(targets, n, n_regions)
    grid = tuple(targets["depth"].shape[1:]) if "depth" in targets else (6, 8)
    rng = np.random.default_rng(seed)
    train_idx, val_idx = _split(n, val_fraction, rng, groups)
    device = _device(encoder)
    steps_per_epoch = sum(len(train_idx) - s >= 2 for s in range(0, len(train_idx), batch_size))
    total_steps = max(1, steps_per_epoch * epochs)
    warmup = max(1, min(100, total_steps // 10))

    def schedule(step: int) -> float:
        if step < warmup:
            return (step + 1) / warmup
        return 0.5 * (1.0 + math.cos(math.pi * (step - warmup) / max(1, total_steps - warmup)))

    history: list[dict[str, float]] = []
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(seed)
        heads = PretrainHeads(encoder.out_dim, n_regions, grid).to(device)
        params = list(encoder.parameters()) + list(heads.parameters())
        opt = torch.optim.AdamW(params, lr=lr, weight_decay=weight_decay)
        sched = torch.optim.lr_scheduler.LambdaLR(opt, schedule)
        for epoch in range(epochs):
            t0 = time.perf_counter()
            encoder.train()
            heads.train()
            order = rng.permutation(train_idx)
            sums: dict[str, float] = {}
            counts: dict[str, int] = {}
            bar = tqdm(
                total=steps_per_epoch,
                desc=f"pretrain {epoch + 1}/{epochs}",
                unit="batch",
                disable=not progress,
                leave=False,
            )
            for start in range(0, len(order), batch_size):
                b = np.sort(order[start : start + batch_size])  # sorted: faster memmap reads
                if len(b) < 2:  # BatchNorm needs two samples
                    continue
                x = _prepare_for(encoder, rgb[b], None if depth is None else depth[b])
                t = _batch_targets(targets, b, device)
                if flip:
                    mirrored = torch.from_numpy(rng.random(len(b)) < 0.5).to(device)
                    x = torch.where(mirrored.view(-1, 1, 1, 1), x.flip(-1), x)
                    if "depth" in t:
                        t["depth"] = torch.where(
                            mirrored.view(-1, 1, 1), t["depth"].flip(-1), t["depth"]
                        )
                loss, parts = pretrain_loss(heads(encoder(x)), t, weights=loss_weights)
                opt.zero_grad(set_to_none=True)
                loss.backward()
                nn.utils.clip_grad_norm_(params, 5.0)
                opt.step()
                sched.step()
                for k, v in parts.items():
                    sums[k] = sums.get(k, 0.0) + v
                    counts[k] = counts.get(k, 0) + 1
                bar.set_postfix(loss=f"{parts['total']:.3f}")
                bar.update()
            bar.close()
            record: dict[str, float] = {"epoch": epoch + 1}
            record.update({f"train_{k}": sums[k] / counts[k] for k in sums})
            if len(val_idx):
                encoder.eval()
                heads.eval()
                record.update(
                    _evaluate(encoder, heads, rgb, depth, targets, val_idx, max(batch_size, 256))
                )
            record["seconds"] = time.perf_counter() - t0
            history.append(record)
    encoder.eval()
    return history


@torch.no_grad()
def encode_views(
    encoder: nn.Module, rgb: np.ndarray, depth: np.ndarray | None, *, batch_size: int = 256
) -> np.ndarray:
    """Features of many views, batch by batch, in eval mode without gradients.

    Input is prepared by the encoder's own ``prepare(rgb, depth)`` when it has one
    (:class:`ViewEncoder`, :class:`ResNetFeatures`), else by :func:`prepare_views`. The
    encoder's train/eval mode is restored afterwards.

    Args:
        encoder: A module mapping prepared views to ``(N, out_dim)``.
        rgb: ``(N, H, W, 3)`` uint8.
        depth: ``(N, H, W)`` metres, or None.
        batch_size: Views per forward pass.

    Returns:
        ``(N, out_dim)`` float32.

    Raises:
        InvalidArgumentError: Bad shapes or batch size.
    """
    rgb = _check_rgb(rgb)
    if batch_size < 1:
        raise InvalidArgumentError(f"batch_size {batch_size}; valid: ≥ 1")
    if depth is not None and len(depth) != len(rgb):
        raise InvalidArgumentError(f"depth has {len(depth)} rows, rgb {len(rgb)}")
    was_training = encoder.training
    encoder.eval()
    try:
        out = []
        for start in range(0, len(rgb), batch_size):
            sl = slice(start, start + batch_size)
            x = _prepare_for(encoder, rgb[sl], None if depth is None else depth[sl])
            out.append(encoder(x).float().cpu().numpy())
    finally:
        encoder.train(was_training)
    if not out:
        return np.zeros((0, int(getattr(encoder, "out_dim", 0))), np.float32)
    return np.concatenate(out).astype(np.float32, copy=False)


# ---------------------------------------------------------------------- ResNet-152


class _Bottleneck(nn.Module):
    """1×1 reduce, 3×3 (strided, the "v1.5" placement), 1×1 expand ×4, plus shortcut."""

    expansion = 4

    def __init__(self, cin: int, width: int, stride: int) -> None:
        super().__init__()
        cout = width * self.expansion
        self.conv1 = nn.Conv2d(cin, width, 1, bias=False)
        self.bn1 = nn.BatchNorm2d(width)
        self.conv2 = nn.Conv2d(width, width, 3, stride, 1, bias=False)
        self.bn2 = nn.BatchNorm2d(width)
        self.conv3 = nn.Conv2d(width, cout, 1, bias=False)
        self.bn3 = nn.BatchNorm2d(cout)
        self.relu = nn.ReLU(inplace=True)
        # Absent (not Identity) without projection, so no "downsample" keys appear then.
        self.downsample: nn.Sequential | None = None
        if stride != 1 or cin != cout:
            self.downsample = nn.Sequential(
                nn.Conv2d(cin, cout, 1, stride, bias=False), nn.BatchNorm2d(cout)
            )

    def forward(self, x: Tensor) -> Tensor:
        """Residual bottleneck block."""
        y = self.relu(self.bn1(self.conv1(x)))
        y = self.relu(self.bn2(self.conv2(y)))
        y = self.bn3(self.conv3(y))
        shortcut = x if self.downsample is None else self.downsample(x)
        return self.relu(y + shortcut)


class ResNet(nn.Module):
    """The ImageNet bottleneck ResNet (He et al. 2016), parameter names as torchvision's.

    7×7/2 stem conv, BN, ReLU, 3×3/2 max-pool, four stages of bottleneck blocks (widths 64,
    128, 256, 512, output ×4; stages 2–4 stride 2 in their first block's 3×3 conv), global
    average pooling and a 1000-way ``fc``. ``forward`` gives logits, :meth:`features` the
    pooled ``(N, 2048)`` vector.
    """

    def __init__(self, layers: Sequence[int], num_classes: int = 1000) -> None:
        """Builds the network for ``layers`` blocks per stage (ResNet-152: 3, 8, 36, 3)."""
        super().__init__()
        self.conv1 = nn.Conv2d(3, 64, 7, 2, 3, bias=False)
        self.bn1 = nn.BatchNorm2d(64)
        self.relu = nn.ReLU(inplace=True)
        self.maxpool = nn.MaxPool2d(3, 2, 1)
        cin = 64
        for i, (width, n) in enumerate(zip((64, 128, 256, 512), layers, strict=True)):
            blocks = []
            for j in range(n):
                blocks.append(_Bottleneck(cin, width, 2 if i > 0 and j == 0 else 1))
                cin = width * _Bottleneck.expansion
            setattr(self, f"layer{i + 1}", nn.Sequential(*blocks))
        self.avgpool = nn.AdaptiveAvgPool2d(1)
        self.fc = nn.Linear(cin, num_classes)
        self.out_dim = cin
        for m in self.modules():
            if isinstance(m, nn.Conv2d):
                nn.init.kaiming_normal_(m.weight, mode="fan_out", nonlinearity="relu")

    def features(self, x: Tensor) -> Tensor:
        """``(N, 3, H, W)`` ImageNet-normalised → ``(N, 2048)`` pooled features."""
        x = self.maxpool(self.relu(self.bn1(self.conv1(x))))
        x = self.layer4(self.layer3(self.layer2(self.layer1(x))))
        return torch.flatten(self.avgpool(x), 1)

    def forward(self, x: Tensor) -> Tensor:
        """``(N, 3, H, W)`` → ``(N, num_classes)`` logits."""
        return self.fc(self.features(x))


class ResNetFeatures(ResNet):
    """A ResNet whose ``forward`` gives the pooled features (HA3D's 2048-d view features).

    Its state_dict keys are torchvision's. ``prepare`` applies :func:`prepare_imagenet`
    (depth ignored) at ``input_size``.

    Attributes:
        out_dim: 2048 for ResNet-152.
        input_size: ``(height, width)`` views are resized to, or None to keep their size.
    """

    def __init__(self, layers: Sequence[int], *, input_size: tuple[int, int] | None = None) -> None:
        """Builds the network; see :class:`ResNet`."""
        super().__init__(layers)
        self.input_size = None if input_size is None else (int(input_size[0]), int(input_size[1]))

    def prepare(self, rgb: np.ndarray, depth: np.ndarray | None = None) -> Tensor:
        """ImageNet-normalised RGB input (``depth`` is ignored)."""
        return prepare_imagenet(rgb, size=self.input_size)

    def forward(self, x: Tensor) -> Tensor:
        """``(N, 3, H, W)`` → ``(N, 2048)`` pooled features."""
        return self.features(x)


RESNET152_LAYERS = (3, 8, 36, 3)


def resnet152() -> ResNet:
    """A randomly initialised ResNet-152 with torchvision's state_dict names and shapes."""
    return ResNet(RESNET152_LAYERS)


_WEIGHTS_HINT = (
    "load_resnet152 needs ImageNet ResNet-152 weights you obtained yourself, e.g. torchvision's "
    "ResNet152_Weights.IMAGENET1K_V1 file (resnet152-394f9c45.pth) saved with "
    "torch.save(model.state_dict(), path) on a machine that has torchvision"
)


def _unwrap_state_dict(obj: Any, path: Path) -> dict[str, Tensor]:
    for key in ("state_dict", "model"):
        if isinstance(obj, Mapping) and isinstance(obj.get(key), Mapping):
            obj = obj[key]
    if not isinstance(obj, Mapping) or not obj:
        raise MalformedDataError(
            f"{path} holds {type(obj).__name__}, not a ResNet-152 state_dict "
            "(a mapping of parameter names to tensors, optionally under 'state_dict'/'model')"
        )
    sd = {str(k): v for k, v in obj.items()}
    if all(k.startswith("module.") for k in sd):  # saved from (Distributed)DataParallel
        sd = {k.removeprefix("module."): v for k, v in sd.items()}
    not_tensors = [k for k, v in sd.items() if not isinstance(v, Tensor)]
    if not_tensors:
        raise MalformedDataError(f"{path}: entries are not tensors: {', '.join(not_tensors[:5])}")
    return sd


def _list(names: Sequence[str], limit: int = 8) -> str:
    more = f" … (+{len(names) - limit} more)" if len(names) > limit else ""
    return ", ".join(names[:limit]) + more


def load_resnet152(
    path: str | Path, *, input_size: tuple[int, int] | None = None
) -> ResNetFeatures:
    """Loads user-supplied ImageNet ResNet-152 weights as a frozen feature encoder.

    Accepts a plain state_dict, one under a ``"state_dict"`` or ``"model"`` key, and keys with a
    ``module.`` prefix. Missing ``num_batches_tracked`` buffers (older checkpoints) and a
    missing ``fc`` (head-less checkpoints; the features do not use it) are tolerated and set
    to zeros.

    Args:
        path: A ``.pth`` file loadable by ``torch.load(..., weights_only=True)``.
        input_size: ``(height, width)`` to resize views to before the network, or None.

    Returns:
        A :class:`ResNetFeatures` in eval mode with gradients off (``requires_grad_(True)``
        to fine-tune); ``out_dim`` 2048.

    Raises:
        MissingDataError: ``path`` does not exist.
        MalformedDataError: The file is not a checkpoint, or its keys or shapes do not match
            ResNet-152 (the message lists the missing, unexpected and mismatched ones).
    """
    path = Path(path).expanduser()
    if not path.is_file():
        raise MissingDataError(f"ResNet-152 weights {path} not found. {_WEIGHTS_HINT}")
    try:
        obj = torch.load(path, map_location="cpu", weights_only=True)
    except (pickle.UnpicklingError, RuntimeError, EOFError, ValueError, OSError) as exc:
        raise MalformedDataError(f"{path} is not a readable PyTorch checkpoint: {exc}") from exc
    sd = _unwrap_state_dict(obj, path)
    # Built on the meta device: every tensor comes from the file, so initialising 60M
    # parameters first would only cost time.
    with torch.device("meta"):
        model = ResNetFeatures(RESNET152_LAYERS, input_size=input_size)
    want = model.state_dict()
    optional = tuple(k for k in want if k.endswith("num_batches_tracked") or k.startswith("fc."))
    missing = [k for k in want if k not in sd and k not in optional]
    unexpected = [k for k in sd if k not in want]
    mismatched = [
        f"{k} {tuple(sd[k].shape)} (want {tuple(want[k].shape)})"
        for k in want
        if k in sd and sd[k].shape != want[k].shape
    ]
    if missing or unexpected or mismatched:
        problems = []
        if missing:
            problems.append(f"missing keys: {_list(missing)}")
        if unexpected:
            problems.append(f"unexpected keys: {_list(unexpected)}")
        if mismatched:
            problems.append(f"shape mismatches: {_list(mismatched)}")
        raise MalformedDataError(
            f"{path} is not a torchvision-layout ResNet-152 state_dict; " + "; ".join(problems)
        )
    for key in optional:
        if key not in sd:
            sd[key] = torch.zeros(want[key].shape, dtype=want[key].dtype)
    model = model.to_empty(device="cpu")
    model.load_state_dict(sd)
    model.eval().requires_grad_(False)
    return model
