"""The ImageNet bottleneck ResNet (torchvision's layout) and loading a user's ResNet-152."""

from __future__ import annotations

import pickle
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import Tensor, nn

from havln_mj.agents.vision.inputs import prepare_imagenet
from havln_mj.errors import MalformedDataError, MissingDataError


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

    Its state_dict keys are torchvision's. ``prepare`` applies :func:`~.prepare_imagenet`
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
        A :class:`~.ResNetFeatures` in eval mode with gradients off (``requires_grad_(True)``
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
