"""What one scored episode holds: reference path, agent trajectory and the people around."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from havln_mj.errors import InvalidArgumentError, MalformedDataError, did_you_mean
from havln_mj.tasks.metrics.trajectory import Step, parse_trajectory

# HA-R2R's ``human_rel_pos`` labels (HA3D ``getRelPos``).
REL_POSITIONS: tuple[str, ...] = ("Beginning", "Obstacle", "Around", "End")


@dataclass(frozen=True)
class Person:
    """A person of the episode, as far as the collision adjustment needs one.

    Attributes:
        viewpoint: The viewpoint the person stands on (HA-R2R ``human_viewpoint``), or None.
        rel_pos: HA-R2R ``human_rel_pos``: one of ``REL_POSITIONS``, or None when unknown.
        position: (x, y, z) in metres; overrides the viewpoint's position when given.
    """

    viewpoint: str | None = None
    rel_pos: str | None = None
    position: tuple[float, float, float] | None = None

    def __post_init__(self) -> None:
        if self.viewpoint is None and self.position is None:
            raise InvalidArgumentError("a Person needs a viewpoint or a position")
        if self.viewpoint is not None and (
            not isinstance(self.viewpoint, str) or not self.viewpoint
        ):
            raise InvalidArgumentError(
                f"person viewpoint must be a non-empty string, got {self.viewpoint!r}"
            )
        if self.rel_pos is not None and self.rel_pos not in REL_POSITIONS:
            raise InvalidArgumentError(
                f"human_rel_pos must be one of {REL_POSITIONS}, got {self.rel_pos!r}"
                f"{did_you_mean(str(self.rel_pos), REL_POSITIONS)}"
            )
        if self.position is not None:
            pos = tuple(self.position)
            ok = len(pos) == 3 and all(
                isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
                for v in pos
            )
            if not ok:
                raise InvalidArgumentError(
                    f"person position must be 3 finite numbers, got {self.position!r}"
                )
            object.__setattr__(self, "position", tuple(float(v) for v in pos))


@dataclass(frozen=True)
class EvalEpisode:
    """One agent run to score against its reference path.

    Attributes:
        episode_id: A name for reports (R2R: ``"<path_id>_<instruction index>"``).
        scan: The scan id, used to pick the navigation graph.
        reference_path: The ground-truth viewpoints, start first, goal last.
        trajectory: The agent's steps; the first must stand on the reference start.
        people: The episode's people (HA-R2R ``human``), for the critical adjustment.
        crux_points: HA-R2R ``crux_points`` (the path's critical nodes), or None to compute
            them from the graph.
    """

    episode_id: str
    scan: str
    reference_path: tuple[str, ...]
    trajectory: tuple[Step, ...]
    people: tuple[Person, ...] = ()
    crux_points: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        path = _viewpoints(self.reference_path, "reference_path")
        if not path:
            raise InvalidArgumentError(f"episode {self.episode_id}: reference_path is empty")
        object.__setattr__(self, "reference_path", path)
        traj = parse_trajectory(self.trajectory)
        if traj[0].viewpoint != path[0]:
            # R2R's eval asserts the same: a trajectory must include the start position.
            raise InvalidArgumentError(
                f"episode {self.episode_id}: trajectory starts at {traj[0].viewpoint!r}, "
                f"but the reference path starts at {path[0]!r}"
            )
        object.__setattr__(self, "trajectory", traj)
        people = tuple(self.people)
        if not all(isinstance(p, Person) for p in people):
            raise InvalidArgumentError(f"episode {self.episode_id}: people must be Person objects")
        object.__setattr__(self, "people", people)
        if self.crux_points is not None:
            object.__setattr__(self, "crux_points", _viewpoints(self.crux_points, "crux_points"))

    @property
    def start(self) -> str:
        """The reference start viewpoint."""
        return self.reference_path[0]

    @property
    def goal(self) -> str:
        """The reference goal viewpoint."""
        return self.reference_path[-1]

    @classmethod
    def from_ha_r2r(
        cls, item: Mapping[str, Any] | Any, trajectory: Iterable[Any], episode_id: str | None = None
    ) -> EvalEpisode:
        """Builds an episode from an R2R or HA-R2R dataset entry and an agent trajectory.

        Args:
            item: The dataset entry: a JSON mapping (``scan``, ``path``, ``path_id``; HA-R2R
                also ``human`` and ``crux_points``) or a record with attributes ``scan``,
                ``path``, ``path_id`` and optionally ``humans`` (each with ``viewpoint`` and
                ``rel_pos``) and ``crux_points``, such as ``havln_mj.tasks.datasets.Episode``.
            trajectory: The agent's steps, in any form ``parse_step`` reads.
            episode_id: The report name; defaults to ``str(path_id)``.

        Raises:
            MalformedDataError: The entry lacks a field or a ``human`` entry is malformed.
            InvalidArgumentError: The trajectory is bad or does not start at the path start.
        """
        try:
            if isinstance(item, Mapping):
                scan, path, path_id = item["scan"], item["path"], item["path_id"]
                people = tuple(
                    Person(h["human_viewpoint"], h.get("human_rel_pos"))
                    for h in item.get("human") or ()
                )
                crux = item.get("crux_points")
            else:
                scan, path, path_id = item.scan, item.path, item.path_id
                humans = getattr(item, "humans", None) or ()
                people = tuple(Person(h.viewpoint, h.rel_pos) for h in humans)
                crux = getattr(item, "crux_points", None)
        except (KeyError, TypeError, AttributeError) as err:
            raise MalformedDataError(
                f"dataset entry {item!r:.200} lacks a field or is malformed ({err!r}); entries "
                "need 'scan', 'path' and 'path_id', HA-R2R 'human' entries 'human_viewpoint' "
                "and 'human_rel_pos'"
            ) from None
        name = episode_id if episode_id is not None else str(path_id)
        return cls(name, scan, tuple(path), tuple(trajectory), people, crux)


def episodes_from_submission(
    submission: Iterable[Mapping[str, Any]],
    dataset: Iterable[Mapping[str, Any]],
    require_all: bool = True,
) -> list[EvalEpisode]:
    """Pairs an R2R-format submission with its (HA-)R2R dataset entries.

    Args:
        submission: ``[{"instr_id": "<path_id>_<k>", "trajectory": [...]}, ...]``.
        dataset: The split's entries.
        require_all: Every instruction of the dataset must have a trajectory, as R2R's eval
            demands.

    Returns:
        One episode per submission entry, in submission order.

    Raises:
        InvalidArgumentError: An ``instr_id`` is unknown, repeated, or (with ``require_all``)
            missing.
        MalformedDataError: An entry lacks ``instr_id`` or ``trajectory``.
    """
    by_path: dict[str, Mapping[str, Any]] = {}
    expected: set[str] = set()
    for item in dataset:
        by_path[str(item["path_id"])] = item
        expected.update(f"{item['path_id']}_{k}" for k in range(len(item.get("instructions", ()))))
    episodes: list[EvalEpisode] = []
    seen: set[str] = set()
    for entry in submission:
        if "instr_id" not in entry or "trajectory" not in entry:
            raise MalformedDataError(
                f"submission entry needs 'instr_id' and 'trajectory', got keys {sorted(entry)}"
            )
        instr_id = str(entry["instr_id"])
        path_id = instr_id.rsplit("_", 1)[0]
        if path_id not in by_path or (expected and instr_id not in expected):
            raise InvalidArgumentError(
                f"unknown instr_id {instr_id!r}: not '<path_id>_<k>' of this split"
                f"{did_you_mean(instr_id, expected)}"
            )
        if instr_id in seen:
            raise InvalidArgumentError(f"instr_id {instr_id!r} appears twice in the submission")
        seen.add(instr_id)
        episodes.append(EvalEpisode.from_ha_r2r(by_path[path_id], entry["trajectory"], instr_id))
    missing = expected - seen
    if require_all and missing:
        raise InvalidArgumentError(
            f"submission lacks {len(missing)} of {len(expected)} instructions, e.g. "
            f"{sorted(missing)[:3]}; pass require_all=False to score a subset"
        )
    return episodes


def _viewpoints(value: Any, name: str) -> tuple[str, ...]:
    if isinstance(value, str) or not isinstance(value, Sequence | Iterable):
        raise InvalidArgumentError(f"{name} must be a sequence of viewpoint ids, got {value!r}")
    vps = tuple(value)
    if not all(isinstance(v, str) and v for v in vps):
        raise InvalidArgumentError(f"{name} must hold non-empty viewpoint id strings, got {vps!r}")
    return vps
