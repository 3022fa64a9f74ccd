"""Terrain-aware trot: footholds on the scanned ground, swings over it, trunk following it.

Everything is planned in the world frame (the estimator's), reading the ground through a
:class:`~havln_mj.robot.go1.height_scan.HeightScan`:

* **Rhythm.** A trot; on rough ground (an edge or a climb in the scan around the trunk) a
  slower one with both diagonal pairs down for part of the cycle, and a speed cap that
  already holds while rough ground lies ahead. The rhythm changes when all feet are down.
* **Trunk reference.** Position and yaw advance with the commanded twist and leak toward
  the estimate (a stiff hold rings at the gait's rhythm); height and pitch follow the line
  through the feet (stance feet where they stand, swing feet where they go), low-pass
  filtered. Integrators on height, pitch and roll take up what the position-controlled legs
  give under load.
* **Stance feet** hold the world point where they touched down; their joint targets put the
  trunk at the reference (leg IK from the reference trunk frame), with a feed-forward
  carrying the robot's weight (Jᵀf) and cancelling joint damping and friction.
* **Swing feet** fly from lift-off to a foothold (:mod:`~havln_mj.robot.go1.footholds`): the
  Raibert point of the commanded twist, moved off edges; the foot keeps a clearance over the
  ground it crosses. It is tracked in the actual trunk frame with the same feed-forward plus
  gravity, which cuts the swing lag of the position actuators from 5-10 cm to 1-3 cm. A foot
  touching near its foothold lands; one that finds no ground keeps reaching down.
"""

from __future__ import annotations

import math

import mujoco

from havln_mj.robot.go1 import constants as const
from havln_mj.robot.go1.actuation import Tracker
from havln_mj.robot.go1.footholds import NEAR, is_rough, standing_pose
from havln_mj.robot.go1.frames import roll_pitch, rotation, to_body, to_world
from havln_mj.robot.go1.gains import TerrainGains
from havln_mj.robot.go1.height_scan import HeightScan
from havln_mj.robot.go1.kinematics import leg_fk, leg_ik
from havln_mj.robot.go1.swing import Swing, raibert_point

TROT_OFFSETS = (0.0, 0.5, 0.5, 0.0)  # FR, FL, RR, RL phase offsets
_WEIGHT = const.TOTAL_MASS * 9.81
_FAR = tuple(0.5 + 0.04 * k for k in range(20))  # where it caps the speed (m ahead)


