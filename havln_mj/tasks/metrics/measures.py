"""Per-episode measures, each a small object that names the measures it reads.

A measure has a ``name`` (its key in reports), ``requires`` (names of the measures whose values
it reads) and ``compute(ctx)``. ``Evaluator`` runs them in dependency order; a measure may
read only what it declares.

The default set, with the standard metric each one gives when averaged over episodes:

=========================  ===================================================
``ne``                     NE, navigation error: geodesic final -> goal (m)
``oracle_ne``              geodesic nearest visited viewpoint -> goal (m)
``sr``                     SR: ``ne < success_distance`` (strict)
``osr``                    oracle SR: ``oracle_ne < success_distance``
``tl``                     TL, trajectory length (m)
``shortest``               graph shortest start -> goal distance (m)
``spl``                    SPL = SR * shortest / max(tl, shortest)
``ndtw``                   nDTW against the reference path
``sdtw``                   SDTW = SR * nDTW
``steps``                  number of steps taken (records after the start)
``collisions``             raw collision count (per step or per visit)
``unavoidable``            people whose collisions are discounted
``tcr``                    TCR: adjusted collision count
``cr``                     CR: adjusted (or raw) count >= 1
``cf_sr``                  collision-free SR: success and adjusted count == 0
=========================  ===================================================
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass, field
from itertools import groupby, pairwise
from typing import ClassVar

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.scene.navgraph import NavGraph
from havln_mj.tasks.metrics.config import MetricConfig
from havln_mj.tasks.metrics.critical import unavoidable_people
from havln_mj.tasks.metrics.dtw import ndtw
from havln_mj.tasks.metrics.episode import EvalEpisode
from havln_mj.tasks.metrics.trajectory import visited_path


@dataclass
class EpisodeContext:
    """What a measure sees: the episode, its graph, the config and earlier results.

    Attributes:
        episode: The episode being scored.
        graph: The navigation graph of the episode's scan.
        config: Thresholds and the collision rule.
        values: Values computed so far for this episode, by measure name.
    """

    episode: EvalEpisode
    graph: NavGraph
    config: MetricConfig
    values: dict[str, float] = field(default_factory=dict)
    _allowed: frozenset[str] = frozenset()
    _reader: str = ""

    def __getitem__(self, name: str) -> float:
        """Returns a declared dependency's value for this episode.

        Raises:
            InvalidArgumentError: The current measure did not declare ``name`` in ``requires``.
        """
        if name not in self._allowed:
            raise InvalidArgumentError(
                f"measure {self._reader!r} read {name!r} without declaring it in requires "
                f"(declared: {sorted(self._allowed)})"
            )
        return self.values[name]

    @property
    def path(self) -> list[str]:
        """The viewpoints the agent visited, consecutive repeats merged."""
        return visited_path(self.episode.trajectory)


class Measure(ABC):
    """One per-episode quantity.

    Subclasses set ``name`` and ``requires`` and implement ``compute``. The summary over
    episodes is ``aggregate`` of the per-episode values (the mean unless overridden).
    """

    name: ClassVar[str]
    requires: ClassVar[tuple[str, ...]] = ()

    @abstractmethod
    def compute(self, ctx: EpisodeContext) -> float:
        """Returns this measure's value for ``ctx.episode``."""

    def aggregate(self, values: Sequence[float]) -> float:
        """Returns the summary over episodes: the mean."""
        return float(np.mean(values))

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r}, requires={self.requires!r})"


class NavigationError(Measure):
    """Geodesic distance from the final viewpoint to the goal (NE, metres)."""

    name = "ne"

    def compute(self, ctx: EpisodeContext) -> float:
        """Returns the geodesic distance from the last step to the goal."""
        return ctx.graph.distance(ctx.episode.trajectory[-1].viewpoint, ctx.episode.goal)


class OracleNavigationError(Measure):
    """Geodesic distance from the visited viewpoint nearest the goal to the goal (metres)."""

    name = "oracle_ne"

    def compute(self, ctx: EpisodeContext) -> float:
        """Returns the smallest goal distance over the visited viewpoints."""
        return min(ctx.graph.distance(vp, ctx.episode.goal) for vp in ctx.path)


class Success(Measure):
    """1 when NE is below the success distance (strict, as R2R), else 0."""

    name = "sr"
    requires = ("ne",)

    def compute(self, ctx: EpisodeContext) -> float:
        """Returns 1.0 on success, else 0.0."""
        return float(ctx["ne"] < ctx.config.success_distance)


class OracleSuccess(Measure):
    """1 when some visited viewpoint is within the success distance of the goal (OSR)."""

    name = "osr"
    requires = ("oracle_ne",)

    def compute(self, ctx: EpisodeContext) -> float:
        """Returns 1.0 on oracle success, else 0.0."""
        return float(ctx["oracle_ne"] < ctx.config.success_distance)


class TrajectoryLength(Measure):
    """Summed geodesic distance between consecutive distinct viewpoints (TL, metres).

    Consecutive viewpoints are normally graph neighbours, so this is the walked length; a
    jump between non-neighbours adds its geodesic distance, as R2R's eval does.
    """

    name = "tl"

    def compute(self, ctx: EpisodeContext) -> float:
        """Returns the summed length of the moves."""
        return sum(ctx.graph.distance(a, b) for a, b in pairwise(ctx.path))


