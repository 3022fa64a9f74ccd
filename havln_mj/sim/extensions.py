"""The simulator's HA-VLN extensions beyond MatterSim's API.

:class:`SimulatorExtensions` is the part of :class:`~havln_mj.sim.simulator.Simulator` that
MatterSim does not have: filming actions (:meth:`~SimulatorExtensions.set_film`), the
collision rule and people's clock of a protocol (:meth:`~SimulatorExtensions.set_rules`),
waiting, stepping elements with actions of any kind (:meth:`~SimulatorExtensions.step`),
the scans, crowds and posed worlds behind the states, and timing. It works on the
simulator's own state; use it through ``Simulator``.
"""

from __future__ import annotations

import math
import numbers
import time
from collections.abc import Sequence

import mujoco
import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.scene.scan import Scan
from havln_mj.sim.actions import parse_mixed
from havln_mj.sim.batch import FilmCallback
from havln_mj.sim.crowd import Crowd
from havln_mj.sim.rules import (
    CollisionRule,
    HumanClock,
    check_pair,
    collision_rule_of,
    human_clock_of,
)


class SimulatorExtensions:
    """HA-VLN's additions to the MatterSim API (mixed into ``Simulator``)."""

    def set_film(
        self, fps: float | None, callback: FilmCallback | None = None, cameras: Sequence[str] = ()
    ) -> None:
        """Draws frames during actions, at ``fps`` per simulated second (None stops).

        ``callback(element, t, views, pose)`` receives the element's index, the simulated
        time, the views of its body camera then of each of ``cameras`` (other cameras of the
        body's world, e.g. the GO1's chase camera ``"go1/chase"``), with the people and the
        body as they were at ``t``, and the body's pose ``(x, y, z, heading)`` then. The
        first frame of an episode is its start state.

        Raises:
            InvalidArgumentError: ``fps`` is not positive, or no callback is given.
        """
        if fps is None:
            self._film = None
            if self._batch is not None:
                self._batch.film = None
            return
        ok = isinstance(fps, numbers.Real) and math.isfinite(fps) and 0 < fps <= 1000
        if not ok or callback is None:
            raise InvalidArgumentError(
                f"set_film takes fps in (0, 1000] and a callback, got {fps!r}"
            )
        self._film = (float(fps), callback, tuple(cameras))
        if self._batch is not None:
            self._batch.film = self._film

    def set_rules(
        self,
        collision_rule: str | CollisionRule | None = None,
        human_clock: str | HumanClock | None = None,
        frame: int | None = None,
    ) -> None:
        """When and how collisions are measured, and which time people are posed at.

        Takes effect from the next state on; may be called at any time.

        Args:
            collision_rule: ``"strict"``, ``"ha3d"`` (both with the simulator's
                ``collision_distance``) or a :class:`~havln_mj.sim.rules.CollisionRule`
                (None: keep the current one).
            human_clock: ``"continuous"``, ``"ha3d"`` or a
                :class:`~havln_mj.sim.rules.HumanClock` (None: keep the current one).
            frame: Where HA3D's counter (re)starts (an evaluation resumed mid-way sets the
                counter it stopped at, :attr:`human_clock_frame`); None keeps the counter
                when the clock stays the same, else starts it at 0.

        Raises:
            InvalidArgumentError: An unknown rule, clock or frame; HA3D's clock with a
                per-action collision check, or with people who react (HA3D's poses people
                only in states, and its people do not react).
        """
        rule = (
            self._rule
            if collision_rule is None
            else collision_rule_of(collision_rule, self._collision_distance)
        )
        clock = self._clock if human_clock is None else human_clock_of(human_clock)
        check_pair(rule, clock, self._people.reactions)
        if frame is None:
            frame = self.human_clock_frame if clock == self._clock else 0
        bad = isinstance(frame, bool) or not isinstance(frame, numbers.Integral)
        if bad or not 0 <= frame < clock.frames:
            raise InvalidArgumentError(
                f"human clock frame must be an integer in [0, {clock.frames}), got {frame!r}"
            )
        self._rule, self._clock, self._frame = rule, clock, int(frame)
        if self._batch is not None:
            self._batch.rule, self._batch.clock, self._batch.frame = rule, clock, self._frame

    @property
    def collision_rule(self) -> CollisionRule:
        """The collision rule in use."""
        return self._rule

    @property
    def human_clock(self) -> HumanClock:
        """The people's clock in use."""
        return self._clock

    @property
    def human_clock_frame(self) -> int:
        """HA3D's shared frame counter now (0 with the continuous clock)."""
        return self._batch.frame if self._batch is not None else self._frame

    # ------------------------------------------------------------------ episodes

    @property
    def robot_actions(self) -> tuple[str, ...]:
        """The robot actions the body takes besides ``"stop"`` (none for the point body)."""
        if not self._initialized:
            self.initialize()
        return self._kind.robot_actions

    def scan(self, scan_id: str) -> Scan:
        """The scan the simulator uses for ``scan_id`` with its geometry (loaded on first use).

        Raises:
            UnknownScanError: No scan or graph can be found for ``scan_id``.
        """
        if not self._initialized:
            self.initialize()
        return self._library.scan(scan_id)

    def people(self, element: int = 0) -> Crowd:
        """The people element ``element`` shares its episode with (reacting to it, if set).

        Raises:
            NotInitializedError: No episode has been started.
        """
        self._started("people")
        return self._batch.elements[element].crowd

    def crowd(self, scan_id: str) -> Crowd:
        """The people of ``scan_id`` (made on first use from the seed and the scan).

        Raises:
            MissingDataError: A real scan the placement file does not list, without region
                labels to place people by (see :mod:`havln_mj.sim.people`).
        """
        if not self._initialized:
            self.initialize()
        return self._crowd(self._library.table(scan_id))

    def people_source(self, scan_id: str) -> str:
        """Where the people of ``scan_id`` come from, in words (for banners and reports).

        Raises:
            MissingDataError: As :meth:`crowd`.
        """
        if not self._initialized:
            self.initialize()
        self.crowd(scan_id)  # a scan that cannot have people fails here, before anything
        return self._people.source(scan_id)

    def draw(self, element: int = 0) -> tuple[mujoco.MjModel, mujoco.MjData]:
        """Element ``element``'s world posed at its time: the people, the body, its camera.

        The model and data a live viewer shows (kinematics done); it shares them with the
        simulator, so re-draw after every action.

        Raises:
            NotInitializedError: No episode has been started.
            InvalidArgumentError: ``element`` is not a batch index.
        """
        self._started("draw")
        n = len(self._batch.elements)
        if (
            isinstance(element, bool)
            or not isinstance(element, numbers.Integral)
            or not 0 <= element < n
        ):
            raise InvalidArgumentError(f"element {element!r} out of range; valid 0–{n - 1}")
        el = self._batch.elements[element]
        return el.body.scene(el.elevation, el.people_t)

    def wait(self, seconds: Sequence[float]) -> None:
        """Each element stays where it is, looking where it looks, for ``seconds`` (≥ 0).

        An extension of MatterSim (HA3D's frame counter, made explicit): people go on moving,
        the collision signal covers the whole wait, and the state (images included) is that
        at the end. ``makeAction`` with index 0 and no turn is the same with
        :data:`~havln_mj.sim.batch.WAIT_S`.

        Raises:
            NotInitializedError: No episode has been started.
            BatchSizeError: ``seconds`` does not have one entry per batch element.
            InvalidArgumentError: A duration is negative or not finite.
        """
        t0 = time.perf_counter()
        self._running()
        durations = []
        for i, s in enumerate(self._per_element("seconds", seconds)):
            ok = isinstance(s, numbers.Real) and not isinstance(s, bool) and math.isfinite(s)
            if not ok or s < 0:
                raise InvalidArgumentError(
                    f"wait for batch element {i} must be a finite number of seconds ≥ 0, got {s!r}"
                )
            durations.append(float(s))
        self._batch.apply([(i, 0, 0.0, 0.0) for i in range(len(durations))], durations)
        self._timers["process"] += time.perf_counter() - t0

    def step(self, actions: Sequence[object]) -> None:
        """One action per element, of any kind; None leaves the element alone.

        An extension of MatterSim for task code that steps elements independently: a graph
        action is a tuple ``(index, dHeading, dElevation)`` (as ``makeAction``), an
        :class:`~havln_mj.sim.egocentric.EgoAction` member an egocentric action (STOP leaves
        the element alone), a string a robot action of
        :data:`~havln_mj.sim.body.ROBOT_ACTIONS` (``"stop"`` leaves it alone). The whole batch is
        checked before anything moves.

        Raises:
            NotInitializedError: No episode has been started.
            BatchSizeError: ``actions`` does not have one entry per batch element.
            InvalidActionError: An action of no kind, or invalid for its element.
        """
        t0 = time.perf_counter()
        elements = self._running()
        graph, robot = parse_mixed(
            elements,
            self._per_element("actions", actions),
            self._cfg.half_hfov(),
            self._kind.robot_actions,
        )
        if graph:
            self._batch.apply(graph)
        if any(r != "stop" for r in robot):
            self._batch.robot(robot)
        self._timers["process"] += time.perf_counter() - t0

    def collision_points(self) -> list[np.ndarray]:
        """Each element's people as the collision rule measures them: ``(K, 3)`` each.

        Pelvis positions (the strict rule), or HA3D's tracked points
        (:func:`~havln_mj.sim.crowd.ha3d_points`) with ``collision_rule="ha3d"``; at the
        time of the element's last state.
        """
        self._started("collision_points")
        return [np.array(self._batch.collision_points(el)) for el in self._batch.elements]

    def timing(self) -> dict[str, float]:
        """Seconds in simulator calls and in rendering, and frames rendered, since the reset."""
        t = self._timers
        return {"process_s": t["process"], "render_s": t["render"], "frames": t["frames"]}
