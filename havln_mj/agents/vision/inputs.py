"""Rendered views as network input: our RGB-D convention and ImageNet's normalisation."""

from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F  # noqa: N812 (the usual torch alias)
from torch import Tensor, nn

from havln_mj.errors import InvalidArgumentError

DEPTH_MAX = 10.0  # metres; depth inputs and targets are clipped here (views.MAX_DEPTH)
IMAGENET_MEAN = (0.485, 0.456, 0.406)
IMAGENET_STD = (0.229, 0.224, 0.225)


def check_rgb(rgb: np.ndarray) -> np.ndarray:
    """``rgb`` as an array; raises InvalidArgumentError unless it is uint8 ``(N, H, W, 3)``."""
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
    """Turns rendered views into :class:`~.ViewEncoder` input.

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
    rgb = check_rgb(rgb)
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
    rgb = check_rgb(rgb)
    x = _rgb_tensor(rgb).mul_(1.0 / 255.0)
    if size is not None and tuple(size) != tuple(x.shape[-2:]):
        x = F.interpolate(x, size=tuple(size), mode="bilinear", align_corners=False, antialias=True)
    mean = torch.tensor(IMAGENET_MEAN).view(1, 3, 1, 1)
    std = torch.tensor(IMAGENET_STD).view(1, 3, 1, 1)
    return (x - mean) / std


def device_of(module: nn.Module) -> torch.device:
    """The device of the module's first parameter (CPU for a module without any)."""
    param = next(module.parameters(), None)
    return param.device if param is not None else torch.device("cpu")


def prepare_for(encoder: nn.Module, rgb: np.ndarray, depth: np.ndarray | None) -> Tensor:
    """The encoder's own ``prepare`` (else :func:`~.prepare_views`), on the encoder's device."""
    prepare = getattr(encoder, "prepare", None)
    x = prepare(rgb, depth) if prepare is not None else prepare_views(rgb, depth)
    return x.to(device_of(encoder))
