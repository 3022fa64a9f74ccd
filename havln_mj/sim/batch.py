"""The running batch: each element's body, view, clock and state, stepped through the Body seam.

:class:`Batch` is the simulator's runtime (the simulator checks the MatterSim API's
arguments, except the plain values of a batch of one, which :meth:`Batch.apply_one` takes as
they come): it starts the elements' bodies, turns graph actions into body moves under the view
rules (discretised or continuous), advances each element's clock by what its body reports,
computes the collision signal along the body's track, renders the state through the frame
pipeline and, when a film is set, frames during actions.

What the collision signal covers and which time people are posed at follow the batch's
:class:`~havln_mj.sim.rules.CollisionRule` and :class:`~havln_mj.sim.rules.HumanClock`
(strict by default; HA3D's on request). Each element's people are posed at its
``people_t``: its own simulated time, or the time of HA3D's shared frame counter.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence

import numpy as np

from havln_mj.frames import TWO_PI
from havln_mj.sim.body import Body, BodyKind, Film, Outcome
from havln_mj.sim.crowd import NO_PROXIMITY, Crowd, Proximity, ha3d_points, state_proximity
from havln_mj.sim.frame import View, ViewSettings
from havln_mj.sim.images import ImageFormat
from havln_mj.sim.navigation import NavTable
from havln_mj.sim.proximity import NearMemo, batch_proximity, knots_proximity, sample_knots
from havln_mj.sim.rules import CollisionRule, HumanClock
from havln_mj.sim.settings import Settings
from havln_mj.sim.state import SimState, ViewPoint, make
from havln_mj.sim.viewing import (
    ELEVATION_INCREMENT,
    HEADING_INCREMENT,
    continuous_view,
    discrete_delta,
    discrete_view,
)

WAIT_S = 1.0
"""Seconds that an action which neither moves nor turns (a wait) lasts."""

_fmod = math.fmod

FilmCallback = Callable[[int, float, list[View], np.ndarray], None]


class Element:
    """One batch element's episode: its body, view, clock and last state."""

    __slots__ = (
        "body",
        "crowd",
        "elevation",
        "film",
        "heading",
        "navigable",
        "people",
        "people_t",
        "people_xyz",
        "state",
        "step",
        "table",
        "time",
        "view_index",
    )

    def __init__(self, table: NavTable, crowd: Crowd, body: Body) -> None:
        self.table, self.crowd, self.body = table, crowd, body
        self.people = len(crowd) > 0
        self.heading = self.elevation = self.time = self.people_t = 0.0
        self.people_xyz: np.ndarray | None = None  # pelvis positions at people_t, once asked
        self.view_index = self.step = 0
        self.navigable: list[ViewPoint] = []
        self.state: SimState | None = None
        self.film: Film | None = None


