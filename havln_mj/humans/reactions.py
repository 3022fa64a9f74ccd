"""People who notice the agent: walkers yield, others glance at it.

A :class:`ReactiveCrowd` wraps a :class:`~havln_mj.humans.crowd.Crowd` and stays a pure
function of (simulated time, the agent's track so far). The simulator hands it the track
explicitly with :meth:`ReactiveCrowd.observe_agent` (the agent's sampled positions of each
action, before asking about that action) and clears it with :meth:`forget_agent` at a new
episode; before the first sample and after the last one the agent is taken to stand where it
was seen first and last. Without a track, or with reactions off, it answers exactly as the
wrapped crowd.

* **Yielding** (people whose clip walks): each walker runs on its own clock, which stops
  while the walker's next step (:data:`STEP_S` ahead on its path) would bring its pelvis
  closer to the agent than ``comfort`` metres, and runs on once the way is clear. A walker
  thus waits in front of a robot standing in a corridor, at least ``comfort`` away, and never
  leaves its own track, so each person's footprint (and the collision signal's pruning) is
  unchanged.
* **Glancing** (everyone, drawing only): within ``glance`` metres a person turns their head
  toward the agent (at most :data:`MAX_GLANCE_RAD` from where they face); the pelvis is not
  moved, so the collision signal does not depend on it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.humans import rotations as rot
from havln_mj.humans.crowd import Crowd, PersonState
from havln_mj.humans.skeleton import JOINT

STEP_S = 0.1  # seconds: a walker's clock is advanced (or held) in steps this long
WALKER_RANGE_M = 0.5  # a clip whose pelvis roams farther than this walks
MAX_GLANCE_RAD = 1.2  # how far a head turns toward the agent


@dataclass(frozen=True)
class Reactions:
    """How people react to the agent.

    Attributes:
        enabled: Whether they react at all (off: exactly the wrapped crowd).
        comfort: Distance (m, horizontal, pelvis to agent) a walker will not step inside.
        glance: Distance (m) within which people turn their heads toward the agent.
    """

    enabled: bool = True
    comfort: float = 1.5
    glance: float = 3.5

    def __post_init__(self) -> None:
        if not (self.comfort > 0 and self.glance >= 0):
            raise InvalidArgumentError(
                f"reactions need comfort > 0 and glance ≥ 0 m, got {self.comfort}, {self.glance}"
            )


class ReactiveCrowd:
    """A crowd that reacts to the agent's track (satisfies ``havln_mj.sim.crowd.Crowd``)."""

    def __init__(self, crowd: Crowd, reactions: Reactions | None = None) -> None:
        self.crowd = crowd
        self.reactions = reactions or Reactions()
        self.people = crowd.people
        roots = [p.clip.root for p in crowd.people]
        self._walkers = np.array(
            [k for k, r in enumerate(roots) if np.ptp(r[:, :2], axis=0).max() > WALKER_RANGE_M],
            dtype=int,
        )
        self.forget_agent()

    # ------------------------------------------------------------------ the agent's track

    def forget_agent(self) -> None:
        """Clears the agent's track (a new episode)."""
        self._track_t = np.zeros(0)
        self._track_xy = np.zeros((0, 2))
        self._clock = np.zeros((1, len(self._walkers)))  # walker clocks at k · STEP_S

    def observe_agent(self, times: np.ndarray, xy: np.ndarray) -> None:
        """Appends the agent's positions ``xy (n, 2)`` (or ``(n, 3)``) at ``times (n,)``.

        Raises:
            InvalidArgumentError: Times decrease, or come before what was already observed.
        """
        times = np.atleast_1d(np.asarray(times, float))
        xy = np.asarray(xy, float).reshape(len(times), -1)[:, :2]
        last = self._track_t[-1] if len(self._track_t) else -math.inf
        if np.any(np.diff(times) < 0) or (len(times) and times[0] < last):
            raise InvalidArgumentError(
                f"agent samples must come in time order after t = {last}, got {times[:3]}..."
            )
        self._track_t = np.concatenate([self._track_t, times])
        self._track_xy = np.concatenate([self._track_xy, xy])
        # Clock steps after the earliest changed agent position must be recomputed.
        keep = math.floor(max(last, 0.0) / STEP_S) + 1 if last > -math.inf else 1
        self._clock = self._clock[: max(keep, 1)]

    def agent_at(self, t: float | np.ndarray) -> np.ndarray | None:
        """The agent's position(s) ``(..., 2)`` at ``t`` (held outside the track), or None."""
        if not len(self._track_t):
            return None
        t = np.asarray(t, float)
        return np.stack(
            [np.interp(t, self._track_t, self._track_xy[:, i]) for i in range(2)], axis=-1
        )

    # ------------------------------------------------------------------ clocks

    def _active(self) -> bool:
        return self.reactions.enabled and len(self._track_t) > 0

    def clocks(self, times: np.ndarray) -> np.ndarray:
        """Each person's clock ``(len(times), N)`` at the given simulated times."""
        times = np.atleast_1d(np.asarray(times, float))
        out = np.repeat(times[:, None], len(self.people), axis=1)
        if not self._active() or not len(self._walkers):
            return out
        self._extend(float(times.max()))
        grid = np.clip(times / STEP_S, 0.0, None)
        i = np.minimum(grid.astype(int), len(self._clock) - 2)
        frac = (grid - i)[:, None]
        c0, c1 = self._clock[i], self._clock[i + 1]
        out[:, self._walkers] = c0 + frac * (c1 - c0)
        return out

    def _extend(self, t: float) -> None:
        """Computes walker clocks on the step grid up to past ``t``."""
        need = math.floor(max(t, 0.0) / STEP_S) + 2
        comfort = self.reactions.comfort
        w = self._walkers
        while len(self._clock) < need:
            s = (len(self._clock) - 1) * STEP_S
            clock = self._clock[-1]
            agent = self.agent_at(s)
            here = self.crowd.positions_at(clock[None], w)[0, :, :2]
            ahead = self.crowd.positions_at(clock[None] + STEP_S, w)[0, :, :2]
            d_here = np.linalg.norm(here - agent, axis=1)
            d_ahead = np.linalg.norm(ahead - agent, axis=1)
            blocked = (d_ahead < comfort) & (d_ahead < d_here)
            self._clock = np.concatenate(
                [self._clock, (clock + np.where(blocked, 0, STEP_S))[None]]
            )

    # ------------------------------------------------------------------ the Crowd protocol

    def __len__(self) -> int:
        return len(self.people)

    @property
    def shapes(self) -> list:
        """Each person's body."""
        return self.crowd.shapes

    @property
    def skins(self) -> list:
        """Each person's SMPL skin or None."""
        return self.crowd.skins

    def footprint(self) -> tuple[np.ndarray, np.ndarray]:
        """The wrapped crowd's footprints (yielding keeps people on their tracks)."""
        return self.crowd.footprint()

    def positions(self, times: np.ndarray, people: np.ndarray | None = None) -> np.ndarray:
        """Pelvis positions ``(len(times), P, 3)``, walkers yielding to the agent."""
        clocks = self.clocks(times)
        k = np.arange(len(self.people)) if people is None else np.asarray(people, int)
        return self.crowd.positions_at(clocks[:, k], k)

    def pose(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """World joint poses at ``t``: yielding walkers, heads turned toward a near agent."""
        pos, quat = self.crowd.pose_at(self.clocks(np.array([t]))[0])
        agent = self.agent_at(t) if self._active() else None
        if agent is not None and self.reactions.glance > 0:
            quat = quat.copy()
            _glance(pos, quat, agent, self.reactions.glance)
        return pos, quat

    def skin_vertices(self, t: float) -> dict:
        """SMPL-skinned vertices (heads not turned: skins follow the clips)."""
        return self.crowd.skin_vertices(t)

    def states(self, t: float, dt: float = 0.05) -> list[PersonState]:
        """Everyone's state at ``t`` (as the wrapped crowd's, with yielding)."""
        if not self.people:
            return []
        around = self.positions(np.array([t - dt / 2, t, t + dt / 2]))
        _, quat = self.crowd.pose_at(self.clocks(np.array([t]))[0])
        forward = rot.rotate(quat[:, JOINT["pelvis"]], np.array([0.0, 1.0, 0.0]))
        return [
            PersonState(
                around[1, k].copy(),
                math.atan2(forward[k, 0], forward[k, 1]) % (2 * math.pi),
                (around[2, k] - around[0, k]) / dt,
                p.activity,
                p.text,
                p.region,
            )
            for k, p in enumerate(self.people)
        ]


def _glance(pos: np.ndarray, quat: np.ndarray, agent: np.ndarray, reach: float) -> None:
    """Turns heads (in place) toward ``agent`` for people within ``reach`` metres."""
    head = JOINT["head"]
    to_agent = agent - pos[:, head, :2]
    dist = np.linalg.norm(to_agent, axis=1)
    forward = rot.rotate(quat[:, head], np.array([0.0, 1.0, 0.0]))
    facing = np.arctan2(forward[:, 0], forward[:, 1])
    wanted = np.arctan2(to_agent[:, 0], to_agent[:, 1])
    turn = np.mod(wanted - facing + np.pi, 2 * np.pi) - np.pi
    near = (dist < reach) & (np.abs(turn) < MAX_GLANCE_RAD + 0.6)  # not behind their back
    weight = np.clip((reach - dist) / 0.5, 0.0, 1.0)
    angle = np.where(near, weight * np.clip(turn, -MAX_GLANCE_RAD, MAX_GLANCE_RAD), 0.0)
    quat[:, head] = rot.mul(rot.from_heading(angle), quat[:, head])
