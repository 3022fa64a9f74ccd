"""What an expert sees of the running episode, and the small rules every expert shares.

:class:`ExpertContext` is handed to an expert's ``reset`` and ``act``; :data:`WAIT` is the
graph action that stays put; the camera helpers make egocentric experts plan level and with
the simulator's own field of view.
"""

from __future__ import annotations

from dataclasses import dataclass

from havln_mj.errors import InvalidArgumentError
from havln_mj.scene.navgraph import NavGraph
from havln_mj.sim.egocentric import EgoAction
from havln_mj.sim.state import SimState
from havln_mj.tasks.episodes import Episode
from havln_mj.tasks.planning import TURN
from havln_mj.tasks.step import GraphAction

WAIT: GraphAction = (0, 0.0, 0.0)
"""The graph action that stays put (the current viewpoint, index 0, and no turn)."""
# MatterSim's default camera (VFOV 0.8 rad, 320×240), when the simulator cannot tell.
DEFAULT_HALF_HFOV = 0.8 * 320 / 240 / 2


@dataclass
class ExpertContext:
    """What an expert sees of the running episode.

    Attributes:
        sim: The simulator (batch size 1, episode started).
        episode: The episode.
        graph: The scan's navigation graph (the simulator's own).
        step: Number of actions taken so far.
        instruction: Which of the episode's instructions is being followed.
    """

    sim: object
    episode: Episode
    graph: NavGraph
    step: int = 0
    instruction: int = 0

    @property
    def instruction_text(self) -> str:
        """The instruction being followed."""
        return self.episode.instructions[self.instruction]

    @property
    def goal(self) -> str:
        """The goal viewpoint."""
        return self.episode.goal


def level_camera(state: SimState) -> EgoAction | None:
    """LOOK_DOWN / LOOK_UP while the camera is off level (egocentric experts plan level)."""
    if state.elevation > TURN / 2:
        return EgoAction.LOOK_DOWN
    if state.elevation < -TURN / 2:
        return EgoAction.LOOK_UP
    return None


def sim_half_hfov(sim: object) -> float:
    """The simulator's half horizontal field of view: its own rule decides FORWARD."""
    return float(getattr(sim, "half_hfov", DEFAULT_HALF_HFOV))


def positive_int(name: str, value: object) -> int:
    """``value``, an integer ≥ 1; raises InvalidArgumentError naming ``name`` otherwise."""
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise InvalidArgumentError(f"{name} must be an integer ≥ 1, got {value!r}")
    return value
