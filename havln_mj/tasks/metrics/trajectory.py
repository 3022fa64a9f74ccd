"""An agent's trajectory: one record per step, parsed from R2R, HA3D or richer formats."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from havln_mj.errors import InvalidArgumentError

# Keys a step mapping may use for HA3D's per-step collision flag (spelled as in HA3D).
_FLAG_KEYS = ("collided", "is_crushed", "isCrushed", "isCrashed")


@dataclass(frozen=True)
class Step:
    """The agent's state after one step (the first step is the start state).

    Attributes:
        viewpoint: The viewpoint id the agent stands on.
        heading: Heading in radians.
        elevation: Elevation in radians.
        collided: Whether a person was within the collision radius at this step.
        collided_people: Ids of the people hit at this step, when known; a non-empty tuple
            implies ``collided``.
    """

    viewpoint: str
    heading: float = 0.0
    elevation: float = 0.0
    collided: bool = False
    collided_people: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.viewpoint, str) or not self.viewpoint:
            raise InvalidArgumentError(
                f"step viewpoint must be a non-empty string, got {self.viewpoint!r}"
            )
        for name in ("heading", "elevation"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise InvalidArgumentError(f"step {name} must be a number, got {value!r}")
            if not math.isfinite(value):
                raise InvalidArgumentError(f"step {name} must be finite, got {value!r}")
            object.__setattr__(self, name, float(value))
        people = _people_ids(self.collided_people)
        object.__setattr__(self, "collided_people", people)
        object.__setattr__(self, "collided", _flag(self.collided) or bool(people))


def parse_step(raw: Any) -> Step:
    """Reads one step record.

    Accepted forms: a ``Step``; a viewpoint id; ``[vp, heading, elevation]`` (R2R
    submission); ``[vp, heading, elevation, flag]`` where ``flag`` is HA3D's ``isCrashed``
    (0/1 or bool) or a sequence of the people ids hit; a mapping with ``viewpoint`` and
    optional ``heading``, ``elevation``, ``collided_people`` and a collision flag under
    ``collided``, ``is_crushed``, ``isCrushed`` or ``isCrashed``.

    Raises:
        InvalidArgumentError: The record has none of these forms or holds bad values.
    """
    if isinstance(raw, Step):
        return raw
    if isinstance(raw, str):
        return Step(raw)
    if isinstance(raw, Mapping):
        if "viewpoint" not in raw:
            raise InvalidArgumentError(f"step mapping needs a 'viewpoint' key, got {dict(raw)!r}")
        flags = [raw[k] for k in _FLAG_KEYS if k in raw]
        return Step(
            raw["viewpoint"],
            raw.get("heading", 0.0),
            raw.get("elevation", 0.0),
            any(_flag(f) for f in flags),
            tuple(raw.get("collided_people", ())),
        )
    if isinstance(raw, Sequence) and len(raw) in (3, 4):
        vp, heading, elevation = raw[0], raw[1], raw[2]
        if len(raw) == 3:
            return Step(vp, heading, elevation)
        extra = raw[3]
        if isinstance(extra, Sequence) and not isinstance(extra, str):
            return Step(vp, heading, elevation, collided_people=tuple(extra))
        return Step(vp, heading, elevation, _flag(extra))
    raise InvalidArgumentError(
        f"cannot read step {raw!r}: expected a viewpoint id, [vp, heading, elevation], "
        "[vp, heading, elevation, collision flag or people ids], a mapping or a Step"
    )


def parse_trajectory(raw: Iterable[Any]) -> tuple[Step, ...]:
    """Reads a whole trajectory with ``parse_step``.

    Raises:
        InvalidArgumentError: The trajectory is empty, not a sequence, or a step is bad (the
            message names the step index).
    """
    if isinstance(raw, str | bytes | Mapping) or not isinstance(raw, Iterable):
        raise InvalidArgumentError(f"trajectory must be a sequence of steps, got {raw!r}")
    steps = []
    for i, item in enumerate(raw):
        try:
            steps.append(parse_step(item))
        except InvalidArgumentError as err:
            raise InvalidArgumentError(f"trajectory step {i}: {err}") from None
    if not steps:
        raise InvalidArgumentError("trajectory is empty: it must hold at least the start step")
    return tuple(steps)


def visited_path(steps: Sequence[Step]) -> list[str]:
    """The viewpoints visited, with consecutive repeats (turns, look-ups) merged."""
    path: list[str] = []
    for step in steps:
        if not path or path[-1] != step.viewpoint:
            path.append(step.viewpoint)
    return path


def _flag(value: Any) -> bool:
    # HA3D stores isCrushed as int(min_distance <= 1); accept 0/1 and bools only.
    if isinstance(value, bool):
        return value
    if isinstance(value, int) and value in (0, 1):
        return bool(value)
    raise InvalidArgumentError(f"collision flag must be a bool or 0/1, got {value!r}")


def _people_ids(value: Any) -> tuple[int, ...]:
    if isinstance(value, str) or not isinstance(value, Iterable):
        raise InvalidArgumentError(f"collided_people must be a sequence of ints, got {value!r}")
    ids = tuple(value)
    if not all(isinstance(i, int) and not isinstance(i, bool) and i >= 0 for i in ids):
        raise InvalidArgumentError(f"collided_people must hold ints >= 0, got {value!r}")
    return ids