class TerrainGait:
    """Gait generator on scanned terrain: twist in, 12 joint targets out.

    Same calling pattern as :class:`~havln_mj.robot.go1.gait.TrotGait`: :meth:`start`,
    :meth:`step` every control tick, :meth:`request_stop`; ``walking`` turns false once
    every foot is down after a stop. :meth:`reset` after a teleport.

    Args:
        gains: The terrain gait's gains.
        data: The robot's data.
        est: The trunk state estimator (``x, y, z, yaw, quat, vx, vy``).
        joint_qadr: qpos addresses of the 12 leg joints.
        joint_dadr: dof addresses of the 12 leg joints.
        foot_geoms: The 4 foot geom ids.
        scan: The height scan.
    """

    def __init__(
        self,
        gains: TerrainGains,
        data: mujoco.MjData,
        est,
        joint_qadr: list[int],
        joint_dadr: list[int],
        foot_geoms: list[int],
        scan: HeightScan,
    ) -> None:
        self.g, self.data, self.est, self.scan = gains, data, est, scan
        self.joint_qadr, self.joint_dadr = joint_qadr, joint_dadr
        self._foot_of = {geom: k for k, geom in enumerate(foot_geoms)}
        self.walking = False
        self.rough = self.rough_ahead = self._rough_mode = self._switching = False
        self._stopping = False
        self._to_swing: set[int] = set()
        self._cycle = 0.0
        self.stance = [True] * 4
        self.feet: list[tuple[float, float, float]] = [(0.0, 0.0, 0.0)] * 4
        self.swings: list[Swing | None] = [None] * 4
        self._swung = [-1] * 4  # the cycle of each leg's last lift-off
        self._lifted_at = [0.0] * 4  # when each leg last lifted off (s)
        self._track = Tracker(data, joint_dadr)
        self.ref = [0.0, 0.0, 0.0]  # trunk reference x, y, yaw
        self.z_ref = self.pitch_ref = 0.0
        self._iz = self._ip = self._ir = 0.0
        self._v = (0.0, 0.0)  # commanded velocity after the acceleration limit
        self._next_scan = -math.inf
        self._rough_at = (math.inf, math.inf)  # where the trunk last had rough ground near
        self._ready = False

    # ------------------------------------------------------------- rhythm

    @property
    def period(self) -> float:
        """The current cycle time (s)."""
        return self.g.rough_period if self._rough_mode else self.g.flat_period

    @property
    def duty(self) -> float:
        """The current stance fraction."""
        return self.g.rough_duty if self._rough_mode else self.g.flat_duty

    @property
    def stopping(self) -> bool:
        """Whether a stop was requested and the feet are still on their way."""
        return self._stopping

    def _leg_phase(self, leg: int) -> float:
        return (self._cycle + TROT_OFFSETS[leg]) % 1.0

    # -------------------------------------------------------------- state

    def _pose(self) -> tuple[tuple[float, float, float], tuple[float, ...]]:
        e = self.est
        roll, pitch = roll_pitch(e.quat)
        return (e.x, e.y, e.z), rotation(roll, pitch, e.yaw)

    def _foot_world(self, leg: int, pos, rot) -> tuple[float, float, float]:
        a = self.joint_qadr[3 * leg]
        q = self.data.qpos
        fx, fy, fz = to_world(rot, leg_fk(leg, q[a], q[a + 1], q[a + 2]))
        return (pos[0] + fx, pos[1] + fy, pos[2] + fz)

    def ground(self, x: float, y: float, top: float | None = None) -> float:
        """Terrain height at (x, y) near a trunk at height ``top`` (default the trunk's).

        Ground more than ``obstacle_rise`` above the line the feet stand on (where the trunk
        stands on it, extended along its pitch) is no step but an obstacle (furniture, a
        wall): ``inf``. Where the scan finds nothing, the floor under the trunk's standing
        height.
        """
        e = self.est
        if top is None and self._ready:
            top = e.z
            ahead = (x - e.x) * math.cos(e.yaw) + (y - e.y) * math.sin(e.yaw)
            level = self.z_ref - self.g.flat_height - ahead * math.tan(self.pitch_ref)
        else:
            top = e.z if top is None else top
            level = top - self.g.flat_height
        h = self.scan.height(x, y, top)
        if h > level + self.g.obstacle_rise:
            return math.inf
        return h if h > -1e3 else top - self.g.flat_height

    def reset(self) -> None:
        """Takes the feet where they stand and the reference where the trunk is."""
        pos, rot = self._pose()
        self.feet = [self._foot_world(k, pos, rot) for k in range(4)]
        self.stance = [True] * 4
        self.swings = [None] * 4
        self.walking = self._stopping = self._switching = self._ready = False
        self.ref = [self.est.x, self.est.y, self.est.yaw]
        self._iz = self._ip = self._ir = 0.0
        self._track.forget()
        self._next_scan = -math.inf
        self._rough_at = (math.inf, math.inf)
        self._look()
        self._rough_mode = self.rough

    def start(self) -> None:
        """Begins walking from the current stance."""
        self.walking, self._stopping = True, False
        self._cycle = 0.0
        self._swung = [-1] * 4
        self._v = (0.0, 0.0)
        self.ref = [self.est.x, self.est.y, self.est.yaw]

    def request_stop(self) -> None:
        """Lets every leg swing once more, then stands."""
        if self.walking and not self._stopping:
            self._stopping = True
            self._to_swing = {k for k in range(4) if self.swings[k] is None}

    # ------------------------------------------------------------ terrain

    def _look(self) -> None:
        """Scans the ground around and ahead of the trunk (every ``scan_period``)."""
        if self.data.time < self._next_scan:
            return
        self._next_scan = self.data.time + self.g.scan_period
        e = self.est
        c, s = math.cos(e.yaw), math.sin(e.yaw)
        jump = self.g.edge_jump
        if is_rough(self.ground, e.x, e.y, c, s, NEAR, jump):
            self._rough_at = (e.x, e.y)
        # Rough ground stays rough until the hind feet are past it too.
        rx, ry = self._rough_at
        self.rough = math.hypot(e.x - rx, e.y - ry) <= self.g.rough_hold
        self.rough_ahead = self.rough or is_rough(self.ground, e.x, e.y, c, s, _FAR, jump)

    def _terrain_reference(self, dt: float) -> None:
        """Trunk height and pitch: the line through the feet at the rhythm's height.

        A stance foot counts where it stands, a swing foot where it is going.
        """
        e = self.est
        c, s = math.cos(e.yaw), math.sin(e.yaw)
        along, height = [0.0, 0.0], [0.0, 0.0]
        for leg in range(4):
            sw = self.swings[leg]
            f = sw.goal if sw is not None else self.feet[leg]
            k = 0 if leg < 2 else 1
            along[k] += 0.5 * (c * (f[0] - e.x) + s * (f[1] - e.y))
            height[k] += 0.5 * f[2]
        pitch = -math.atan2(height[0] - height[1], max(along[0] - along[1], 0.2))
        mid = 0.5 * (height[0] + height[1]) - 0.5 * (along[0] + along[1]) * math.tan(-pitch)
        stand = self.g.rough_height if self._rough_mode else self.g.flat_height
        z = mid - const.FOOT_RADIUS + self.g.touchdown_depth + stand
        if not self._ready:
            self.z_ref, self.pitch_ref, self._ready = z, pitch, True
            return
        a = min(1.0, dt / self.g.terrain_filter)
        self.z_ref += a * (z - self.z_ref)
        self.pitch_ref += a * (pitch - self.pitch_ref)

    def standing_pose(
        self, x: float, y: float, yaw: float, top: float
    ) -> tuple[float, float, list[float]]:
        """:func:`~havln_mj.robot.go1.footholds.standing_pose` on this gait's ground."""
        return standing_pose(lambda px, py: self.ground(px, py, top), x, y, yaw, top, self.g)

    # --------------------------------------------------------------- step

    def step(
        self, dt: float, vx: float, vy: float, wz: float, ex: float = 0.0, ey: float = 0.0
    ) -> list[float]:
        """Advances the gait by ``dt`` and returns the 12 joint targets.

        Args:
            dt: Control period (s).
            vx: Commanded forward velocity (m/s, trunk frame).
            vy: Commanded leftward velocity (m/s).
            wz: Commanded yaw rate (rad/s, counter-clockwise).
            ex: Measured minus commanded forward velocity, for balance foot placement.
            ey: Measured minus commanded lateral velocity.
        """
        g, e = self.g, self.est
        self._look()
        self._terrain_reference(dt)
        self._choose_rhythm()
        pos, rot = self._pose()
        roll, pitch = roll_pitch(e.quat)
        self._iz = _clip(self._iz + g.ki_height * (self.z_ref - pos[2]) * dt, 0.05)
        self._ip = _clip(self._ip + g.ki_pitch * (self.pitch_ref - pitch) * dt, 0.15)
        self._ir = _clip(self._ir - g.ki_roll * roll * dt, 0.15)
        vx, vy = self._limit(dt, vx, vy)
        if self.walking:
            self._advance_reference(dt, vx, vy, wz)
            self._cycle += dt / self.period
            if self._stopping and not self._to_swing and all(self.stance):
                self.walking = self._stopping = False
        else:
            self._advance_reference(0.0, 0.0, 0.0, 0.0)
        ref_rot = rotation(self._ir, self.pitch_ref + self._ip, self.ref[2])
        ref_pos = (self.ref[0], self.ref[1], self.z_ref + self._iz)
        contacts = self._contacts()
        load = _WEIGHT / (sum(1 for sw in self.swings if sw is None) or 1)
        grf = to_body(rot, (0.0, 0.0, load))
        twist = (vx, vy, wz, ex, ey)
        follow = min(1.0, dt / g.stance_follow) if self._rough_mode and g.stance_follow else 0.0
        heading = (math.cos(e.yaw), math.sin(e.yaw)) if follow else (1.0, 0.0)
        out: list[float] = []
        for leg in range(4):
            psi = self._leg_phase(leg)
            swinging = self.walking and psi >= self.duty
            if swinging and self.swings[leg] is None and self._may_lift(leg):
                self._lift_off(leg, pos, rot)
            sw = self.swings[leg]
            if sw is not None:
                s = (psi - self.duty) / (1.0 - self.duty) if swinging else 1.0
                q = self._swing_leg(leg, sw, s, dt, twist, pos, rot, leg in contacts)
                if q is not None:
                    out.extend(q)
                    continue
            if follow:
                self._follow_foot(leg, pos, rot, follow, heading)
            out.extend(self._stance_leg(leg, ref_pos, ref_rot, grf, dt))
        return out

    def _limit(self, dt: float, vx: float, vy: float) -> tuple[float, float]:
        """The commanded velocity, capped on or before rough ground and rate limited."""
        g = self.g
        cap = g.rough_speed if self.rough_ahead or self._rough_mode else math.inf
        k = min(1.0, cap / max(1e-9, math.hypot(vx, vy)))
        a = g.accel * dt
        self._v = (
            self._v[0] + _clip(vx * k - self._v[0], a),
            self._v[1] + _clip(vy * k - self._v[1], a),
        )
        return self._v

    def _choose_rhythm(self) -> None:
        """Changes rhythm with the ground: at once when standing, else with all feet down."""
        if self.rough == self._rough_mode:
            self._switching = False
            return
        if not self.walking:
            self._rough_mode = self.rough
            return
        self._switching = True
        if all(sw is None for sw in self.swings):
            # The pair that lifted longest ago swings first in the new rhythm.
            first = min(range(4), key=lambda k: self._lifted_at[k])
            self._rough_mode, self._switching = self.rough, False
            self._cycle = (self.duty - TROT_OFFSETS[first]) % 1.0
            self._swung = [-1] * 4

    def _may_lift(self, leg: int) -> bool:
        """Whether a leg due to swing may lift now (once per cycle; not while switching)."""
        n = math.floor(self._cycle + TROT_OFFSETS[leg])
        if n == self._swung[leg] or self._switching:
            return False
        self._swung[leg] = n
        if self._stopping:
            if leg not in self._to_swing:
                return False
            self._to_swing.discard(leg)
        return True

    def _advance_reference(self, dt: float, vx: float, vy: float, wz: float) -> None:
        e, g, r = self.est, self.g, self.ref
        c, s = math.cos(r[2]), math.sin(r[2])
        r[0] += (c * vx - s * vy) * dt
        r[1] += (s * vx + c * vy) * dt
        r[2] += wz * dt
        if self.walking:
            k = min(1.0, g.ref_leak * dt)
            r[0] += k * (e.x - r[0])
            r[1] += k * (e.y - r[1])
            r[2] += k * math.remainder(e.yaw - r[2], 2 * math.pi)
        dx, dy = r[0] - e.x, r[1] - e.y
        d = math.hypot(dx, dy)
        if d > g.max_lead:
            r[0], r[1] = e.x + dx * g.max_lead / d, e.y + dy * g.max_lead / d
        dyaw = math.remainder(r[2] - e.yaw, 2 * math.pi)
        if abs(dyaw) > g.max_yaw_lead:
            r[2] = e.yaw + math.copysign(g.max_yaw_lead, dyaw)

    def _contacts(self) -> set[int]:
        d = self.data
        if not d.ncon:
            return set()
        fo = self._foot_of
        out = set()
        for g1, g2 in d.contact.geom[: d.ncon].tolist():
            if g1 in fo:
                out.add(fo[g1])
            if g2 in fo:
                out.add(fo[g2])
        return out

    # --------------------------------------------------------------- legs

    def _stance_leg(self, leg: int, ref_pos, ref_rot, grf, dt: float):
        f = self.feet[leg]
        b = to_body(ref_rot, (f[0] - ref_pos[0], f[1] - ref_pos[1], f[2] - ref_pos[2]))
        hx, hy = const.HIP_OFFSETS[leg]
        return self._track(leg, leg_ik(leg, b[0] - hx, b[1] - hy, b[2]), dt, grf)

    def _follow_foot(self, leg: int, pos, rot, a: float, heading: tuple[float, float]) -> None:
        """Moves a stance foot's reference toward the foot, along the heading and up.

        A loaded foot sinks and creeps downhill; legs held to where it landed push it along
        the ground and, on a steep slope, slip it (a 30° ramp stalled at a third of the speed).
        """
        o, f = self.feet[leg], self._foot_world(leg, pos, rot)
        c, s = heading
        along = a * (c * (f[0] - o[0]) + s * (f[1] - o[1]))
        self.feet[leg] = (o[0] + c * along, o[1] + s * along, o[2] + a * (f[2] - o[2]))

    def _lift_off(self, leg: int, pos, rot) -> None:
        self._lifted_at[leg] = self.data.time
        self.stance[leg] = False
        self.swings[leg] = Swing(self._foot_world(leg, pos, rot))
        self._track.forget(leg)

    def _land(self, leg: int, pos, rot) -> None:
        self.feet[leg] = self._foot_world(leg, pos, rot)
        self._track.forget(leg)
        self.stance[leg] = True
        self.swings[leg] = None

    def _swing_leg(self, leg, sw: Swing, s, dt, twist, pos, rot, touching: bool):
        """Joint targets of a swinging leg, or None once it has landed (it is stance then)."""
        g = self.g
        if not sw.locked:
            t_left = max(0.0, 1.0 - s) * (1.0 - self.duty) * self.period
            half = 0.5 * self.duty * self.period
            aim = raibert_point(self.est, leg, t_left, twist, self.pitch_ref, half, g)
            sw.aim_at(aim, self.ground, g)
            sw.locked = s >= g.lock_phase
        if touching and s > g.swing_end:
            foot = self._foot_world(leg, pos, rot)
            near = math.hypot(foot[0] - sw.goal[0], foot[1] - sw.goal[1]) < g.edge_margin
            if near and foot[2] < sw.goal[2] + g.land_band:
                return self._land(leg, pos, rot)
        at = sw.target(s, dt, g)
        if at is None:  # it found no ground reaching down
            return self._land(leg, pos, rot)
        b = to_body(rot, (at[0] - pos[0], at[1] - pos[1], at[2] - pos[2]))
        hx, hy = const.HIP_OFFSETS[leg]
        return self._track(leg, leg_ik(leg, b[0] - hx, b[1] - hy, b[2]), dt, None)


def _clip(v: float, limit: float) -> float:
    return -limit if v < -limit else limit if v > limit else v
