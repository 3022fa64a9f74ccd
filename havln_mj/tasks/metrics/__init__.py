"""HA-VLN metrics: R2R's NE, SR, OSR, TL, SPL, nDTW, SDTW and HA-VLN's TCR, CR, collision-free SR.

Build one ``EvalEpisode`` per agent run (``EvalEpisode.from_ha_r2r`` or
``episodes_from_submission``) and score them with ``Evaluator`` (or ``evaluate``). Each metric
is a ``Measure`` object with declared dependencies; ``MetricConfig`` holds thresholds and the
collision rule (critical nodes as in the HA-VLN paper by default, ``MetricConfig.ha3d()`` for
HA3D's code).
"""

from havln_mj.tasks.metrics.config import MetricConfig
from havln_mj.tasks.metrics.critical import crux_points, unavoidable_people
from havln_mj.tasks.metrics.dtw import dtw, ndtw
from havln_mj.tasks.metrics.episode import (
    REL_POSITIONS,
    EvalEpisode,
    Person,
    episodes_from_submission,
)
from havln_mj.tasks.metrics.evaluator import (
    EvaluationResult,
    Evaluator,
    evaluate,
    resolve_order,
)
from havln_mj.tasks.metrics.measures import (
    DEFAULT_MEASURES,
    EpisodeContext,
    Measure,
    default_measures,
)
from havln_mj.tasks.metrics.trajectory import Step, parse_step, parse_trajectory, visited_path

__all__ = [
    "DEFAULT_MEASURES",
    "REL_POSITIONS",
    "EpisodeContext",
    "EvalEpisode",
    "EvaluationResult",
    "Evaluator",
    "Measure",
    "MetricConfig",
    "Person",
    "Step",
    "crux_points",
    "default_measures",
    "dtw",
    "episodes_from_submission",
    "evaluate",
    "ndtw",
    "parse_step",
    "parse_trajectory",
    "resolve_order",
    "unavoidable_people",
    "visited_path",
]
