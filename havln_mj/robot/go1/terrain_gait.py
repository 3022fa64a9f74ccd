"""Terrain-aware gait: footholds on the scanned ground, swings over it, trunk following it.

Everything is planned in the world frame (the estimator's):

* **Gaits.** A trot on even ground; on rough ground (an edge or a climb in the scan ahead) a
  slower walk that swings one leg at a time and sways the trunk over the triangle of the
  other three feet. The gait changes with every foot down.
* **Trunk reference.** Position and yaw advance with the commanded twist and leak toward
  the estimate (a stiff hold at the gait's rhythm rocks the trunk); height and pitch follow
  the line through the feet (stance feet where they stand, swing feet where they go), low-pass
  filtered. Integrators on height, pitch and roll take up the sag of the position-controlled
  legs.
* **Stance feet** hold the world point where they touched down; their joint targets put the
  trunk at the reference (leg IK from the reference trunk frame), with a feed-forward that
  carries the robot's weight.
* **Swing feet** fly from lift-off to a foothold: the Raibert point of the commanded twist,
  moved along the walking direction to the nearest spot with no edge within a margin. The
  foot keeps a clearance above the ground it passes over, rising early enough to clear what
  lies ahead; it is tracked in the actual trunk frame with a feed-forward that cancels the
  joint damping, friction and gravity the position actuators would otherwise lag behind.
  A foot touching near its foothold lands there; one that finds no ground keeps reaching down.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mujoco

from havln_mj.robot.go1 import constants as const
from havln_mj.robot.go1.height_scan import HeightScan
from havln_mj.robot.go1.kinematics import leg_fk, leg_ik, leg_jacobian_t


@dataclass(frozen=True)
class GaitMode:
    """One gait's rhythm and posture.

    Attributes:
        offsets: Phase offset of each leg (FR, FL, RR, RL); a leg swings while its phase
            is past ``duty``.
        duty: Stance fraction of the cycle.
        period: Cycle time (s).
        speed: Speed cap (m/s).
        height: Trunk height above the feet's line (m).
        sway: How far the trunk moves toward the centroid of the support triangle (0: not at
            all, 1: onto it).
        leak: Rate (1/s) at which the trunk reference decays toward the estimate.
        creep: The trunk moves only while all four feet are down, between swings.
    """

    offsets: tuple[float, float, float, float]
    duty: float
    period: float
    speed: float
    height: float
    sway: float = 0.0
    leak: float = 5.0
    creep: bool = False


TROT = GaitMode((0.0, 0.5, 0.5, 0.0), 0.5, 0.4, 10.0, 0.27)
# Lateral sequence: RL, FL, RR, FR swing in turn.
WALK = GaitMode((0.0, 0.5, 0.25, 0.75), 0.8, 2.0, 0.1, 0.28, 0.8, 0.0)
# RL, FL, RR, FR swing in turn, each for 15 % of the cycle; the trunk moves in between.
CREEP = GaitMode((0.1, 0.6, 0.35, 0.85), 0.85, 2.4, 0.08, 0.28, 0.8, 0.0, True)


@dataclass
class TerrainParams:
    """Gait parameters (SI units)."""

    flat: GaitMode = TROT
    rough: GaitMode = WALK
    clearance: float = 0.06  # swing foot above the highest ground it passes over
    min_lift: float = 0.06  # swing foot above its lift-off and touch-down points
    touchdown_depth: float = 0.01
    raibert_gain: float = 0.05
    max_lead: float = 0.05  # how far the reference may run ahead of the estimate (m)
    max_yaw_lead: float = 0.1  # rad
    edge_margin: float = 0.06  # footholds keep this far from a riser (m)
    drop_margin: float = 0.1  # and this far from a drop
    edge_jump: float = 0.025  # a rise this big between 2 cm samples is an edge
    foothold_shift: float = 0.16  # farthest a foothold moves off its Raibert point
    terrain_filter: float = 0.1  # s
    ki_height: float = 2.0
    ki_pitch: float = 2.0
    ki_roll: float = 2.0
    feedforward: float = 1.0
    accel: float = 1.0  # m/s²: most the commanded speed changes
    damping: float = 0.0  # s: trunk velocity error fed back into the stance legs' reference
    weight_share: float = 1.0  # fraction of the weight the stance feed-forward carries
    touchdown_blend: float = 0.0  # s over which a new stance leg blends into the reference
    land_band: float = 0.03  # a swing foot touching lower than this above its goal has landed
    nose_clearance: float = 0.2  # front hips above the ground under the head (m)
    pitch_gain: float = 1.0  # trunk pitch as a fraction of the feet's line
    lock_phase: float = 0.3  # swing phase after which the foothold no longer moves
    swing_move: tuple[float, float] = (0.15, 0.8)  # swing phases of the horizontal motion
    swing_rate: float = 1.2  # most height a swing foot changes per unit of swing phase (m)
    extra: dict = field(default_factory=dict)


_KP = 100.0
_DAMPING = (1.0, 2.0, 2.0)  # joint damping of (abduction, thigh, knee)
_FRICTIONLOSS = 0.2
_QD_MAX = 8.0  # rad/s: faster target steps are jumps, not motion to feed forward
_AHEAD = tuple(-0.3 + 0.04 * k for k in range(24))  # where rough ground changes gait (m)
_NOSE = (0.2, 0.25, 0.3, 0.35, 0.4)  # ground the head must clear (m ahead of the trunk)
_FAR = tuple(0.5 + 0.04 * k for k in range(20))  # where it slows the robot down (m)
_N = 20  # samples of a swing's height profile
_WEIGHT = const.TOTAL_MASS * 9.81
_JOINT_LO = tuple(const.JOINT_RANGES[p][0] for p in const.LEG_PARTS)
_JOINT_HI = tuple(const.JOINT_RANGES[p][1] for p in const.LEG_PARTS)
_SWAY_FROM = 0.3  # fraction of a swing after which the sway moves on toward the next triangle


def _smooth(s: float) -> float:
    if s <= 0.0:
        return 0.0
    if s >= 1.0:
        return 1.0
    return s * s * (3.0 - 2.0 * s)


def _rot(roll: float, pitch: float, yaw: float) -> tuple[float, ...]:
    """Row-major R = Rz(yaw) Ry(pitch) Rx(roll)."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return (
        cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,
        sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,
        -sp, cp * sr, cp * cr,
    )  # fmt: skip


