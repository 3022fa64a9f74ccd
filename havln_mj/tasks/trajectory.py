"""What an expert's run leaves: one record per action, and the trajectory they make.

A :class:`Trajectory` gives the run in R2R's and HA3D's submission formats.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from havln_mj.tasks.episodes import Episode
from havln_mj.tasks.step import STOP, Action, StepResult


@dataclass(frozen=True)
class StepRecord:
    """The state after one action (or the start state).

    Attributes:
        action: The action (None for the start state).
        viewpoint: Viewpoint id after the action.
        heading: Heading after the action (radians).
        elevation: Elevation after the action (radians).
        is_crushed: HA3D's ``isCrushed``: 1 when the action came within the collision
            distance of a person.
        crushed_by: Indices of those people in ``getHumanState()``.
        time: Simulated seconds since the start.
        distance: Walking distance to the goal from where the body truly is (metres).
        rewards: Reward terms by name plus ``"total"`` (empty for the start state).
        fell: The body has fallen, or its physics diverged (the episode is over).
    """

    action: Action | None
    viewpoint: str
    heading: float
    elevation: float
    is_crushed: int
    crushed_by: tuple[int, ...]
    time: float
    distance: float
    rewards: Mapping[str, float] = field(default_factory=dict)
    fell: bool = False


@dataclass(frozen=True)
class Trajectory:
    """An expert's run through one episode.

    Attributes:
        episode: The episode.
        expert: The expert's name.
        records: The start state, then one record per action (STOP included).
        stopped: Whether the expert chose STOP (False: it hit the step cap).
    """

    episode: Episode
    expert: str
    records: tuple[StepRecord, ...]
    stopped: bool

    @property
    def steps(self) -> tuple[StepRecord, ...]:
        """The records of the actions (without the start state)."""
        return self.records[1:]

    @property
    def final_viewpoint(self) -> str:
        """Where the agent ended."""
        return self.records[-1].viewpoint

    @property
    def path(self) -> list[str]:
        """Viewpoints visited, consecutive repeats merged."""
        out: list[str] = []
        for r in self.records:
            if not out or out[-1] != r.viewpoint:
                out.append(r.viewpoint)
        return out

    @property
    def collisions(self) -> int:
        """Number of actions with ``isCrushed`` (HA3D's per-step count)."""
        return sum(r.is_crushed for r in self.records)

    @property
    def total_reward(self) -> float:
        """Sum of the step rewards."""
        return sum(r.rewards.get("total", 0.0) for r in self.records)

    def _moves(self) -> list[StepRecord]:
        return [r for r in self.records if r.action is not STOP]

    def r2r(self) -> list[list]:
        """R2R's submission trajectory ``[[viewpoint, heading, elevation], ...]``.

        STOP is left out: it does not change the state.
        """
        return [[r.viewpoint, r.heading, r.elevation] for r in self._moves()]

    def ha3d(self) -> list[list]:
        """HA3D's trajectory ``[[viewpoint, heading, elevation, isCrushed], ...]``."""
        return [[r.viewpoint, r.heading, r.elevation, r.is_crushed] for r in self._moves()]

    def submission(self, k: int = 0) -> dict:
        """The R2R results entry ``{"instr_id": "<path_id>_<k>", "trajectory": [...]}``."""
        return {"instr_id": f"{self.episode.path_id}_{k}", "trajectory": self.r2r()}


def record_of(result: StepResult) -> StepRecord:
    """The record of a task step's result (rewards only after an action)."""
    state = result.state
    rewards = {**result.reward_terms, "total": result.reward} if result.action is not None else {}
    return StepRecord(
        result.action,
        state.location.viewpointId,
        float(state.heading),
        float(state.elevation),
        int(result.collided),
        result.crushed_by,
        float(state.time),
        result.distance,
        rewards,
        result.fell,
    )
