"""Thresholds and the collision-counting rule shared by all measures."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from havln_mj.errors import InvalidArgumentError
from havln_mj.sim.crowd import COLLISION_DISTANCE
from havln_mj.tasks.rewards import SUCCESS_DISTANCE  # R2R and HA-R2R: success when NE < 3 m

CriticalMode = Literal["paper", "ha3d", "none"]
CRITICAL_MODES: tuple[str, ...] = ("paper", "ha3d", "none")

DTW_THRESHOLD = 3.0  # metres; d_th of nDTW (Ilharco et al. 2019)
COLLISION_RADIUS = COLLISION_DISTANCE  # metres; HA-VLN's threshold (HA3D: distance <= 1)


@dataclass(frozen=True)
class MetricConfig:
    """How episodes are scored.

    Collisions are counted per trajectory step: a step (one low-level action, turns included,
    and the start state) with at least one person within the collision radius adds 1, as
    HA3D's ``isCrushed`` flag does. The count is then reduced by the number of *unavoidable*
    people of the episode, chosen by ``critical``:

    * ``"paper"`` (default): people standing within ``collision_radius`` of a critical node
      of the reference path. Critical nodes are the path's crux points, the nodes the agent
      must pass to reach the goal: start, goal and every bottleneck node (HA-R2R's
      ``crux_points``; recomputed from the graph by ``crux_points`` when absent).
    * ``"ha3d"``: people whose HA-R2R ``human_rel_pos`` is ``Beginning`` or ``End``, as HA3D's
      ``tasks/HA/eval.py`` does (its ``crux_points`` are stored but unused).
    * ``"none"``: no adjustment.

    Attributes:
        success_distance: An episode succeeds when its navigation error is below this (m).
        dtw_threshold: The ``d_th`` of nDTW (m).
        collision_radius: Distance (m) from a critical node within which a person is
            unavoidable in ``"paper"`` mode.
        critical: Which people are unavoidable: ``"paper"``, ``"ha3d"`` or ``"none"``.
        clip: Clip the adjusted count at 0 (HA-VLN 2.0: ``TCR_ep = max(0, c - unavoidable)``).
            HA3D's code does not clip, so an episode can score a negative count.
        cr_adjusted: CR counts episodes whose adjusted count is >= 1 (HA-VLN 2.0:
            ``CR_ep = min(TCR_ep, 1)``); False counts episodes with >= 1 raw collision, as
            HA3D's ``hits_rate`` does.
    """

    success_distance: float = SUCCESS_DISTANCE
    dtw_threshold: float = DTW_THRESHOLD
    collision_radius: float = COLLISION_RADIUS
    critical: CriticalMode = "paper"
    clip: bool = True
    cr_adjusted: bool = True

    def __post_init__(self) -> None:
        for name in ("success_distance", "dtw_threshold", "collision_radius"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise InvalidArgumentError(f"{name} must be a number, got {value!r}")
            if not math.isfinite(value) or value <= 0:
                raise InvalidArgumentError(f"{name} must be finite and > 0, got {value!r}")
        if self.critical not in CRITICAL_MODES:
            raise InvalidArgumentError(
                f"critical must be one of {CRITICAL_MODES}, got {self.critical!r}"
            )

    @classmethod
    def ha3d(cls) -> MetricConfig:
        """The rules of HA3D's ``tasks/HA/eval.py``: Beginning/End people, no clip, raw CR."""
        return cls(critical="ha3d", clip=False, cr_adjusted=False)
