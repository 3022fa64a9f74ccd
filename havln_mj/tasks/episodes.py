"""R2R and HA-R2R episodes in memory: paths, their instructions and the people on them.

An :class:`Episode` is one path of an R2R / HA-R2R file with its instructions; instruction
``k`` of path ``p`` is the :class:`Instruction` ``instr_id = "<p>_<k>"``. A :class:`Dataset`
holds the episodes of one file (reading and writing files: :mod:`havln_mj.tasks.datasets`).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

from havln_mj.errors import InvalidArgumentError, MalformedDataError

REL_POSITIONS = ("Beginning", "Obstacle", "Around", "End")


@dataclass(frozen=True)
class HumanOnPath:
    """A person HA-R2R links to a path (one ``human`` entry).

    Attributes:
        viewpoint: The viewpoint the person stands on (``human_viewpoint``).
        rel_pos: ``Beginning``, ``Obstacle``, ``Around`` or ``End`` (``human_rel_pos``).
        description: ``"region:activity"`` (``human_description``).
    """

    viewpoint: str
    rel_pos: str
    description: str


@dataclass(frozen=True)
class Episode:
    """One path with its instructions.

    Attributes:
        path_id: R2R path id (unique across splits).
        scan: Matterport scan id.
        path: Viewpoint ids, start first, goal last (the start only in R2R test).
        heading: Start heading in radians (elevation is 0).
        instructions: The instructions (usually 3).
        distance: Path length in metres as the file gives it; None when absent (R2R test).
        humans: HA-R2R's people on the path; None for R2R files (no ``human`` key).
        crux_points: HA-R2R's crux points; None when absent.
        rel_pos_descriptions: HA-R2R's ``Relative Position Description``; None when absent.
        extra: Any other keys of the JSON object, kept for writing back.
    """

    path_id: int
    scan: str
    path: tuple[str, ...]
    heading: float
    instructions: tuple[str, ...]
    distance: float | None = None
    humans: tuple[HumanOnPath, ...] | None = None
    crux_points: tuple[str, ...] | None = None
    rel_pos_descriptions: tuple[str, ...] | None = None
    extra: Mapping[str, Any] = field(default_factory=dict, hash=False)

    @property
    def start(self) -> str:
        """The start viewpoint."""
        return self.path[0]

    @property
    def goal(self) -> str:
        """The goal viewpoint (the last of ``path``)."""
        return self.path[-1]

    def instruction(self, k: int) -> Instruction:
        """Instruction ``k`` of this path.

        Raises:
            InvalidArgumentError: There is no instruction ``k``.
        """
        if not 0 <= k < len(self.instructions):
            raise InvalidArgumentError(
                f"path {self.path_id} has {len(self.instructions)} instructions; "
                f"k must be in 0–{len(self.instructions) - 1}, got {k}"
            )
        return Instruction(f"{self.path_id}_{k}", self, k, self.instructions[k])

    def instruction_items(self) -> tuple[Instruction, ...]:
        """All instructions of the path as ``Instruction`` records."""
        return tuple(self.instruction(k) for k in range(len(self.instructions)))


@dataclass(frozen=True)
class Instruction:
    """One instruction: what an agent is evaluated on.

    Attributes:
        instr_id: ``"<path_id>_<k>"``.
        episode: The path it describes.
        k: Its index in ``episode.instructions``.
        text: The instruction.
    """

    instr_id: str
    episode: Episode
    k: int
    text: str


class Dataset:
    """The episodes of one file, in file order.

    Attributes:
        episodes: The episodes.
        source: Where they were read from (for messages).
    """

    def __init__(self, episodes: Iterable[Episode], source: str = "<memory>") -> None:
        self.episodes: tuple[Episode, ...] = tuple(episodes)
        self.source = source
        self._by_id = {e.path_id: e for e in self.episodes}
        if len(self._by_id) != len(self.episodes):
            raise MalformedDataError(f"{source}: path_id values are not unique")

    def __len__(self) -> int:
        return len(self.episodes)

    def __iter__(self) -> Iterator[Episode]:
        return iter(self.episodes)

    def __getitem__(self, i: int) -> Episode:
        return self.episodes[i]

    def __repr__(self) -> str:
        return f"Dataset({self.source!r}, paths={len(self)}, instructions={self.num_instructions})"

    @property
    def num_instructions(self) -> int:
        """Number of instructions over all paths."""
        return sum(len(e.instructions) for e in self.episodes)

    @property
    def instructions(self) -> tuple[Instruction, ...]:
        """Every instruction, path by path."""
        return tuple(i for e in self.episodes for i in e.instruction_items())

    def episode(self, path_id: int) -> Episode:
        """The episode with ``path_id``.

        Raises:
            InvalidArgumentError: No episode has that id.
        """
        try:
            return self._by_id[path_id]
        except KeyError:
            raise InvalidArgumentError(f"{self.source}: no path_id {path_id!r}") from None

    def instruction(self, instr_id: str) -> Instruction:
        """The instruction ``"<path_id>_<k>"``.

        Raises:
            InvalidArgumentError: The id is malformed or names no instruction here.
        """
        m = re.fullmatch(r"(-?\d+)_(\d+)", str(instr_id))
        if m is None:
            raise InvalidArgumentError(f"instr_id must look like '<path_id>_<k>', got {instr_id!r}")
        return self.episode(int(m[1])).instruction(int(m[2]))
