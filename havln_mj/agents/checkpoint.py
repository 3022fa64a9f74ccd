"""Agent checkpoints: one file with everything needed to run, evaluate or resume an agent.

A checkpoint holds the agent kind (``vln_cm`` / ``vln_dt``), the model's configuration and
weights, the instruction vocabulary, the view encoder (configuration and weights) with the
feature settings, and for resuming the training configuration, iteration, optimiser state,
generator states and loss history (a released checkpoint, :meth:`AgentBundle.released`, keeps
the configuration, iteration and history only). Files are written atomically. The trained
checkpoints shipped in ``agents/`` load by name (:func:`resolve_checkpoint`).
"""

from __future__ import annotations

import dataclasses
import io
import pickle
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import torch
from torch import nn

from havln_mj.agents.featurize import FeatureSpec
from havln_mj.agents.vision import ViewEncoder
from havln_mj.cache import atomic_write_bytes
from havln_mj.errors import MalformedDataError, MissingDataError
from havln_mj.paths import project_home
from havln_mj.tasks.vocab import Vocabulary

FORMAT = "havln_mj-agent-1"
AGENTS = ("vln_cm", "vln_dt")
# What a released checkpoint keeps of the training state: enough to tell how it was made.
RELEASE_STATE = ("config", "iteration", "history", "best")


def shipped_checkpoints() -> list[Path]:
    """The trained checkpoints shipped in the project's ``agents/`` folder."""
    try:
        return sorted((project_home() / "agents").glob("*.pt"))
    except MissingDataError:
        return []


def resolve_checkpoint(path: str | Path) -> Path:
    """The checkpoint file ``path`` names.

    A path that exists is taken as it is; a relative one that does not is looked up in the
    project home (``agents/vln_cm_small.pt``) and in its ``agents/`` folder
    (``vln_cm_small.pt``), so the shipped checkpoints load from any working directory.

    Raises:
        MissingDataError: No such file; the message lists the shipped checkpoints.
    """
    given = Path(path).expanduser()
    if given.is_file():
        return given
    if not given.is_absolute():
        try:
            home = project_home()
        except MissingDataError:
            home = None
        for candidate in () if home is None else (home / given, home / "agents" / given):
            if candidate.is_file():
                return candidate
    shipped = ", ".join(f"agents/{p.name}" for p in shipped_checkpoints()) or "none found"
    raise MissingDataError(
        f"agent checkpoint {given} does not exist; train one with `python -m "
        f"havln_mj.agents.train --config vln_cm_small --out runs/cm` (then runs/cm/best.pt), "
        f"or use a shipped one: {shipped}"
    )


def build_model(agent: str, config: dict) -> nn.Module:
    """A fresh network of ``agent`` from its configuration dict.

    Raises:
        MalformedDataError: Unknown agent kind.
    """
    if agent == "vln_cm":
        from havln_mj.agents.vln_cm import VLNCM, CMConfig

        return VLNCM(CMConfig(**config))
    if agent == "vln_dt":
        from havln_mj.agents.vln_dt import DecisionTransformer, DTConfig

        return DecisionTransformer(DTConfig(**config))
    raise MalformedDataError(f"unknown agent kind {agent!r}; valid: {', '.join(AGENTS)}")


@dataclass
class AgentBundle:
    """A trained (or training) agent and what it observes with.

    Attributes:
        agent: ``"vln_cm"`` or ``"vln_dt"``.
        model: The network.
        model_config: Its configuration (``CMConfig`` / ``DTConfig`` fields).
        vocab: The instruction vocabulary.
        encoder: The view encoder its features come from (ours, or a user's ResNet-152).
        features: How the features are rendered.
        state: Training state for resuming (iteration, optimiser, generators, history, config).
    """

    agent: str
    model: nn.Module
    model_config: dict
    vocab: Vocabulary
    encoder: nn.Module
    features: FeatureSpec
    state: dict[str, Any] = field(default_factory=dict)

    def released(self) -> AgentBundle:
        """This agent without what only resuming needs (optimiser and generator states).

        What stays is what evaluating needs, plus the training configuration, iteration,
        history and best score; the optimiser's two moments per weight go.
        """
        state = {k: self.state[k] for k in RELEASE_STATE if k in self.state}
        return dataclasses.replace(self, state=state)

    def save(self, path: str | Path) -> None:
        """Writes the checkpoint atomically."""
        spec = asdict(self.features)
        blob = {
            "format": FORMAT,
            "agent": self.agent,
            "model_config": self.model_config,
            "state_dict": self.model.state_dict(),
            "vocab": list(self.vocab.tokens),
            # A user's ResNet-152 is referenced by its file (the spec), not copied (230 MB).
            "encoder": (
                {"config": self.encoder.config(), "state_dict": self.encoder.state_dict()}
                if isinstance(self.encoder, ViewEncoder)
                else None
            ),
            "features": spec,
            "state": self.state,
        }
        buf = io.BytesIO()
        torch.save(blob, buf)
        atomic_write_bytes(Path(path), buf.getvalue())

    @classmethod
    def load(cls, path: str | Path) -> AgentBundle:
        """Reads a checkpoint.

        ``path`` is resolved by :func:`resolve_checkpoint` (shipped checkpoints by name).

        Raises:
            MissingDataError: No such file.
            MalformedDataError: Not an agent checkpoint, or a damaged one.
        """
        path = resolve_checkpoint(path)
        try:
            blob = torch.load(path, map_location="cpu", weights_only=False)
        except (RuntimeError, EOFError, OSError, ValueError, pickle.UnpicklingError) as exc:
            raise MalformedDataError(f"{path} cannot be read as a checkpoint: {exc}") from None
        if not isinstance(blob, dict) or blob.get("format") != FORMAT:
            raise MalformedDataError(f"{path} is not a havln_mj agent checkpoint ({FORMAT})")
        try:
            model = build_model(blob["agent"], blob["model_config"])
            model.load_state_dict(blob["state_dict"])
            features = FeatureSpec.from_dict(blob["features"])
            encoder = features.fixed_encoder()
            if encoder is None:
                encoder = ViewEncoder.from_config(blob["encoder"]["config"])
                encoder.load_state_dict(blob["encoder"]["state_dict"])
        except (KeyError, TypeError, RuntimeError) as exc:
            raise MalformedDataError(f"checkpoint {path} is damaged: {exc}") from None
        return cls(
            blob["agent"],
            model.eval(),
            blob["model_config"],
            Vocabulary(blob["vocab"]),
            encoder.eval(),
            features,
            blob.get("state") or {},
        )
