"""The view encoder trained on our renders, and batched feature extraction."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F  # noqa: N812 (the usual torch alias)
from torch import Tensor, nn

from havln_mj.agents.vision.inputs import check_rgb, prepare_for, prepare_views
from havln_mj.errors import InvalidArgumentError


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
        in_channels: 4 for RGB-D (:func:`~.prepare_views` with depth), 3 for RGB.
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
        """:func:`~.prepare_views` for this encoder's channels (depth is ignored by RGB models).

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


@torch.no_grad()
def encode_views(
    encoder: nn.Module, rgb: np.ndarray, depth: np.ndarray | None, *, batch_size: int = 256
) -> np.ndarray:
    """Features of many views, batch by batch, in eval mode without gradients.

    Input is prepared by the encoder's own ``prepare(rgb, depth)`` when it has one
    (:class:`~.ViewEncoder`, :class:`~.ResNetFeatures`), else by :func:`~.prepare_views`. The
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
    rgb = check_rgb(rgb)
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
            x = prepare_for(encoder, rgb[sl], None if depth is None else depth[sl])
            out.append(encoder(x).float().cpu().numpy())
    finally:
        encoder.train(was_training)
    if not out:
        return np.zeros((0, int(getattr(encoder, "out_dim", 0))), np.float32)
    return np.concatenate(out).astype(np.float32, copy=False)
