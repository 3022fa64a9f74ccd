"""The running batch: each element's body, view, clock and state, stepped through the Body seam.

:class:`Batch` is the simulator's runtime (the simulator itself checks the MatterSim API's
arguments): it starts the elements' bodies, turns graph actions into body moves under the view
rules (discretised or continuous), advances each element's clock by what its body reports,
computes the collision signal along the body's track, renders the state through the frame
pipeline and, when a film is set, frames during actions.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

import numpy as np

from havln_mj.sim.body import Body, BodyKind, Film, Outcome
from havln_mj.sim.crowd import NO_PROXIMITY, Crowd, knots_proximity, sample_knots
from havln_mj.sim.frame import View
from havln_mj.sim.images import ImageFormat
from havln_mj.sim.navigation import NavTable
from havln_mj.sim.settings import Settings
from havln_mj.sim.state import SimState, ViewPoint
from havln_mj.sim.viewing import (
    ELEVATION_INCREMENT,
    HEADING_INCREMENT,
    continuous_view,
    discrete_delta,
    discrete_view,
)

WAIT_S = 1.0  # seconds a "stay" action without rotation lasts

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
        "state",
        "step",
        "table",
        "time",
        "view_index",
    )

    def __init__(self, table: NavTable, crowd: Crowd, body: Body) -> None:
        self.table, self.crowd, self.body = table, crowd, body
        self.heading = self.elevation = self.time = 0.0
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
        collision_distance: HA-VLN's collision threshold (metres, horizontal).
        timers: The simulator's timers (rendering time and frames are added).
    """

    def __init__(
        self,
        cfg: Settings,
        kind: BodyKind,
        image_format: ImageFormat,
        collision_distance: float,
        timers: dict,
    ) -> None:
        self.cfg, self.kind, self.format = cfg, kind, image_format
        self.collision_distance = collision_distance
        self.timers = timers
        self.elements: list[Element] = []
        self.film: tuple[float, FilmCallback, tuple[str, ...]] | None = None
        self.reactions = None  # how people react to the agent (None: they do not)

    def view(self, heading: float, elevation: float) -> tuple[float, float, int]:
        """Heading, elevation and view index under the view rules."""
        if self.cfg.discretized:
            return discrete_view(heading, elevation)
        return continuous_view(heading, elevation, self.cfg.elevation_limits)

    def start(self, starts: Sequence[tuple[NavTable, Crowd, str, float, float]]) -> None:
        """New episodes: ``(table, crowd, viewpoint, heading, elevation)`` per element.

        With :attr:`reactions` on, each element's people are its own: they react to that
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
        for i, (el, start) in enumerate(zip(elements, starts, strict=True)):
            el.film = self._new_film(i, el)
            outcome = el.body.start(start[2], el.heading, el.elevation, 0.0)
            self.finish(i, outcome, el.elevation, starting=True)

    def _new_film(self, i: int, el: Element) -> Film | None:
        if self.film is None or not self.cfg.rendering:
            return None
        fps, callback, cameras = self.film

        def draw(t: float) -> None:
            t0 = time.perf_counter()
            settings = self.cfg.view_settings()
            views = [el.body.render(settings, el.elevation, t)]
            views += [el.body.render(settings, 0.0, t, cam) for cam in cameras]
            self.timers["render"] += time.perf_counter() - t0
            self.timers["frames"] += len(views)
            callback(i, t, views, np.asarray(el.body.pose(), float))

        return Film(fps, draw)

    def apply(
        self, actions: list[tuple[int, int, float, float]], waits: Sequence[float] | None = None
    ) -> None:
        """Move, then rotate, for each (element, index, dh, de); ``waits`` override WAIT_S."""
        discretized, limits = self.cfg.discretized, self.cfg.elevation_limits
        for n, (i, k, dh, de) in enumerate(actions):
            el = self.elements[i]
            if discretized:
                dh = discrete_delta(dh, HEADING_INCREMENT)
                de = discrete_delta(de, ELEVATION_INCREMENT)
                heading, elevation, _ = discrete_view(el.heading + dh, el.elevation + de)
            else:
                heading, elevation, _ = continuous_view(el.heading + dh, el.elevation + de, limits)
            target = el.navigable[k].viewpointId
            wait_s = WAIT_S if waits is None else waits[n]
            outcome = el.body.move(target, heading, elevation, el.time, wait_s, el.film)
            self.finish(i, outcome, elevation)

    def robot(self, actions: Sequence[str]) -> None:
        """A robot action per element (``"stop"`` leaves it alone)."""
        for i, (el, act) in enumerate(zip(self.elements, actions, strict=True)):
            if act != "stop":
                self.finish(i, el.body.robot_action(act, el.time, el.film), el.elevation)

    def finish(self, i: int, outcome: Outcome, elevation: float, starting: bool = False) -> None:
        """Advances element ``i``'s clock and view by ``outcome`` and publishes its state."""
        el = self.elements[i]
        if not starting:
            el.time += outcome.duration
            el.step += 1
        el.heading, el.elevation, el.view_index = self.view(outcome.heading, elevation)
        el.navigable = el.table.candidates(
            outcome.viewpoint, el.heading, el.elevation, self.cfg.cos_half_hfov()
        )
        contact = NO_PROXIMITY
        if len(el.crowd):
            contact = knots_proximity(el.crowd, outcome.knots, self.collision_distance)
        if starting and el.film is not None:
            el.film.tick(el.time)
        rgb, depth, mask = self._images(el)
        el.state = SimState(
            el.table.scan_id,
            el.step,
            rgb,
            depth,
            el.navigable[0],
            el.heading,
            el.elevation,
            el.view_index,
            el.navigable,
            el.time,
            int(contact.crushed),
            contact.people,
            contact.min_distance,
            mask,
            el.body.pose(),
            outcome.fell,
            outcome.contacts,
            outcome.arrived,
            outcome.diverged,
        )

    def _images(self, el: Element) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        cfg = self.cfg
        if not cfg.rendering:
            return (*self.format.blank(cfg.width, cfg.height), None)
        t0 = time.perf_counter()
        view = el.body.render(self.cfg.view_settings(), el.elevation, el.time)
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
