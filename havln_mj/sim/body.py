"""The Body seam: what executes the simulator's actions, and what it reports.

The simulator never asks which body it drives. A :class:`BodyKind` (one per simulator:
``"point"`` or ``"go1"``, see :data:`~havln_mj.sim.bodies.BODY_KINDS`) makes a :class:`Body` per
batch element on a scan; the body starts at a viewpoint, executes graph actions (a move to a
neighbour, a turn, a wait) and, when it has a robot's action set, the robot's continuous
actions, and returns an :class:`Outcome`: how long the action took, where the body's base was
over time (the track the collision signal is sampled along), where it ended, whether it arrived,
fell, diverged or touched anyone. It draws itself through the frame pipeline
(:mod:`havln_mj.sim.frame`).

**Truth.** ``Outcome.viewpoint`` is the viewpoint the body stands at when the action ends: the
target when the body arrived within :data:`ARRIVAL_M` of it (horizontally, on its floor),
else the last viewpoint it stood at. ``arrived`` says which. The point body always arrives;
a robot that stalls on a stair or falls does not, and the state says so.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import NamedTuple, Protocol

import mujoco
import numpy as np

from havln_mj.scene.navgraph import NavGraph
from havln_mj.sim.crowd import Crowd
from havln_mj.sim.frame import View, ViewSettings

ARRIVAL_M = 0.3
"""A body whose base ends within this horizontal distance of a viewpoint, on a floor within
this height of the viewpoint's floor, stands at that viewpoint."""

Knots = Sequence[Sequence[float]] | np.ndarray
"""A body's track over an action, as rows ``(t, x, y, z)`` of its base, linear in between."""

Observe = Callable[[Knots], None]
"""Tells the people (those who react) where the body went, given its knots over an action."""


def ignore(knots: Knots) -> None:
    """An :data:`Observe` for people who do not react."""


class Film:
    """Frames to draw during actions, at ``fps`` frames per simulated second.

    A kinematic body, which can pose itself at any moment, asks :meth:`times` for the frame
    times of an action and calls ``draw`` at each, drawn pose set; a physics body calls
    :meth:`tick` at every controller tick, and a frame is drawn when one is due.

    Args:
        fps: Frames per simulated second.
        draw: Draws the body's current drawn pose at a simulated time.
    """

    def __init__(self, fps: float, draw: Callable[[float], None]) -> None:
        self.period = 1.0 / fps
        self.draw = draw
        self._next = -math.inf

    def times(self, t0: float, t1: float) -> list[float]:
        """Frame times in ``(t0, t1]`` still due, on the film's grid; ``t1`` always last."""
        start = max(self._next, t0 + self.period)
        n = max(0, math.floor((t1 - start) / self.period + 1e-9) + 1)
        out = [start + k * self.period for k in range(n) if start + k * self.period < t1 - 1e-9]
        out.append(t1)
        self._next = t1 + self.period
        return out

    def tick(self, t: float) -> None:
        """Draws a frame at ``t`` if one is due."""
        if t + 1e-9 >= self._next:
            self._next = t + self.period
            self.draw(t)


class Outcome(NamedTuple):
    """What one action did.

    Attributes:
        duration: Simulated seconds the action took.
        knots: The base's track: rows ``(t, x, y, z)``, linear between rows, first row at the
            action's start and last at its end (one row for an instant).
        viewpoint: The viewpoint the body stands at afterwards (see the module docstring).
        heading: The body's true heading afterwards (radians).
        arrived: Whether a move reached its target viewpoint (True for turns and waits).
        fell: Whether the body fell (the episode is over).
        diverged: Whether the physics diverged (MuJoCo reported a numerical warning; the
            episode is over and the body's pose is not to be trusted).
        contacts: Most body–person physical contacts at once during the action.
        detail: Body-specific detail (the GO1's primitive results), for reports.
    """

    duration: float
    knots: Knots
    viewpoint: str
    heading: float
    arrived: bool = True
    fell: bool = False
    diverged: bool = False
    contacts: int = 0
    detail: object = None


