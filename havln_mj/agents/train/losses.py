"""VLN-CM's losses: teacher forcing on recorded demos, student forcing against the expert.

Both run on the model's device. ``forward`` is the module whose call gives the teacher-forced
logits: the model itself, or a :class:`torch.nn.DataParallel` around it that splits the batch
over several GPUs. Student forcing steps the simulator once per action, so it calls the model
step by step and samples the actions on the CPU with the run's generator (the same draws on
every device).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import torch
from torch import nn

from havln_mj.agents.demos import Demo
from havln_mj.agents.rollouts import EgoRollouts
from havln_mj.agents.vln_cm import START, VLNCM, sequence_loss
from havln_mj.tasks.episodes import Instruction


def _device(model: nn.Module) -> torch.device:
    return next(model.parameters()).device


def pad_demos(demos: Sequence[Demo], device: torch.device | str = "cpu") -> dict[str, torch.Tensor]:
    """Teacher-forcing tensors of demos, padded to the longest, on ``device``."""
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
    arrays = {
        "instruction": np.stack([d.instruction for d in demos]),
        "obs": obs,
        "prev": prev,
        "masks": masks,
        "targets": targets,
        "valid": valid,
    }
    return {k: torch.as_tensor(v).to(device) for k, v in arrays.items()}


def teacher_loss(
    model: VLNCM, demos: Sequence[Demo], forward: nn.Module | None = None
) -> tuple[torch.Tensor, int]:
    """Teacher-forced cross-entropy on demos; the number of steps it covers.

    Args:
        model: The network.
        demos: The demos of the batch.
        forward: What computes the logits (default: ``model``; a data-parallel wrapper).
    """
    b = pad_demos(demos, _device(model))
    logits = (forward or model)(b["instruction"], b["obs"], b["prev"], b["masks"])
    return sequence_loss(logits, b["targets"], b["valid"]), int(b["valid"].sum())


def student_loss(
    model: VLNCM, rollouts: EgoRollouts, instructions: Sequence[Instruction], gen: torch.Generator
) -> tuple[torch.Tensor, int]:
    """Student forcing: sample the agent's actions, learn the expert's at every state reached."""
    dev = _device(model)
    n = len(instructions)
    rollouts.start(instructions)
    ctx, pad, state = model.encode(torch.as_tensor(rollouts.encoded_instructions()).to(dev))
    prev = torch.full((n,), START, dtype=torch.long, device=dev)
    total, steps = torch.zeros((), device=dev), 0
    while not rollouts.done[:n].all():
        obs, masks = rollouts.observe()
        targets = torch.as_tensor(rollouts.expert_actions()[:n]).to(dev)
        running = torch.as_tensor(~rollouts.done[:n]).to(dev)
        logits, state, _ = model.step(
            torch.as_tensor(obs[:n]).to(dev),
            prev,
            state,
            ctx,
            pad,
            torch.as_tensor(masks[:n]).to(dev),
        )
        ce = torch.nn.functional.cross_entropy(logits, targets, reduction="none")
        total = total + (ce * running).sum()
        steps += int(running.sum())
        probs = torch.softmax(logits.detach(), dim=1).cpu()
        sampled = torch.multinomial(probs, 1, generator=gen).squeeze(1)
        actions = np.zeros(rollouts.batch_size, np.int64)
        actions[:n] = sampled.numpy()
        rollouts.step(actions)
        prev = sampled.to(dev)
    return total / max(steps, 1), steps