class ShortestLength(Measure):
    """The graph's shortest start -> goal distance (SPL's l; not the JSON ``distance``)."""

    name = "shortest"

    def compute(self, ctx: EpisodeContext) -> float:
        """Returns the shortest distance; raises InvalidArgumentError if unreachable."""
        ep = ctx.episode
        length = ctx.graph.distance(ep.start, ep.goal)
        if math.isinf(length):
            raise InvalidArgumentError(
                f"episode {ep.episode_id}: goal {ep.goal!r} cannot be reached from start "
                f"{ep.start!r} in scan {ctx.graph.name}"
            )
        return length


class SPL(Measure):
    """Success weighted by path length: SR * l / max(TL, l) (Anderson et al. 2018)."""

    name = "spl"
    requires = ("sr", "tl", "shortest")

    def compute(self, ctx: EpisodeContext) -> float:
        """Returns SPL in [0, 1]."""
        longest = max(ctx["tl"], ctx["shortest"])
        # Start == goal and no move: a perfect run, not 0/0.
        return ctx["sr"] * (ctx["shortest"] / longest if longest > 0 else 1.0)


class NDTW(Measure):
    """Normalised dynamic time warping between the reference and the visited path."""

    name = "ndtw"

    def compute(self, ctx: EpisodeContext) -> float:
        """Returns nDTW in (0, 1]."""
        cfg = ctx.config
        return ndtw(ctx.graph, ctx.episode.reference_path, ctx.path, cfg.dtw_threshold)


class SDTW(Measure):
    """Success weighted by nDTW: SR * nDTW."""

    name = "sdtw"
    requires = ("sr", "ndtw")

    def compute(self, ctx: EpisodeContext) -> float:
        """Returns SDTW in [0, 1]."""
        return ctx["sr"] * ctx["ndtw"]


class Steps(Measure):
    """Number of steps taken: trajectory records after the start (turns included)."""

    name = "steps"

    def compute(self, ctx: EpisodeContext) -> float:
        """Returns the step count."""
        return float(len(ctx.episode.trajectory) - 1)


class Collisions(Measure):
    """Raw collision count: the steps, start included, flagged as collided.

    With ``count="step"`` (HA3D), lingering or turning next to a person adds one per step;
    with ``count="viewpoint"``, each visit to a viewpoint (a run of consecutive steps on
    it) adds at most one.
    """

    name = "collisions"

    def compute(self, ctx: EpisodeContext) -> float:
        """Returns the number of collided steps (or visits)."""
        steps = ctx.episode.trajectory
        if ctx.config.count == "step":
            return float(sum(step.collided for step in steps))
        visits = [any(s.collided for s in run) for _, run in groupby(steps, lambda s: s.viewpoint)]
        return float(sum(visits))


class Unavoidable(Measure):
    """Number of the episode's people whose collisions are discounted (``MetricConfig``)."""

    name = "unavoidable"

    def compute(self, ctx: EpisodeContext) -> float:
        """Returns the number of unavoidable people."""
        return float(len(unavoidable_people(ctx.episode, ctx.graph, ctx.config)))


class TotalCollisions(Measure):
    """Adjusted collision count (TCR when averaged): collisions - unavoidable.

    Clipped at 0 when ``config.clip`` (HA-VLN 2.0); HA3D's code lets it go negative.
    """

    name = "tcr"
    requires = ("collisions", "unavoidable")

    def compute(self, ctx: EpisodeContext) -> float:
        """Returns the adjusted count."""
        adjusted = ctx["collisions"] - ctx["unavoidable"]
        return max(adjusted, 0.0) if ctx.config.clip else adjusted


class CollisionRate(Measure):
    """1 when the episode has a collision (CR when averaged).

    Uses the adjusted count when ``config.cr_adjusted`` (HA-VLN 2.0), the raw count otherwise
    (HA3D's ``hits_rate``).
    """

    name = "cr"
    requires = ("collisions", "tcr")

    def compute(self, ctx: EpisodeContext) -> float:
        """Returns 1.0 when the counted collisions are >= 1, else 0.0."""
        count = ctx["tcr"] if ctx.config.cr_adjusted else ctx["collisions"]
        return float(count >= 1)


class CollisionFreeSuccess(Measure):
    """1 when the episode succeeds with an adjusted collision count of exactly 0.

    Without clipping a negative count fails this test, as in HA3D's ``successes_nohits``.
    """

    name = "cf_sr"
    requires = ("sr", "tcr")

    def compute(self, ctx: EpisodeContext) -> float:
        """Returns 1.0 for a collision-free success, else 0.0."""
        return float(ctx["sr"] == 1.0 and ctx["tcr"] == 0.0)


DEFAULT_MEASURES: tuple[type[Measure], ...] = (
    NavigationError,
    OracleNavigationError,
    Success,
    OracleSuccess,
    TrajectoryLength,
    ShortestLength,
    SPL,
    NDTW,
    SDTW,
    Steps,
    Collisions,
    Unavoidable,
    TotalCollisions,
    CollisionRate,
    CollisionFreeSuccess,
)


def default_measures() -> dict[str, Measure]:
    """Returns fresh instances of the default measures, by name."""
    return {cls.name: cls() for cls in DEFAULT_MEASURES}