class Body(Protocol):
    """One batch element's body on one scan."""

    viewpoint: str
    """The viewpoint the body stands at."""

    observe: Observe
    """Called with the body's knots as soon as they are known (before the frames of a
    kinematic move are drawn, after a physical one), so that people who react see them."""

    def start(self, viewpoint: str, heading: float, elevation: float, t: float) -> Outcome:
        """Places the body at ``viewpoint`` facing ``heading`` at time ``t`` (an instant)."""
        ...

    def move(
        self,
        target: str,
        heading: float,
        elevation: float,
        t: float,
        wait_s: float,
        film: Film | None = None,
    ) -> Outcome:
        """A graph action: go to neighbour ``target`` (or stay), then face the new view.

        A move to the current viewpoint without a turn is a wait of ``wait_s`` seconds.
        """
        ...

    def robot_action(self, action: str, t: float, film: Film | None = None) -> Outcome:
        """A robot's continuous action (:data:`ROBOT_ACTIONS`; not ``"stop"``).

        Raises:
            InvalidActionError: The body has no robot action set.
        """
        ...

    def pose(self) -> np.ndarray:
        """The true pose of the base now: ``(x, y, z, heading)``."""
        ...

    def goal_distance(self, goal: str) -> float:
        """Walking distance from where the body truly is to viewpoint ``goal`` (metres)."""
        ...

    def scene(self, elevation: float, t: float) -> tuple[mujoco.MjModel, mujoco.MjData]:
        """The body's world posed at ``t`` (people, the body, its camera at ``elevation``).

        For a live viewer or an export; kinematics is done.
        """
        ...

    def render(
        self, settings: ViewSettings, elevation: float, t: float, camera: str | None = None
    ) -> View:
        """A view of the body's drawn pose at simulated time ``t``.

        Args:
            settings: Image size and outputs.
            elevation: The body camera's elevation (radians).
            t: Simulated seconds (people are posed at ``t``).
            camera: Another camera of the body's world (e.g. a chase camera); default the
                body's own camera.
        """
        ...


class BodyKind(Protocol):
    """Makes the bodies of one simulator and holds what they share per scan."""

    name: str
    robot_actions: tuple[str, ...]
    """The robot actions its bodies take besides ``"stop"`` (none for the point body)."""

    def body(self, scan_id: str, graph: NavGraph, crowd: Crowd) -> Body:
        """A new body on ``scan_id``."""
        ...

    def prepare(self, scan_id: str, crowd: Crowd, rendering: bool) -> None:
        """Builds what the scan's bodies share ahead of use (preloading)."""
        ...

    def close(self) -> None:
        """Releases renderers and worlds."""
        ...


ROBOT_ACTIONS = ("stop", "forward", "turn_left", "turn_right")
"""The real robot's action set (the GO1's)."""


def nearest_viewpoint(graph: NavGraph, position: np.ndarray, floor_z: float) -> tuple[str, float]:
    """The included viewpoint nearest a base on ``floor_z``, and its horizontal distance.

    Viewpoints on other storeys count 10 m per metre of floor difference, so a viewpoint of
    the floor the body stands on wins.
    """
    best, best_cost, best_gap = "", math.inf, math.inf
    for vp in graph.nodes:
        p = graph.position(vp)
        gap = math.hypot(p[0] - position[0], p[1] - position[1])
        cost = gap + 10.0 * abs(graph.floor_z(vp) - floor_z)
        if cost < best_cost:
            best, best_cost, best_gap = vp, cost, gap
    return best, best_gap


def stands_at(graph: NavGraph, vp: str, position: np.ndarray, floor_z: float) -> bool:
    """Whether a base at ``position`` on ``floor_z`` stands at viewpoint ``vp``."""
    p = graph.position(vp)
    near = math.hypot(p[0] - position[0], p[1] - position[1]) <= ARRIVAL_M
    return near and abs(graph.floor_z(vp) - floor_z) <= ARRIVAL_M
