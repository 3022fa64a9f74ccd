"""Evaluation protocols: our strict one, and HA3D's, to compare with the HA-VLN paper.

A :class:`TaskProtocol` gathers every rule that differs between the two, for every layer
that applies one: the simulator (when and how collisions are measured, which clock people
follow: :mod:`havln_mj.sim.rules`), the task step, the sub-optimal expert, the metrics and
the evaluation's camera.

Each rule, strict (the default) first, then HA3D's (with where its code says so):

* **When collisions are checked**: along every action at ≥ 16 Hz, start state included; HA3D:
  in the state after each action and in the start state (``HA3DSim.py``, ``getState``).
* **Distance**: horizontal, from the base to each pelvis; HA3D: 3-D, from the camera to one
  tracked point per person (``src/utils/get_info.py``, ``getHumanLocations``).
* **People's clock**: each episode's simulated time; HA3D: one 120-frame counter shared by
  every episode, +16 frames at a start and +32 per action.
* **Sub-optimal expert when blocked**: it waits, and after ``max_waits`` (10) waits in an
  episode walks on ignoring people; HA3D: it stops (its "no path" answer is the end action:
  ``tasks/HA/utils.py``, ``tasks/HA/env.py``).
* **Expert planning**: shortest by length, removing the nodes within 1 m (horizontally, on
  their storey) of people within 4.5 m; HA3D: fewest hops, the same radii in 3-D.
* **Expert step cap**: the expert's own (150); HA3D: 20 (``param.py``, ``max_episode_len``).
* **TCR**: hits minus the people near crux points, clipped at 0; HA3D: hits minus the people
  labelled ``Beginning`` or ``End``, not clipped (``tasks/HA/eval.py``).
* **CR**: share of episodes whose adjusted count is ≥ 1; HA3D: with any raw hit.
* **Evaluation camera**: MatterSim's default (320×240, 0.8 rad); HA3D: 640×480, 60° (it
  decides which neighbours are navigable).

Collisions are counted per step (turns included) in both; ``count="viewpoint"`` on the
:class:`~havln_mj.tasks.metrics.config.MetricConfig` counts each visit to a viewpoint once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from havln_mj.errors import InvalidArgumentError
from havln_mj.sim.rules import DISTANCES
from havln_mj.tasks.metrics.config import MetricConfig

PROTOCOL_NAMES = ("strict", "ha3d")
DEFAULT_MAX_WAITS = 10
"""Waits the strict sub-optimal expert makes in an episode before it ignores people."""


@dataclass(frozen=True)
class ExpertRules:
    """How the human-aware (sub-optimal) expert plans and what it does when boxed in.

    When no path avoids people, the expert waits (stays a second and re-plans) up to
    ``max_waits`` times per episode, then does ``after_waits``: ``"walk"`` on along the
    shortest path ignoring people, or ``"stop"``. HA3D's expert stops at once
    (``max_waits=0, after_waits="stop"``).

    Attributes:
        distance: ``"horizontal"`` (to pelvis positions, on the viewpoint's storey) or
            ``"camera_3d"`` (HA3D: 3-D between viewpoint cameras and tracked points).
        weighted: Shortest paths by length (True) or by hops (HA3D).
        max_waits: Waits per episode before ``after_waits`` (None: wait for ever).
        after_waits: ``"walk"`` or ``"stop"``.
    """

    distance: str = "horizontal"
    weighted: bool = True
    max_waits: int | None = DEFAULT_MAX_WAITS
    after_waits: str = "walk"

    def __post_init__(self) -> None:
        if self.distance not in DISTANCES:
            raise InvalidArgumentError(
                f"expert distance {self.distance!r} unknown; valid: {DISTANCES}"
            )
        if not isinstance(self.weighted, bool):
            raise InvalidArgumentError(f"weighted takes a bool, got {self.weighted!r}")
        m = self.max_waits
        if m is not None and (isinstance(m, bool) or not isinstance(m, int) or m < 0):
            raise InvalidArgumentError(f"max_waits must be an integer ≥ 0 or None, got {m!r}")
        if self.after_waits not in ("walk", "stop"):
            raise InvalidArgumentError(
                f"after_waits {self.after_waits!r} unknown; valid: 'walk', 'stop'"
            )


@dataclass(frozen=True)
class TaskProtocol:
    """Every rule an evaluation protocol fixes (see the module docstring).

    Attributes:
        name: ``"strict"`` or ``"ha3d"``.
        collision_rule: The simulator's collision rule (``"strict"`` or ``"ha3d"``).
        human_clock: The simulator's human clock (``"continuous"`` or ``"ha3d"``).
        metrics: How episodes are scored.
        expert: The human-aware expert's rules.
        expert_max_steps: Step cap of the experts (None: each expert's own).
        camera: ``(width, height, vfov radians)`` of the evaluation's simulator (None: the
            simulator's default).
    """

    name: str
    collision_rule: str = "strict"
    human_clock: str = "continuous"
    metrics: MetricConfig = field(default_factory=MetricConfig)
    expert: ExpertRules = field(default_factory=ExpertRules)
    expert_max_steps: int | None = None
    camera: tuple[int, int, float] | None = None

    def configure(self, sim: object) -> None:
        """Sets the simulator's collision rule and human clock for this protocol.

        Raises:
            InvalidArgumentError: The simulator cannot follow it (e.g. its people react).
        """
        sim.set_rules(self.collision_rule, self.human_clock)

    def with_metrics(self, **changes: object) -> TaskProtocol:
        """A copy with some fields of its metrics changed (e.g. ``count``)."""
        return replace(self, metrics=replace(self.metrics, **changes))


STRICT = TaskProtocol("strict")
HA3D = TaskProtocol(
    "ha3d",
    collision_rule="ha3d",
    human_clock="ha3d",
    metrics=MetricConfig.ha3d(),
    expert=ExpertRules(distance="camera_3d", weighted=False, max_waits=0, after_waits="stop"),
    expert_max_steps=20,
    camera=(640, 480, math.radians(60.0)),
)
PROTOCOLS = {"strict": STRICT, "ha3d": HA3D}


def get_protocol(protocol: str | TaskProtocol) -> TaskProtocol:
    """The protocol called ``protocol`` (or ``protocol`` itself).

    Raises:
        InvalidArgumentError: An unknown name.
    """
    if isinstance(protocol, TaskProtocol):
        return protocol
    if isinstance(protocol, str) and protocol in PROTOCOLS:
        return PROTOCOLS[protocol]
    raise InvalidArgumentError(
        f"protocol {protocol!r} unknown; valid: {', '.join(PROTOCOL_NAMES)} or a TaskProtocol"
    )
