"""Where an agent's episodes come from: procedural houses or R2R / HA-R2R files.

A split is given in a config as either

* ``{"scenes": ["proc-0:40"], "per_scene": 20, "skip": 0}``: paths generated in procedural
  houses (``"proc-A:B"`` stands for ``proc-A`` … ``proc-(B-1)``; ``skip`` leaves out each
  house's first paths, so ``skip: 20`` after a 20-path train split gives new paths in the same
  houses: val_seen), or
* ``{"dataset": "HA_val_seen"}``: an R2R / HA-R2R file or split name
  (:func:`havln_mj.tasks.datasets.load_dataset`; real scans need the connectivity folder).

The people seed is the run's; procedural people and features use it too.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

from havln_mj.errors import InvalidArgumentError
from havln_mj.scene.ids import expand_scene_ranges
from havln_mj.tasks.datasets import load_dataset
from havln_mj.tasks.episodes import Episode, Instruction
from havln_mj.tasks.procedural import procedural_episodes


def split_episodes(
    spec: Mapping,
    seed: int,
    *,
    connectivity_dir: str | Path | None = None,
    data_dir: str | Path | None = None,
) -> list[Episode]:
    """The episodes a split spec names (see the module docstring).

    Raises:
        InvalidArgumentError: The spec names neither scenes nor a dataset, or has unknown keys.
    """
    keys = set(spec)
    if "scenes" in keys and keys <= {"scenes", "per_scene", "skip"}:
        scenes = expand_scene_ranges(spec["scenes"])
        return procedural_episodes(
            scenes, int(spec.get("per_scene", 20)), seed, int(spec.get("skip", 0))
        )
    if keys == {"dataset"}:
        data = load_dataset(spec["dataset"], connectivity_dir=connectivity_dir, data_dir=data_dir)
        return list(data.episodes)
    raise InvalidArgumentError(
        f"split spec {dict(spec)!r}; valid: {{'scenes': [...], 'per_scene': N, 'skip': K}} "
        "or {'dataset': FILE_OR_SPLIT}"
    )


def instructions_of(episodes: Sequence[Episode]) -> list[Instruction]:
    """Every instruction of ``episodes``, in order."""
    return [ins for e in episodes for ins in e.instruction_items()]


def scans_of(episodes: Sequence[Episode]) -> list[str]:
    """The scans ``episodes`` visit, in first-seen order."""
    return list(dict.fromkeys(e.scan for e in episodes))
