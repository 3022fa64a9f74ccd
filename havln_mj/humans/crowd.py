"""The people of a scene as a function of simulated time.

Each person plays a looping clip (see :mod:`havln_mj.humans.clip`) from their own start
offset, placed in the world by an anchor (a floor point and a heading). The crowd answers
what the simulator and renderer ask: pelvis positions at many times (for the collision
signal), full joint poses at one time (for drawing), and each person's state (position,
heading, velocity, activity, region). It satisfies :class:`havln_mj.sim.crowd.Crowd`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.humans import rotations as rot
from havln_mj.humans.body import BodyShape
from havln_mj.humans.clip import Clip
from havln_mj.humans.segments import segment_orientations
from havln_mj.humans.skeleton import JOINT, forward_kinematics
from havln_mj.humans.skinned import Skin


@dataclass(frozen=True)
class Person:
    """One person in a scene.

    Attributes:
        shape: Body size and colours.
        clip: The looping motion, in the anchor frame.
        anchor: Floor point ``(x, y, z)`` the clip's origin is placed at (world, metres).
        heading: Direction the clip's +y faces (radians, from +y turning right).
        activity: Activity id (from the catalog, or the source motion's name).
        text: What the person is doing, in words.
        region: Region label code of where they are.
        viewpoint: The viewpoint they were placed at ("" if none).
        start: Seconds into the clip at simulated time 0 (so people are not in step).
        offsets: Rest joint offsets the clip is posed with (default: the skin's, else the
            body's own).
        skin: An SMPL model and shape to draw this person as a skinned mesh instead of the
            built-in body (needs a rotation clip).
    """

    shape: BodyShape
    clip: Clip
    anchor: np.ndarray
    heading: float
    activity: str
    text: str = ""
    region: str = "-"
    viewpoint: str = ""
    start: float = 0.0
    offsets: np.ndarray | None = None
    skin: Skin | None = None

    def __post_init__(self) -> None:
        if self.skin is not None and self.clip.local is None:
            raise InvalidArgumentError(
                f"person doing {self.activity!r}: a skinned mesh needs joint rotations, but "
                "the clip has joint positions only (segment mode)"
            )

    @property
    def rest_offsets(self) -> np.ndarray:
        """The offsets used for forward kinematics."""
        if self.offsets is not None:
            return self.offsets
        return self.skin.offsets if self.skin is not None else self.shape.offsets


@dataclass(frozen=True)
class PersonState:
    """A person at one instant (what ``getHumanState`` reports).

    Attributes:
        position: Pelvis position ``(3,)``.
        heading: Facing direction of the pelvis (radians, from +y turning right).
        velocity: Pelvis velocity ``(3,)`` in m/s.
        activity: Activity id.
        text: The activity in words.
        region: Region label code.
    """

    position: np.ndarray
    heading: float
    velocity: np.ndarray
    activity: str
    text: str
    region: str


class Crowd:
    """People whose poses are a function of simulated time."""

    def __init__(self, people: list[Person]) -> None:
        self.people = list(people)
        self._anchor = np.array([p.anchor for p in self.people], float).reshape(-1, 3)
        self._yaw = rot.from_heading(np.array([p.heading for p in self.people], float))
        self._yaw_m = rot.to_matrix(self._yaw)
        self._start = np.array([p.start for p in self.people], float)
        self._offsets = np.array([p.rest_offsets for p in self.people], float).reshape(-1, 24, 3)
        # Every pelvis track in one table, so collision queries sample all people at once.
        clips = [p.clip for p in self.people]
        self._roots = np.concatenate([c.root for c in clips]) if clips else np.zeros((0, 3))
        self._base = np.cumsum([0] + [c.frames for c in clips[:-1]]).astype(int)
        self._fps = np.array([c.fps for c in clips], float)
        self._last = np.array([c.frames - 1 for c in clips], float)
        self._loop = np.array([c.loop_start for c in clips], float)
        self._rotational = [k for k, p in enumerate(self.people) if p.clip.local is not None]
        # A circle around each person's whole pelvis track, for cheap far-away checks.
        self._centres = np.zeros((len(clips), 2))
        self._radii = np.zeros(len(clips))
        for k, clip in enumerate(clips):
            xy = (self._anchor[k] + clip.root @ self._yaw_m[k].T)[:, :2]
            self._centres[k] = (xy.min(axis=0) + xy.max(axis=0)) / 2
            self._radii[k] = np.linalg.norm(xy - self._centres[k], axis=1).max()
        self._segments = [k for k, p in enumerate(self.people) if p.clip.local is None]

    def __len__(self) -> int:
        return len(self.people)

    @property
    def shapes(self) -> list[BodyShape]:
        """Each person's body."""
        return [p.shape for p in self.people]

    def positions(self, times: np.ndarray, people: np.ndarray | None = None) -> np.ndarray:
        """Pelvis positions ``(len(times), P, 3)`` at the given simulated seconds.

        Args:
            times: Simulated seconds.
            people: Indices of the people wanted (default: everyone, in order).
        """
        times = np.atleast_1d(np.asarray(times, float))
        k = slice(None) if people is None else np.asarray(people, int)
        return self.positions_at(times[:, None] + np.zeros(len(self._start[k])), k)

    def positions_at(self, clock: np.ndarray, people: slice | np.ndarray) -> np.ndarray:
        """Pelvis positions ``(n, P, 3)`` with each person's own clock ``(n, P)`` (seconds).

        ``people`` selects the P people (a slice or indices); a person's clock replaces the
        simulated time (reacting people run late, see :mod:`havln_mj.humans.reactions`).
        """
        k = people
        # Clip.frame_time for all people at once: loop from loop_start past the last frame
        # (simulated time and start offsets are never negative).
        f = (clock + self._start[k]) * self._fps[k]
        last, loop = self._last[k], self._loop[k]
        period = last - loop
        wrapped = loop + np.mod(f - loop, np.maximum(period, 1.0))
        f = np.where(f > last, np.where(period > 0, wrapped, last), f)
        i0 = f.astype(int)
        w = (f - i0)[..., None]
        base = self._base[k]
        r0 = self._roots[base + i0]
        root = r0 + w * (self._roots[base + np.minimum(i0 + 1, last.astype(int))] - r0)
        # Turn by each anchor's heading (about z) and place it.
        c, s = self._yaw_m[k, 0, 0], self._yaw_m[k, 1, 0]
        out = np.empty_like(root)
        out[..., 0] = c * root[..., 0] - s * root[..., 1]
        out[..., 1] = s * root[..., 0] + c * root[..., 1]
        out[..., 2] = root[..., 2]
        return out + self._anchor[k]

    def footprint(self) -> tuple[np.ndarray, np.ndarray]:
        """Circles ``(centres (N, 2), radii (N,))`` holding each pelvis at all times."""
        return self._centres, self._radii

    def pose(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """World joint positions ``(N, 24, 3)`` and orientations ``(N, 24, 4)`` at time ``t``."""
        return self.pose_at(np.full(len(self.people), float(t)))

    def pose_at(self, clock: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World joint poses (as :meth:`pose`) with each person's own clock ``(N,)``."""
        n = len(self.people)
        pos = np.empty((n, 24, 3))
        quat = np.empty((n, 24, 4))
        if self._rotational:
            ks = self._rotational
            local, root_w = self._world_rooted(ks, clock)
            pos[ks], quat[ks] = forward_kinematics(self._offsets[ks], local, root_w)
        for k in self._segments:
            joints, _ = self.people[k].clip.sample(clock[k] + self._start[k])
            world = self._anchor[k] + joints @ self._yaw_m[k].T
            pos[k] = world
            quat[k] = segment_orientations(world, self._offsets[k])
        return pos, quat

    def _world_rooted(self, ks: list[int], t: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Poses of people ``ks`` (rotation clips) at time ``t`` (or clocks ``(N,)``), rooted.

        Returns:
            Local rotations ``(K, 24, 4)`` with the pelvis turned into the world, and world
            pelvis positions ``(K, 3)``.
        """
        q0, q1, w, root = [], [], [], []
        clock = np.broadcast_to(np.asarray(t, float), (len(self.people),))
        for k in ks:
            clip = self.people[k].clip
            i0, i1, wk = clip.blend_frames(float(clock[k] + self._start[k]))
            q0.append(clip.local[i0])
            q1.append(clip.local[i1])
            w.append(wk)
            root.append(clip.root[i0] + wk * (clip.root[i1] - clip.root[i0]))
        # Neighbouring frames are close: nlerp is slerp to within 0.1° here, and much cheaper.
        local = rot.nlerp(np.array(q0), np.array(q1), np.array(w)[:, None])
        # Place the pelvis in the world, then the rest follows through the kinematic tree.
        local[:, 0] = rot.mul(self._yaw[ks], local[:, 0])
        root_w = self._anchor[ks] + np.einsum("kij,kj->ki", self._yaw_m[ks], np.array(root))
        return local, root_w

    @property
    def skins(self) -> list[Skin | None]:
        """Each person's SMPL skin, or None for the built-in body."""
        return [p.skin for p in self.people]

    def skin_vertices(self, t: float) -> dict[int, np.ndarray]:
        """World mesh vertices ``(V, 3)`` of each skinned person at time ``t``."""
        ks = [k for k, skin in enumerate(self.skins) if skin is not None]
        if not ks:
            return {}
        local, root_w = self._world_rooted(ks, t)
        out = {}
        for i, k in enumerate(ks):
            skin = self.people[k].skin
            out[k] = skin.model.skin(skin.betas, local[i], root_w[i])
        return out

    def states(self, t: float, dt: float = 0.05) -> list[PersonState]:
        """Everyone's state at time ``t`` (velocity by a central difference over ``dt``)."""
        if not self.people:
            return []
        around = self.positions(np.array([t - dt / 2, t, t + dt / 2]))
        _, quat = self.pose(t)
        forward = rot.rotate(quat[:, JOINT["pelvis"]], np.array([0.0, 1.0, 0.0]))
        out = []
        for k, p in enumerate(self.people):
            heading = math.atan2(forward[k, 0], forward[k, 1]) % (2 * math.pi)
            out.append(
                PersonState(
                    around[1, k].copy(),
                    heading,
                    (around[2, k] - around[0, k]) / dt,
                    p.activity,
                    p.text,
                    p.region,
                )
            )
        return out
