"""A training run's configuration: the JSON config's keys, checked against what reads them.

Every section is checked before anything is built: top-level keys against
:class:`TrainConfig`, ``model`` against the agent's model dataclass
(:class:`~havln_mj.agents.vln_cm.CMConfig` / :class:`~.DTConfig`, less
the sizes the data set), ``model.text`` against the text encoder's arguments, ``features``
against :class:`~havln_mj.agents.featurize.FeatureSpec` with ``features.view`` against
:class:`~havln_mj.agents.views.ViewConfig` and ``features.encoder`` against
:class:`~.ViewEncoder`, and the splits against their two forms. A bad
key raises :class:`~havln_mj.errors.InvalidArgumentError` naming the dotted key and the valid
ones; a bad value raises the model's own error, before any rendering starts.
"""

from __future__ import annotations

import dataclasses
import inspect
import json
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from havln_mj.agents.checkpoint import AGENTS
from havln_mj.agents.featurize import FeatureSpec
from havln_mj.agents.views import ViewConfig
from havln_mj.errors import InvalidArgumentError, MissingDataError, did_you_mean
from havln_mj.paths import project_home

FEEDBACKS = ("teacher", "sample", "mixed")
DATA_SIZES = ("vocab_size", "obs_dim")  # model sizes the training data sets
SPLIT_KEYS = ("scenes", "per_scene", "skip", "dataset")
TEXT_KEYS = ("d_model", "n_layers", "n_heads", "max_len", "dropout")
BERT_KEYS = ("bert", "vocab", "d_model", "max_len")


def check_keys(section: str, given: Mapping[str, Any], valid: Iterable[str]) -> None:
    """Raises InvalidArgumentError naming the first key of ``given`` not in ``valid``.

    Args:
        section: Dotted name of the section (``""`` for the top level).
        given: The section's keys and values.
        valid: Its valid keys.
    """
    if not isinstance(given, Mapping):
        raise InvalidArgumentError(
            f"config section {section or 'top level'!r} must be an object of keys, got "
            f"{type(given).__name__} {given!r}"
        )
    valid = sorted(valid)
    for key in given:
        if key not in valid:
            name = f"{section}.{key}" if section else key
            raise InvalidArgumentError(
                f"unknown config key {name!r}; valid keys of "
                f"{section or 'the top level'}: {', '.join(valid)}.{did_you_mean(key, valid)}"
            )


def _fields(cls: type) -> list[str]:
    return [f.name for f in dataclasses.fields(cls)]


def _model_class(agent: str) -> type:
    if agent == "vln_cm":
        from havln_mj.agents.vln_cm import CMConfig

        return CMConfig
    from havln_mj.agents.vln_dt import DTConfig

    return DTConfig


def resolved_model(agent: str, model: Mapping[str, Any]) -> dict[str, Any]:
    """The ``model`` section checked and completed with the model's defaults.

    Raises:
        InvalidArgumentError: An unknown key (named with the valid ones) or a bad value.
    """
    cls = _model_class(agent)
    check_keys("model", model, [n for n in _fields(cls) if n not in DATA_SIZES])
    text = model.get("text")
    if text is not None:
        check_keys("model.text", text, BERT_KEYS if "bert" in text else TEXT_KEYS)
    full = dataclasses.asdict(cls(**dict.fromkeys(DATA_SIZES, 1), **model))
    return {k: v for k, v in full.items() if k not in DATA_SIZES}


def resolved_features(features: Mapping[str, Any]) -> dict[str, Any]:
    """The ``features`` section checked and completed with the feature defaults.

    Raises:
        InvalidArgumentError: An unknown key (named with the valid ones) or a bad value.
    """
    from havln_mj.agents.vision import ViewEncoder

    check_keys("features", features, [n for n in _fields(FeatureSpec) if n != "seed"])
    check_keys("features.view", features.get("view", {}), _fields(ViewConfig))
    params = inspect.signature(ViewEncoder).parameters
    defaults = {k: p.default for k, p in params.items() if k != "in_channels"}
    check_keys("features.encoder", features.get("encoder", {}), defaults)
    encoder = {k: list(v) if isinstance(v, tuple) else v for k, v in defaults.items()}
    spec = FeatureSpec.from_dict(
        {**features, "encoder": {**encoder, **features.get("encoder", {})}}
    )
    out = dataclasses.asdict(spec)
    out.pop("seed")  # the run's people seed
    return out


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
        for name in ("train", "val"):
            if getattr(self, name) is not None:
                check_keys(name, getattr(self, name), SPLIT_KEYS)
        resolved_model(self.agent, self.model)
        resolved_features(self.features)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> TrainConfig:
        """From a config dict, naming an unknown key and the valid ones.

        Raises:
            InvalidArgumentError: An unknown key or a bad value, in any section.
        """
        check_keys("", d, _fields(cls))
        if "agent" not in d or "train" not in d:
            raise InvalidArgumentError("a training config needs 'agent' and 'train' keys")
        return cls(**d)

    def resolved(self) -> dict[str, Any]:
        """Every setting with the defaults filled in (``model``, ``features`` included).

        It reads back through :meth:`from_dict` to the same run.
        """
        out = dataclasses.asdict(self)
        out["model"] = resolved_model(self.agent, self.model)
        out["features"] = resolved_features(self.features)
        return out


def _parse_override(item: str) -> tuple[list[str], Any]:
    key, sep, value = item.partition("=")
    if not sep or not key:
        raise InvalidArgumentError(f"override {item!r} is not key=value")
    try:
        return key.split("."), json.loads(value)
    except json.JSONDecodeError:
        return key.split("."), value


def apply_overrides(d: dict, overrides: Sequence[str]) -> dict:
    """``d`` with each ``key=value`` set (dotted keys reach into sections; values as JSON).

    Raises:
        InvalidArgumentError: An override without ``=``, or a dotted key through a value that
            is not a section.
    """
    for item in overrides:
        keys, value = _parse_override(item)
        target = d
        for depth, key in enumerate(keys[:-1]):
            if target.get(key) is None:
                target[key] = {}
            target = target[key]
            if not isinstance(target, dict):
                where = ".".join(keys[: depth + 1])
                raise InvalidArgumentError(f"override {item!r}: {where!r} is not a section")
        target[keys[-1]] = value
    return d


def _config_path(path: Path) -> Path:
    path = Path(path).expanduser()
    if not path.is_file() and len(path.parts) == 1:  # a built-in config by name
        builtin = project_home() / "agents" / "configs" / path.with_suffix(".json").name
        path = builtin if builtin.is_file() else path
    if not path.is_file():
        raise MissingDataError(
            f"config file {path} does not exist; give a file or a name from agents/configs/ "
            "(vln_cm, vln_dt, vln_cm_small, vln_dt_small, vln_cm_smoke, ...)"
        )
    return path


def read_config(path: Path, agent: str | None, overrides: Sequence[str]) -> TrainConfig:
    """A config file (or a built-in config's name) with ``key=value`` overrides.

    Override values are parsed as JSON when they parse, else taken as strings.

    Raises:
        MissingDataError: No such file.
        InvalidArgumentError: Bad JSON, an override without ``=``, an unknown key in any
            section (named with the valid ones), or an agent mismatch.
    """
    path = _config_path(path)
    try:
        d = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise InvalidArgumentError(f"config {path} is not valid JSON: {exc}") from None
    d = apply_overrides(d, overrides)
    if agent is not None:
        if d.get("agent", agent) != agent:
            raise InvalidArgumentError(
                f"--agent {agent} but the config {path} is for {d['agent']!r}"
            )
        d["agent"] = agent
    return TrainConfig.from_dict(d)