class Batch:
    """The elements of a simulator's current episodes.

    Args:
        cfg: The simulator's settings (read at every step: the camera may change).
        kind: Makes the bodies.
        image_format: Turns rendered views into state images.
        rule: When and how collisions are measured (its threshold included).
        timers: The simulator's timers (rendering time and frames are added).

    Attributes:
        rule: The collision rule (read at every state).
        frame: HA3D's shared frame counter (with ``clock.kind == "ha3d"``).
    """

    def __init__(
        self,
        cfg: Settings,
        kind: BodyKind,
        image_format: ImageFormat,
        rule: CollisionRule,
        timers: dict,
    ) -> None:
        self.cfg, self.kind, self.format = cfg, kind, image_format
        self.rule = rule
        self.clock = HumanClock.continuous()
        self.frame = 0
        self.timers = timers
        self.elements: list[Element] = []
        self.film: tuple[float, FilmCallback, tuple[str, ...]] | None = None
        self.reactions = None  # how people react to the agent (None: they do not)
        self._near = NearMemo()
        self._cos_fov: float | None = None
        self._view: ViewSettings | None = None  # the state images' view settings
        self._blank: tuple[np.ndarray, np.ndarray] | None = None
        self._revision = -1  # the settings' revision _cos_fov and _blank were derived from

    @property
    def clock(self) -> HumanClock:
        """The people's clock."""
        return self._clock

    @clock.setter
    def clock(self, clock: HumanClock) -> None:
        self._clock = clock
        self._continuous = clock.kind == "continuous"  # read at every state

    def view(self, heading: float, elevation: float) -> tuple[float, float, int]:
        """Heading, elevation and view index under the view rules."""
        if self.cfg.discretized:
            return discrete_view(heading, elevation)
        return continuous_view(heading, elevation, self.cfg.elevation_limits)

    def start(self, starts: Sequence[tuple[NavTable, Crowd, str, float, float]]) -> None:
        """New episodes: ``(table, crowd, viewpoint, heading, elevation)`` per element.

        With ``reactions`` on, each element's people are its own: they react to that
        element's body alone.
        """
        elements = []
        for table, crowd, _, h, e in starts:
            reacting = self.reactions is not None and len(crowd) > 0
            if reacting:
                from havln_mj.humans.reactions import ReactiveCrowd  # only when people react

                crowd = ReactiveCrowd(crowd, self.reactions)
            el = Element(table, crowd, self.kind.body(table.scan_id, table.graph, crowd))
            if reacting:
                el.body.observe = _observer(crowd)
            el.heading, el.elevation, _ = self.view(h, e)
            elements.append(el)
        self.elements = elements
        self._prepare_step()
        shared = self._tick(self._clock.after_start)
        started = []
        for i, (el, start) in enumerate(zip(elements, starts, strict=True)):
            el.people_t = shared if shared is not None else el.time
            el.film = self._new_film(i, el)
            outcome = el.body.start(start[2], el.heading, el.elevation, 0.0)
            started.append((el, outcome, None, el.elevation, 0))
        self._settle_all(started, starting=True)

    def _tick(self, advance: Callable[[int], int]) -> float | None:
        """Advances HA3D's shared counter and returns the people's time (None: own clocks)."""
        if self._continuous:
            return None
        self.frame = advance(self.frame)
        return self._clock.seconds(self.frame)

    def _new_film(self, i: int, el: Element) -> Film | None:
        if self.film is None or not self.cfg.rendering:
            return None
        fps, callback, cameras = self.film

        def draw(t: float) -> None:
            t0 = time.perf_counter()
            settings = self.cfg.view_settings()
            # On HA3D's clock people hold the pose of the state the action leads to.
            people_t = t if self._continuous else el.people_t
            views = [el.body.render(settings, el.elevation, people_t)]
            views += [el.body.render(settings, 0.0, people_t, cam) for cam in cameras]
            self.timers["render"] += time.perf_counter() - t0
            self.timers["frames"] += len(views)
            callback(i, t, views, np.asarray(el.body.pose(), float))

        return Film(fps, draw)

    def apply(
        self, actions: list[tuple[int, int, float, float]], waits: Sequence[float] | None = None
    ) -> None:
        """Move, then rotate, for each (element, index, dh, de); ``waits`` override WAIT_S.

        Measured along the actions, the collision signal of every element with people is
        computed in one call once they have all moved.
        """
        cfg = self.cfg
        if cfg.revision != self._revision:
            self._prepare_step()
        shared = None
        if not self._continuous and actions:
            shared = self._tick(self._clock.after_action)
        discretized, (lo, hi) = cfg.discretized, cfg.elevation_limits
        along = self.rule.check == "action"
        elements, deferred = self.elements, []
        for n, (i, k, dh, de) in enumerate(actions):
            el = elements[i]
            if shared is not None:
                el.people_t = shared
            if discretized:
                dh = discrete_delta(dh, HEADING_INCREMENT)
                de = discrete_delta(de, ELEVATION_INCREMENT)
                heading, elevation, index = discrete_view(el.heading + dh, el.elevation + de)
            else:
                heading = math.fmod(el.heading + dh, TWO_PI)  # wrap_heading, inlined
                if heading < 0.0:
                    heading += TWO_PI
                    if heading >= TWO_PI:
                        heading = 0.0
                elevation, index = el.elevation + de, 0
                if elevation < lo:  # clamped, without min/max calls (hot)
                    elevation = lo
                elif elevation > hi:
                    elevation = hi
            outcome = el.body.move(
                el.navigable[k].viewpointId,
                heading,
                elevation,
                el.time,
                WAIT_S if waits is None else waits[n],
                el.film,
            )
            if not el.people:
                self._settle(el, outcome, heading, elevation, index, NO_PROXIMITY)
            elif not along:
                self._settle(el, outcome, heading, elevation, index, None)
            elif len(actions) == 1:  # one element moved (hot): its signal, then its state
                threshold = self.rule.threshold
                contact = knots_proximity(el.crowd, outcome[1], threshold, self._near)
                self._settle(el, outcome, heading, elevation, index, contact)
            else:
                deferred.append((el, outcome, heading, elevation, index))
        if deferred:
            self._settle_all(deferred)

    def apply_one(self, indices: object, headings: object, elevations: object) -> bool:
        """``makeAction``'s arguments for a batch of one, applied as :meth:`apply` would.

        The hot path of agents stepping one element on its own clock with continuous views,
        with the values agents pass: one-entry lists of an int in range and finite floats.
        Anything else (another batch size or type, a discretised view, HA3D's shared clock)
        returns False, nothing changed, for the caller to check and :meth:`apply`.
        """
        cfg = self.cfg
        if cfg.revision != self._revision:
            self._prepare_step()
        lists = type(indices) is list and type(headings) is list and type(elevations) is list
        if not lists or cfg.discretized or not self._continuous:
            return False
        try:
            (el,), (k,), (dh,), (de,) = self.elements, indices, headings, elevations
        except ValueError:
            return False
        # A float is finite when x - x is 0 (inf - inf and NaN give NaN), with no call.
        if not (
            type(k) is int
            and type(dh) is float
            and type(de) is float
            and dh - dh == 0.0
            and de - de == 0.0
            and 0 <= k < len(el.navigable)
        ):
            return False
        heading = _fmod(el.heading + dh, TWO_PI)  # as apply wraps and clamps, inlined
        if heading < 0.0:
            heading += TWO_PI
            if heading >= TWO_PI:
                heading = 0.0
        lo, hi = cfg.elevation_limits
        elevation = el.elevation + de
        if elevation < lo:
            elevation = lo
        elif elevation > hi:
            elevation = hi
        outcome = el.body.move(
            el.navigable[k].viewpointId, heading, elevation, el.time, WAIT_S, el.film
        )
        if not el.people:
            contact = NO_PROXIMITY
        elif self.rule.check == "action":
            contact = knots_proximity(el.crowd, outcome[1], self.rule.threshold, self._near)
        else:
            contact = None
        self._settle(el, outcome, heading, elevation, 0, contact)
        return True

    def robot(self, actions: Sequence[str]) -> None:
        """A robot action per element (``"stop"`` leaves it alone)."""
        self._prepare_step()
        shared = self._tick(self._clock.after_action)
        moved = []
        for el, act in zip(self.elements, actions, strict=True):
            if act != "stop":
                if shared is not None:
                    el.people_t = shared
                outcome = el.body.robot_action(act, el.time, el.film)
                moved.append((el, outcome, None, el.elevation, 0))
        self._settle_all(moved)

    def _prepare_step(self) -> None:
        """What every element's state needs this step: navigation rule, view, blank images.

        Derived once per change of the settings (the camera may change between steps).
        """
        cfg = self.cfg
        if cfg.revision != self._revision:
            self._revision = cfg.revision
            self._cos_fov = cfg.cos_half_hfov()
            self._view = self.format.settings(cfg.view_settings())
            self._blank = None if cfg.rendering else self.format.blank(cfg.width, cfg.height)

    def _settle_all(self, moved: list[tuple], starting: bool = False) -> None:
        """Settles each ``(element, outcome, heading asked, elevation, view index)``.

        Measured along the actions, the collision signal of all of them is computed in one
        call; measured in the states, each after its state's view.
        """
        contacts: list[Proximity | None]
        if self.rule.check == "action":
            if len(moved) == 1:  # a batch of one (hot)
                el, outcome = moved[0][0], moved[0][1]
                contact = knots_proximity(el.crowd, outcome.knots, self.rule.threshold, self._near)
                self._settle(*moved[0], contact, starting)
                return
            tracks = [(m[0].crowd, m[1].knots) for m in moved]
            contacts = batch_proximity(tracks, self.rule.threshold, self._near)
        else:
            contacts = [None if m[0].people else NO_PROXIMITY for m in moved]
        for m, contact in zip(moved, contacts, strict=True):
            self._settle(*m, contact, starting)

    def _settle(
        self,
        el: Element,
        outcome: Outcome,
        heading: float | None,
        elevation: float,
        index: int,
        contact: Proximity | None,
        starting: bool = False,
    ) -> None:
        """Advances ``el``'s clock and view by ``outcome`` and publishes its state.

        ``heading`` is the heading the action asked for (None: the view rules are applied to
        the body's heading, as for robot actions and starts); ``contact`` the collision
        signal (None: measured in the state reached, by the batch's rule).
        """
        duration, _, viewpoint, body_heading, arrived, fell, diverged, contacts, _ = outcome
        t = el.time
        if not starting:
            el.time = t = t + duration
            el.step += 1
        if self._continuous:
            el.people_t = t
        el.people_xyz = None
        if heading is None or body_heading != heading:
            heading, elevation, index = self.view(body_heading, elevation)
        el.heading, el.elevation, el.view_index = heading, elevation, index
        el.navigable = navigable = el.table.candidates(viewpoint, heading, elevation, self._cos_fov)
        if contact is None:
            contact = self._contact(el, outcome)
        crushed, crushed_by, min_distance = contact
        blank = self._blank
        if blank is None:
            if starting and el.film is not None:
                el.film.tick(t)
            rgb, depth, mask, semantic, instance = self._images(el)
        else:
            rgb, depth = blank
            mask = semantic = instance = None
        el.state = make(
            SimState,
            (
                el.table.scan_id,
                el.step,
                rgb,
                depth,
                navigable[0],
                heading,
                elevation,
                index,
                navigable,
                t,
                1 if crushed else 0,
                crushed_by,
                min_distance,
                mask,
                el.body.pose(),
                fell,
                contacts,
                arrived,
                diverged,
                semantic,
                instance,
            ),
        )

    def _contact(self, el: Element, outcome: Outcome) -> Proximity:
        """The collision signal of the state just reached, by a rule measuring in states.

        (A rule measuring along actions is computed for the whole batch: :meth:`_settle_all`.)
        """
        rule = self.rule
        if rule.distance == "camera_3d":
            camera = el.navigable[0].position
            return state_proximity(self.collision_points(el), camera, rule.threshold)
        base = np.asarray(outcome.knots, float).reshape(-1, 4)[-1, 1:]
        return knots_proximity(el.crowd, [(el.people_t, *base)], rule.threshold)

    def people_at(self, el: Element) -> np.ndarray:
        """Element ``el``'s people's pelvis positions ``(P, 3)`` as its state has them."""
        if el.people_xyz is None:
            el.people_xyz = el.crowd.positions(np.array([el.people_t]))[0]
        return el.people_xyz

    def collision_points(self, el: Element) -> np.ndarray:
        """The people as the collision rule measures them: pelvis positions or HA3D's points."""
        if self.rule.distance == "camera_3d":
            return ha3d_points(el.crowd, self.people_at(el))
        return self.people_at(el)

    def _images(self, el: Element) -> tuple:
        cfg = self.cfg
        if not cfg.rendering:
            return (*self.format.blank(cfg.width, cfg.height), None, None, None)
        t0 = time.perf_counter()
        view = el.body.render(self._view, el.elevation, el.people_t)  # (_prepare_step's)
        images = self.format.images(view)
        self.timers["render"] += time.perf_counter() - t0
        self.timers["frames"] += 1
        return images


def _observer(crowd) -> Callable:
    """Tells a reactive crowd where the body went, sampled as the collision signal is."""

    def observe(knots) -> None:
        times, positions = sample_knots(np.asarray(knots, float).reshape(-1, 4))
        crowd.observe_agent(times, positions[:, :2])

    return observe
