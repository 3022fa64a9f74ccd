"""A learned GO1 policy as a small numpy MLP, read from a ``.npz`` file.

The file holds (``allow_pickle`` off, every entry a plain array):

* ``format_version``: ``FORMAT_VERSION``;
* ``spec``: the JSON of the :class:`~havln_mj.robot.go1.learned.observation.PolicySpec` the
  policy was trained with (observation layout, action scale, policy rate);
* ``train_config``: the JSON of the training configuration (for the record);
* ``obs_mean``, ``obs_std``: the observation normalisation (the policy sees
  ``clip((obs - mean) / std, ±clip_obs)``);
* ``w0, b0, w1, b1, ...``: the layers (``w`` of shape ``(out, in)``), ELU between them and
  none after the last, whose output is the action.

Evaluation is deterministic: the mean action, no sampling.
"""

from __future__ import annotations

import json
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from havln_mj.errors import MalformedDataError, MissingDataError
from havln_mj.paths import asset_path
from havln_mj.robot.go1.learned.observation import PolicySpec

FORMAT_VERSION = 1
SHIPPED = ("robots", "go1", "policy.npz")
"""Where the shipped policy lies (:func:`havln_mj.paths.asset_path` parts)."""


@dataclass(frozen=True)
class LearnedPolicy:
    """An MLP from normalised observations to actions.

    Attributes:
        spec: What the policy observes and how its action is applied.
        weights: Layer matrices, each ``(out, in)``.
        biases: Layer biases.
        obs_mean: Observation mean.
        obs_std: Observation standard deviation.
        train_config: The training configuration it came from (a JSON object).
    """

    spec: PolicySpec
    weights: tuple[np.ndarray, ...]
    biases: tuple[np.ndarray, ...]
    obs_mean: np.ndarray
    obs_std: np.ndarray
    train_config: dict

    def act(self, obs: np.ndarray) -> np.ndarray:
        """The action (clipped to ``±spec.clip_actions``) for one observation vector."""
        c = self.spec.clip_obs
        x = np.clip((np.asarray(obs, dtype=np.float64) - self.obs_mean) / self.obs_std, -c, c)
        last = len(self.weights) - 1
        for k, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            x = w @ x + b
            if k < last:
                x = np.where(x > 0.0, x, np.expm1(np.minimum(x, 0.0)))  # ELU
        a = self.spec.clip_actions
        return np.clip(x, -a, a)

    def save(self, path: str | Path) -> None:
        """Writes the policy (to a temporary file first, then moved into place)."""
        path = Path(path)
        arrays: dict[str, np.ndarray] = {
            "format_version": np.array(FORMAT_VERSION),
            "spec": np.array(json.dumps(self.spec.to_json())),
            "train_config": np.array(json.dumps(self.train_config)),
            "obs_mean": self.obs_mean.astype(np.float32),
            "obs_std": self.obs_std.astype(np.float32),
        }
        for k, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            arrays[f"w{k}"], arrays[f"b{k}"] = w.astype(np.float32), b.astype(np.float32)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.name + ".tmp")
        with open(tmp, "wb") as f:
            np.savez(f, **arrays)
        tmp.replace(path)


def load_policy(path: str | Path | None = None) -> LearnedPolicy:
    """Reads a policy file (default: the shipped ``robots/go1/policy.npz``).

    Raises:
        MissingDataError: No file there.
        MalformedDataError: Not a policy file of this format version, or its arrays disagree.
    """
    path = Path(path) if path is not None else asset_path(*SHIPPED)
    if not path.is_file():
        raise MissingDataError(f"GO1 policy file not found: {path}")
    try:
        with np.load(path, allow_pickle=False) as z:
            raw = {k: z[k] for k in z.files}
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as err:
        raise MalformedDataError(f"{path} is not a GO1 policy .npz file: {err}") from err
    missing = [
        k for k in ("format_version", "spec", "obs_mean", "obs_std", "w0", "b0") if k not in raw
    ]
    if missing:
        raise MalformedDataError(f"{path}: policy file lacks {missing}; has {sorted(raw)}")
    version = int(raw["format_version"])
    if version != FORMAT_VERSION:
        raise MalformedDataError(
            f"{path}: policy format version {version}, this runtime reads {FORMAT_VERSION}"
        )
    try:
        spec = PolicySpec.from_json(json.loads(str(raw["spec"])))
        config = json.loads(str(raw.get("train_config", "{}")))
    except (json.JSONDecodeError, TypeError) as err:
        raise MalformedDataError(f"{path}: bad policy spec: {err}") from err
    n = sum(1 for k in raw if k.startswith("w"))
    weights = tuple(raw[f"w{k}"].astype(np.float64) for k in range(n))
    biases = tuple(raw.get(f"b{k}", np.zeros(0)).astype(np.float64) for k in range(n))
    mean, std = raw["obs_mean"].astype(np.float64), raw["obs_std"].astype(np.float64)
    _check_shapes(path, spec, weights, biases, mean, std)
    return LearnedPolicy(spec, weights, biases, mean, std, config)


def _check_shapes(path, spec: PolicySpec, weights, biases, mean, std) -> None:
    size = spec.obs_size
    if mean.shape != (size,) or std.shape != (size,) or not np.all(std > 0):
        raise MalformedDataError(
            f"{path}: observation normalisation must be {size} values (std > 0), got "
            f"{mean.shape} and {std.shape}"
        )
    n_in = size
    for k, (w, b) in enumerate(zip(weights, biases, strict=True)):
        if w.ndim != 2 or w.shape[1] != n_in or b.shape != (w.shape[0],):
            raise MalformedDataError(
                f"{path}: layer {k} has w {w.shape}, b {b.shape}; expected ({'n'}, {n_in})"
            )
        if not (np.all(np.isfinite(w)) and np.all(np.isfinite(b))):
            raise MalformedDataError(f"{path}: layer {k} holds non-finite weights")
        n_in = w.shape[0]
    if n_in != spec.action_size:
        raise MalformedDataError(f"{path}: the last layer gives {n_in} actions, need 12")
