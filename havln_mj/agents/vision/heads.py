"""Pretraining read-outs: linear heads predicting simulator ground truth, and their loss."""

from __future__ import annotations

from collections.abc import Mapping

import torch
import torch.nn.functional as F  # noqa: N812 (the usual torch alias)
from torch import Tensor, nn

from havln_mj.agents.vision.inputs import DEPTH_MAX
from havln_mj.errors import InvalidArgumentError

TARGET_KEYS = ("region", "person", "forward", "depth")
# The person fraction is small and its soft-target gradient weak; weighted up so it is learnt
# alongside the others (tuned on a synthetic set where all four are learnable).
DEFAULT_LOSS_WEIGHTS = {"region": 1.0, "person": 10.0, "forward": 1.0, "depth": 1.0}
"""Weights of the view encoder's pretraining loss terms."""


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
    """The multi-task loss of :class:`~.PretrainHeads` predictions.

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