def _to_body(r: tuple[float, ...], v: tuple[float, float, float]) -> tuple[float, float, float]:
    """R^T v."""
    x, y, z = v
    return (
        r[0] * x + r[3] * y + r[6] * z,
        r[1] * x + r[4] * y + r[7] * z,
        r[2] * x + r[5] * y + r[8] * z,
    )


def _to_world(r: tuple[float, ...], v: tuple[float, float, float]) -> tuple[float, float, float]:
    """R v."""
    x, y, z = v
    return (
        r[0] * x + r[1] * y + r[2] * z,
        r[3] * x + r[4] * y + r[5] * z,
        r[6] * x + r[7] * y + r[8] * z,
    )


def roll_pitch(quat: tuple[float, float, float, float]) -> tuple[float, float]:
    """Roll and pitch (ZYX Euler angles) of a (w, x, y, z) quaternion."""
    w, x, y, z = quat
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x))))
    return roll, pitch


class _Swing:
    """One swing's plan: lift-off point, foothold, height profile."""

    __slots__ = ("goal", "locked", "start", "zs")

    def __init__(self, start: tuple[float, float, float]) -> None:
        self.start = start
        self.goal = start
        self.zs: list[float] | None = None
        self.locked = False


class TerrainGait:
    """Gait generator on scanned terrain: twist in, 12 joint targets out.

    Same calling pattern as :class:`~havln_mj.robot.go1.gait.TrotGait`: :meth:`start`,
    :meth:`step` every control tick, :meth:`request_stop`; :attr:`walking` turns false once
    every foot is down after a stop.
    """

    def __init__(
        self,
        params: TerrainParams,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        est,
        joint_qadr: list[int],
        joint_dadr: list[int],
        foot_geoms: list[int],
        scan: HeightScan,
    ) -> None:
        self.p = params
        self.model, self.data, self.est = model, data, est
        self.joint_qadr, self.joint_dadr = joint_qadr, joint_dadr
        self.scan = scan
        self._foot_of = {g: k for k, g in enumerate(foot_geoms)}
        self.mode = params.flat
        self._switch: GaitMode | None = None
        self.walking = False
        self._stopping = False
        self._cycle = 0.0
        self.stance = [True] * 4
        self.feet: list[tuple[float, float, float]] = [(0.0, 0.0, 0.0)] * 4
        self.swings: list[_Swing | None] = [None] * 4
        self._q_prev: list[list[float] | None] = [None] * 4
        self.ref = [0.0, 0.0, 0.0]  # x, y, yaw
        self.z_ref = 0.0
        self.pitch_ref = 0.0
        self._iz = self._ip = self._ir = 0.0
        self._terrain_ready = False
        self.rough = self.rough_ahead = False
        self._mode_since = 0.0
        self._sway_off = (0.0, 0.0)
        self._cmd_prev: tuple[float, float] | None = None
        self._v = (0.0, 0.0)  # commanded velocity after the acceleration limit
        self._to_swing: set[int] = set()
        self._swung = [-1] * 4  # the leg cycle of each leg's last lift-off
        self._lifted_at = [0.0] * 4  # when each leg last lifted off (s)
        self._blend: list = [None] * 4  # (touch-down time, body-frame offset) of new stance legs

    # ----------------------------------------------------------------- state

    def _pose(self) -> tuple[tuple[float, float, float], tuple[float, ...]]:
        e = self.est
        roll, pitch = roll_pitch(e.quat)
        return (e.x, e.y, e.z), _rot(roll, pitch, e.yaw)

    def _foot_world(self, leg: int, pos, rot) -> tuple[float, float, float]:
        a = self.joint_qadr[3 * leg]
        q = self.data.qpos
        fx, fy, fz = leg_fk(leg, q[a], q[a + 1], q[a + 2])
        wx, wy, wz = _to_world(rot, (fx, fy, fz))
        return (pos[0] + wx, pos[1] + wy, pos[2] + wz)

    def reset(self) -> None:
        """Takes the feet where they stand and the reference where the trunk is."""
        pos, rot = self._pose()
        self.feet = [self._foot_world(k, pos, rot) for k in range(4)]
        self.stance = [True] * 4
        self.swings = [None] * 4
        self.walking = False
        self._stopping = False
        self._switch = None
        self.ref = [self.est.x, self.est.y, self.est.yaw]
        self._terrain_ready = False
        self._iz = self._ip = self._ir = 0.0
        self._q_prev = [None] * 4
        _, _, self.rough = self._terrain_target(self.est.x, self.est.y, self.est.yaw, pos[2])
        self.mode = self.p.rough if self.rough else self.p.flat

    def start(self) -> None:
        """Begins walking from the current stance."""
        self._mode_since = self.data.time
        self._v = (0.0, 0.0)
        self.walking = True
        self._stopping = False
        self._cycle = 0.0
        self._swung = [-1] * 4
        self.ref = [self.est.x, self.est.y, self.est.yaw]

    def request_stop(self) -> None:
        """Lets every leg swing once more, then stands."""
        if self.walking and not self._stopping:
            self._stopping = True
            self._to_swing = {k for k in range(4) if self.swings[k] is None}

    @property
    def stopping(self) -> bool:
        """Whether a stop was requested and the feet are still on their way."""
        return self._stopping

    def _leg_phase(self, leg: int) -> float:
        return (self._cycle + self.mode.offsets[leg]) % 1.0

    # -------------------------------------------------------------- terrain

    def _ground(self, x: float, y: float, top: float | None = None) -> float:
        top = self.est.z if top is None else top
        h = self.scan.height(x, y, top)
        return h if h > -1e3 else top - self.p.flat.height

    def _terrain_target(self, x: float, y: float, yaw: float, top: float):
        """Trunk height and pitch the ground under the hips asks for; whether it is rough.

        The ground under each hip pair is the mid-range of the ground within 15 cm of it
        along the trunk (on a stair, halfway between a tread and the next). Ground is rough
        where the scan along the trunk, 0.3 m behind to 0.6 m ahead, has an edge or climbs
        more than 0.1 m.
        """
        c, s = math.cos(yaw), math.sin(yaw)
        hips = []
        for hx in (const.HIP_X, -const.HIP_X):
            hs = [self._ground(x + c * (hx + d), y + s * (hx + d), top) for d in _WINDOW]
            hips.append(0.5 * (min(hs) + max(hs)))
        rough = self._rough(x, y, c, s, top, _AHEAD)
        mode = self.p.rough if rough else self.p.flat
        z = 0.5 * (hips[0] + hips[1]) + mode.height
        pitch = -self.p.pitch_gain * math.atan2(hips[0] - hips[1], 2.0 * const.HIP_X)
        return z, pitch, rough

    def _rough(self, x: float, y: float, c: float, s: float, top: float, ahead) -> bool:
        """Whether the scan along (c, s) at distances ``ahead`` has an edge or climbs 0.1 m."""
        hs = [self._ground(x + c * d, y + s * d, top) for d in ahead]
        if any(abs(b - a) > self.p.edge_jump for a, b in zip(hs, hs[1:], strict=False)):
            return True
        return max(hs) - min(hs) > 0.1

    def _terrain_reference(self, dt: float) -> None:
        """Filtered trunk height and pitch: the line through the feet, at the mode's height.

        A stance foot counts where it stands, a swing foot where it is going.
        """
        e = self.est
        _, ground_pitch, self.rough = self._terrain_target(e.x, e.y, e.yaw, e.z)
        c, s = math.cos(e.yaw), math.sin(e.yaw)
        self.rough_ahead = self.rough or self._rough(e.x, e.y, c, s, e.z, _FAR)
        along, height = [0.0, 0.0], [0.0, 0.0]
        for leg in range(4):
            sw = self.swings[leg]
            f = sw.goal if sw is not None else self.feet[leg]
            k = 0 if leg < 2 else 1
            along[k] += 0.5 * (c * (f[0] - e.x) + s * (f[1] - e.y))
            height[k] += 0.5 * f[2]
        run = max(along[0] - along[1], 0.2)
        pitch = -self.p.pitch_gain * math.atan2(height[0] - height[1], run)
        if self.p.extra.get("scan_pitch", False):
            pitch = ground_pitch
        mid = 0.5 * (height[0] + height[1]) - 0.5 * (along[0] + along[1]) * math.tan(-pitch)
        z = mid - const.FOOT_RADIUS + self.p.touchdown_depth + self.mode.height
        # The head must clear the ground ahead of it: pitch up about the rear hips if not.
        ahead = max(self._ground(e.x + c * d, e.y + s * d) for d in _NOSE)
        rear_z = z + const.HIP_X * math.sin(pitch)
        need = ahead + self.p.nose_clearance - rear_z
        span = 2.0 * const.HIP_X
        if need > -span * math.sin(pitch):
            pitch = -math.asin(min(0.9, need / span))
            z = rear_z - const.HIP_X * math.sin(pitch)
        if not self._terrain_ready:
            self.z_ref, self.pitch_ref = z, pitch
            self._terrain_ready = True
            return
        a = min(1.0, dt / self.p.terrain_filter)
        self.z_ref += a * (z - self.z_ref)
        self.pitch_ref += a * (pitch - self.pitch_ref)

    def standing_pose(
        self, x: float, y: float, yaw: float, top: float
    ) -> tuple[float, float, list[float]]:
        """Trunk height, pitch and 12 joint angles standing at (x, y) with feet on the ground.

        Each foot stands on safe ground under its hip (the trunk at the terrain's height and
        pitch), so the robot can be placed on a stair or a ramp.
        """
        z, pitch, _ = self._terrain_target(x, y, yaw, top)
        rot = _rot(0.0, pitch, yaw)
        q: list[float] = []
        for leg in range(4):
            hx, hy = const.HIP_OFFSETS[leg]
            ry = hy + const.LEG_SIDE[leg] * const.ABDUCTION
            hip = _to_world(rot, (hx, ry, 0.0))
            fx, fy = self._safe(x + hip[0], y + hip[1], math.cos(yaw), math.sin(yaw), top)
            fz = self._ground(fx, fy, top) + const.FOOT_RADIUS - self.p.touchdown_depth
            b = _to_body(rot, (fx - x, fy - y, fz - z))
            q.extend(_clip_joints(leg_ik(leg, b[0] - hx, b[1] - hy, b[2])))
        return z, pitch, q

    # ------------------------------------------------------------------ step

    def step(
        self, dt: float, vx: float, vy: float, wz: float, ex: float = 0.0, ey: float = 0.0
    ) -> list[float]:
        """Advances the gait by ``dt`` and returns the 12 joint targets."""
        p, e = self.p, self.est
        self._terrain_reference(dt)
        self._choose_mode()
        pos, rot = self._pose()
        roll, pitch = roll_pitch(e.quat)
        self._iz = _clip(self._iz + p.ki_height * (self.z_ref - pos[2]) * dt, 0.05)
        self._ip = _clip(self._ip + p.ki_pitch * (self.pitch_ref - pitch) * dt, 0.15)
        self._ir = _clip(self._ir - p.ki_roll * roll * dt, 0.15)
        cap = min(self.mode.speed, p.rough.speed if self.rough_ahead else math.inf)
        k = min(1.0, cap / max(1e-9, math.hypot(vx, vy)))
        # Speed changes at most ``accel`` (a cap that drops would stop the trunk short).
        a = p.accel * dt
        self._v = (
            self._v[0] + _clip(vx * k - self._v[0], a),
            self._v[1] + _clip(vy * k - self._v[1], a),
        )
        vx, vy = self._v
        sx, sy = self._sway() if self.mode.sway > 0.0 and self.walking else (0.0, 0.0)
        ramp = _smooth((self.data.time - self._mode_since) / 0.3)  # into the sway gently
        self._sway_off = (sx * ramp, sy * ramp)
        if self.walking:
            if self.mode.creep:  # all the motion between swings
                k = 0.0 if self._swing_phase() else 1.0 / (1.0 - 4.0 * (1.0 - self.mode.duty))
                vx, vy, wz = vx * k, vy * k, wz * k
            self._advance_reference(dt, vx, vy, wz)
            self._cycle += dt / self.mode.period
            if self._stopping and not self._to_swing and all(self.stance):
                self.walking = self._stopping = False
        else:
            self._advance_reference(0.0, 0.0, 0.0, 0.0)
        sx, sy = self._sway_off
        cx, cy = self.ref[0] + sx, self.ref[1] + sy
        # Damping: lead the legs against the trunk's velocity error (its springs ring else).
        if self._cmd_prev is not None and p.damping > 0.0:
            c, s = math.cos(e.yaw), math.sin(e.yaw)
            vwx, vwy = c * e.vx - s * e.vy, s * e.vx + c * e.vy
            ux, uy = (cx - self._cmd_prev[0]) / dt, (cy - self._cmd_prev[1]) / dt
            self._cmd_prev = (cx, cy)
            cx -= p.damping * (vwx - ux)
            cy -= p.damping * (vwy - uy)
        else:
            self._cmd_prev = (cx, cy)
        ref_rot = _rot(self._ir, self.pitch_ref + self._ip, self.ref[2])
        ref_pos = (cx, cy, self.z_ref + self._iz)
        contacts = self._contacts()
        n_stance = sum(1 for k in range(4) if self.swings[k] is None) or 1
        load = p.weight_share * _WEIGHT / n_stance
        twist = (vx, vy, wz, ex, ey)
        out: list[float] = []
        for leg in range(4):
            psi = self._leg_phase(leg)
            swinging = self.walking and psi >= self.mode.duty
            if swinging and self.swings[leg] is None and self._may_lift(leg):
                self._lift_off(leg, pos, rot)
            sw = self.swings[leg]
            if sw is not None:
                s = (psi - self.mode.duty) / (1.0 - self.mode.duty) if swinging else 1.0
                q = self._swing_leg(leg, sw, s, dt, twist, pos, rot, leg in contacts)
                if q is not None:
                    out.extend(q)
                    continue
            out.extend(self._stance_leg(leg, ref_pos, ref_rot, rot, load, dt))
        return out

    def _choose_mode(self) -> None:
        """Switches gait when the ground changes: at once when standing, else feet down."""
        want = self.p.rough if self.rough else self.p.flat
        if want is self.mode:
            self._switch = None
            return
        if not self.walking:
            self.mode = want
            return
        self._switch = want
        if all(s is None for s in self.swings):
            # The leg that lifted longest ago swings first in the new gait.
            first = min(range(4), key=lambda k: self._lifted_at[k])
            self.mode, self._switch = want, None
            self._mode_since = self.data.time
            self._cycle = (want.duty - want.offsets[first]) % 1.0
            self._swung = [-1] * 4

    def _may_lift(self, leg: int) -> bool:
        """Whether a leg due to swing may lift now (once per cycle; not while changing gait)."""
        n = math.floor(self._cycle + self.mode.offsets[leg])
        if n == self._swung[leg] or self._switch is not None:
            return False
        self._swung[leg] = n
        if self._stopping:
            if leg not in self._to_swing:
                return False
            self._to_swing.discard(leg)
        return True

    def _swing_phase(self) -> bool:
        """Whether some leg's swing window holds the current phase."""
        return any(self._leg_phase(leg) >= self.mode.duty for leg in range(4))

    def _sway(self) -> tuple[float, float]:
        """Trunk offset toward the support triangle of the leg swinging now or next."""
        m = self.mode
        phase = self._cycle % 1.0
        swing = 1.0 - m.duty
        starts = sorted(((m.duty - o) % 1.0, leg) for leg, o in enumerate(m.offsets))
        # The leg whose swing (widened by the blend) holds the phase, blending into the next.
        for k, (s0, leg) in enumerate(starts):
            s1, nxt = starts[(k + 1) % 4]
            gap_end = s1 if s1 > s0 else s1 + 1.0
            ph = phase if phase >= s0 else phase + 1.0
            if ph < gap_end:
                a = self._sway_of(leg)
                lo = s0 + (1.0 if m.creep else _SWAY_FROM) * swing
                hi = gap_end - 0.01
                if ph <= lo or hi <= lo:
                    return a
                b = self._sway_of(nxt)
                w = _smooth((ph - lo) / (hi - lo))
                return a[0] + (b[0] - a[0]) * w, a[1] + (b[1] - a[1]) * w
        return 0.0, 0.0

    def _sway_of(self, leg: int) -> tuple[float, float]:
        """Offset from the four feet's centroid to the other three's (scaled by ``sway``)."""
        f = [self.swings[k].start if self.swings[k] is not None else self.feet[k] for k in range(4)]
        cx = sum(p[0] for p in f) / 4.0
        cy = sum(p[1] for p in f) / 4.0
        k = self.mode.sway / 3.0
        return k * (cx - f[leg][0]), k * (cy - f[leg][1])

    def _advance_reference(self, dt: float, vx: float, vy: float, wz: float) -> None:
        e, p, r = self.est, self.p, self.ref
        c, s = math.cos(r[2]), math.sin(r[2])
        r[0] += (c * vx - s * vy) * dt
        r[1] += (s * vx + c * vy) * dt
        r[2] += wz * dt
        # The estimate stands where the reference plus the sway puts it.
        ex, ey = e.x - self._sway_off[0], e.y - self._sway_off[1]
        k = min(1.0, self.mode.leak * dt) if self.walking else 0.0
        r[0] += k * (ex - r[0])
        r[1] += k * (ey - r[1])
        r[2] += k * math.remainder(e.yaw - r[2], 2 * math.pi)
        dx, dy = r[0] - ex, r[1] - ey
        d = math.hypot(dx, dy)
        if d > p.max_lead:
            r[0], r[1] = ex + dx * p.max_lead / d, ey + dy * p.max_lead / d
        dyaw = math.remainder(r[2] - e.yaw, 2 * math.pi)
        if abs(dyaw) > p.max_yaw_lead:
            r[2] = e.yaw + math.copysign(p.max_yaw_lead, dyaw)

    def _contacts(self) -> set[int]:
        d = self.data
        n = d.ncon
        if not n:
            return set()
        out = set()
        fo = self._foot_of
        for g1, g2 in d.contact.geom[:n].tolist():
            if g1 in fo:
                out.add(fo[g1])
            if g2 in fo:
                out.add(fo[g2])
        return out

    # ------------------------------------------------------------------ legs

    def _stance_leg(self, leg: int, ref_pos, ref_rot, rot, load: float, dt: float):
        f = self.feet[leg]
        b = _to_body(ref_rot, (f[0] - ref_pos[0], f[1] - ref_pos[1], f[2] - ref_pos[2]))
        hx, hy = const.HIP_OFFSETS[leg]
        blend = self._blend[leg]
        if blend is not None:  # a foot just down: from where it stands to the reference
            w = min(1.0, (self.data.time - blend[0]) / self.p.touchdown_blend)
            if blend[1] is None:
                a = self.joint_qadr[3 * leg]
                qp = self.data.qpos
                now = leg_fk(leg, qp[a], qp[a + 1], qp[a + 2])
                blend = self._blend[leg] = (blend[0], tuple(n - v for n, v in zip(now, b)))
            off = blend[1]
            b = (b[0] + (1 - w) * off[0], b[1] + (1 - w) * off[1], b[2] + (1 - w) * off[2])
            if w >= 1.0:
                self._blend[leg] = None
        q = leg_ik(leg, b[0] - hx, b[1] - hy, b[2])
        return self._feedforward(leg, q, dt, _to_body(rot, (0.0, 0.0, load)))

    def _lift_off(self, leg: int, pos, rot) -> None:
        self._lifted_at[leg] = self.data.time
        self.stance[leg] = False
        self.swings[leg] = _Swing(self._foot_world(leg, pos, rot))
        self._q_prev[leg] = None

    def _land(self, leg: int, pos, rot) -> None:
        self.feet[leg] = self._foot_world(leg, pos, rot)
        self._blend[leg] = (self.data.time, None) if self.p.touchdown_blend > 0 else None
        self._q_prev[leg] = None
        self.stance[leg] = True
        self.swings[leg] = None

    def _foothold(self, leg: int, t_left: float, twist) -> tuple[float, float]:
        """The Raibert foothold (world xy) of a swing ending in ``t_left`` seconds.

        The hip where the reference will be at touch-down, then half a stance of the ground's
        motion ahead, plus a balance term on the velocity error.
        """
        vx, vy, wz, ex, ey = twist
        p, e = self.p, self.est
        r = self.ref if self.mode.sway > 0.0 else (e.x, e.y, e.yaw)
        t_stance = self.mode.duty * self.mode.period
        c, s = math.cos(r[2]), math.sin(r[2])
        tx = r[0] + (c * vx - s * vy) * t_left
        ty = r[1] + (s * vx + c * vy) * t_left
        yaw_td = r[2] + wz * t_left
        hx, hy = const.HIP_OFFSETS[leg]
        ry = hy + const.LEG_SIDE[leg] * const.ABDUCTION
        rx = hx * math.cos(self.pitch_ref)
        ct, st = math.cos(yaw_td), math.sin(yaw_td)
        fx = vx - wz * ry
        fy = vy + wz * rx
        ox = 0.5 * fx * t_stance + p.raibert_gain * ex
        oy = 0.5 * fy * t_stance + p.raibert_gain * ey
        return (tx + ct * (rx + ox) - st * (ry + oy), ty + st * (rx + ox) + ct * (ry + oy))

    def _safe(
        self, x: float, y: float, ux: float, uy: float, top: float | None = None
    ) -> tuple[float, float]:
        """The point nearest (x, y) along direction (ux, uy) clear of edges.

        A foothold keeps ``edge_margin`` from a riser rising beside it (the toe clears it) and
        ``drop_margin`` from a drop (the foot stays on its tread, the shin above the nosing).
        """
        p = self.p
        step = 0.02
        n = int(round(p.foothold_shift / step))
        m = int(round(max(p.edge_margin, p.drop_margin) / step))
        hs = [
            self._ground(x + ux * k * step, y + uy * k * step, top)
            for k in range(-n - m, n + m + 1)
        ]
        if max(hs) - min(hs) <= p.edge_jump:
            return x, y
        rise, drop = p.edge_margin / step - 1e-9, p.drop_margin / step - 1e-9
        for k in sorted(range(-n, n + 1), key=abs):
            i = k + n + m
            ok = True
            for j in range(i - m, i + m):  # the jump between samples j and j + 1
                dh = hs[j + 1] - hs[j]
                if abs(dh) <= p.edge_jump:
                    continue
                outward = dh if j >= i else -dh  # going away from the foothold
                gap = (j - i + 0.5) if j >= i else (i - j - 0.5)
                if gap < (drop if outward < 0 else rise):
                    ok = False
                    break
            if ok:
                return x + ux * k * step, y + uy * k * step
        return x, y

    def _plan_heights(self, sw: _Swing) -> None:
        """The swing's heights at ``_N + 1`` even phases: over the ground, then down.

        Between lift-off and touch-down the foot keeps ``clearance`` above the highest ground
        within ``edge_margin`` of where it is; it climbs or drops no faster than
        ``swing_rate`` per unit of phase, rising early enough to clear what lies ahead.
        """
        p = self.p
        (x0, y0, z0), (gx, gy, gz) = sw.start, sw.goal
        dx, dy = gx - x0, gy - y0
        length = math.hypot(dx, dy)
        ux, uy = (dx / length, dy / length) if length > 1e-6 else (0.0, 0.0)
        step = 0.01
        a = int(round(p.edge_margin / step))
        n = int(length / step) + 1
        ground = [
            self._ground(x0 + ux * k * step, y0 + uy * k * step) + const.FOOT_RADIUS
            for k in range(-a, n + a + 1)
        ]
        m0, m1 = p.swing_move
        zs = []
        for i in range(_N + 1):
            si = i / _N
            if si <= m0:
                zs.append(z0 + p.min_lift * _smooth(si / m0) if m0 > 0 else z0)
            elif si >= m1:
                zs.append(gz + p.min_lift * (1.0 - _smooth((si - m1) / (1.0 - m1))))
            else:
                k = int(round(length * _smooth((si - m0) / (m1 - m0)) / step)) + a
                zs.append(max(ground[max(0, k - a) : k + a + 1]) + p.clearance)
        rate = p.swing_rate / _N
        for i in range(_N - 1, 0, -1):  # rise early enough
            zs[i] = max(zs[i], zs[i + 1] - rate)
        for i in range(1, _N):  # drop no faster
            zs[i] = max(zs[i], zs[i - 1] - rate)
        zs[0], zs[_N] = z0, gz
        sw.zs = zs

    def _swing_z(self, sw: _Swing, s: float) -> float:
        f = min(max(s, 0.0), 1.0) * _N
        i = min(int(f), _N - 1)
        return sw.zs[i] + (sw.zs[i + 1] - sw.zs[i]) * (f - i)

    def _swing_leg(
        self, leg, sw: _Swing, s, dt, twist, pos, rot, touching: bool
    ) -> tuple[float, float, float] | None:
        """Joint targets of a swinging leg, or None once it has landed (it is stance then)."""
        p = self.p
        m0, m1 = p.swing_move
        if not sw.locked:
            t_left = max(0.0, (1.0 - s)) * (1.0 - self.mode.duty) * self.mode.period
            gx, gy = self._foothold(leg, t_left, twist)
            dx, dy = gx - sw.start[0], gy - sw.start[1]
            d = math.hypot(dx, dy)
            if d > 0.02:
                gx, gy = self._safe(gx, gy, dx / d, dy / d)
            if sw.zs is None or math.hypot(gx - sw.goal[0], gy - sw.goal[1]) > 0.01:
                gz = self._ground(gx, gy) + const.FOOT_RADIUS - p.touchdown_depth
                sw.goal = (gx, gy, gz)
                self._plan_heights(sw)
            if s >= p.lock_phase:
                sw.locked = True
        if touching and s > m1:
            foot = self._foot_world(leg, pos, rot)
            near = math.hypot(foot[0] - sw.goal[0], foot[1] - sw.goal[1]) < p.edge_margin
            if near and foot[2] < sw.goal[2] + p.land_band:
                return self._land(leg, pos, rot)
        x0, y0, _ = sw.start
        gx, gy, gz = sw.goal
        h = _smooth((s - m0) / (m1 - m0))
        z = self._swing_z(sw, s)
        if s >= 1.0:  # no ground yet: keep reaching down
            sw.goal = (gx, gy, gz - 0.3 * dt)
            z = sw.goal[2]
            if gz < sw.start[2] - 0.35:
                return self._land(leg, pos, rot)
        target = (x0 + (gx - x0) * h, y0 + (gy - y0) * h, z)
        b = _to_body(rot, (target[0] - pos[0], target[1] - pos[1], target[2] - pos[2]))
        hx, hy = const.HIP_OFFSETS[leg]
        q = leg_ik(leg, b[0] - hx, b[1] - hy, b[2])
        return self._feedforward(leg, q, dt, None)

    def _feedforward(self, leg: int, q, dt: float, grf) -> tuple[float, float, float]:
        """Joint targets that make the actuators track ``q`` despite damping and gravity.

        ``grf`` is the ground's force on a stance foot (trunk frame) the leg must bear.
        """
        prev = self._q_prev[leg]
        self._q_prev[leg] = list(q)
        k = self.p.feedforward
        if k <= 0.0:
            return _clip_joints(q)
        bias = self.data.qfrc_bias
        load = leg_jacobian_t(leg, q[0], q[1], q[2], grf) if grf is not None else (0.0,) * 3
        out = []
        for j in range(3):
            qd = (q[j] - prev[j]) / dt if prev is not None else 0.0
            qd = max(-_QD_MAX, min(_QD_MAX, qd))
            tau = _DAMPING[j] * qd + _FRICTIONLOSS * math.tanh(qd / 0.2) - load[j]
            tau += bias[self.joint_dadr[3 * leg + j]]
            out.append(q[j] + k * tau / _KP)
        return _clip_joints(out)


_WINDOW = (-0.15, -0.1, -0.05, 0.0, 0.05, 0.1, 0.15)  # ground sampled around a hip (m)


def _clip(v: float, limit: float) -> float:
    return -limit if v < -limit else limit if v > limit else v


def _clip_joints(q) -> tuple[float, float, float]:
    return tuple(
        lo if v < lo else hi if v > hi else v
        for v, lo, hi in zip(q, _JOINT_LO, _JOINT_HI, strict=True)
    )
