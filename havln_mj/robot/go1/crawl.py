"""Statically stable crawl for stairs: one leg at a time, the trunk over the other three.

* **Sequence.** The legs step in pairs of one side, the trailing leg first (walking forwards:
  left hind, left front, right hind, right front). Before a foot lifts, the centre of mass
  moves into the triangle of the other three feet
  (:func:`~havln_mj.robot.go1.stance_forces.support_target`); the foot lifts only once it is
  ``lift_margin`` inside.
* **Stance.** The stance legs are torque-controlled through the position actuators (a target
  of ``q + τ / kp``): a PD on the centre of mass and the trunk attitude asks for a force and a
  moment, shared among the stance feet within their friction cones
  (:func:`~havln_mj.robot.go1.stance_forces.distribute`); each leg gives its share as
  ``−Jᵀf``. Legs that hold joint angles fight each other once their feet stand at different
  heights; legs that push with a force do not.
* **Trunk pose.** The hips ride ``height`` above the ground under them (the height scan
  averaged over ``±ground_window`` along the heading), the trunk pitched with it, each hip
  kept within reach of its stance foot's ground and the next swing leg's hip of its foothold;
  rate limited.
* **Footholds.** ``stride`` on from the foot's last one, within reach of its hip, then moved
  to the nearest safe spot of the flat piece of ground it falls on: ``drop_gap`` from the edge
  of a drop, ``face_gap`` from the foot of a riser (edges found in the height scan along the
  walking direction).
* **Swing.** Up to ``clearance`` above the higher of lift-off and foothold, across, down; a
  contact force over ``touch_force`` lands it; a foot that finds no ground reaches on down.

The GO1's knees point backwards: facing down a stair, a front knee strikes the nose of the
step the foot leaves. The crawl descends stairs backwards (facing up them, ``vx < 0``), which
mirrors a climb.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from havln_mj.robot.go1 import constants as const
from havln_mj.robot.go1.actuation import KP, clip_joints
from havln_mj.robot.go1.estimator import quat_yaw
from havln_mj.robot.go1.frames import rotation
from havln_mj.robot.go1.gains import CrawlGains
from havln_mj.robot.go1.height_scan import HeightScan
from havln_mj.robot.go1.kinematics import leg_ik, leg_jacobian_t
from havln_mj.robot.go1.stance_forces import distribute, support_margin, support_target

_FORWARD_PAIRS = ((3, 1), (2, 0))  # (RL, FL), (RR, FR): trailing leg of a side first
_BACKWARD_PAIRS = ((1, 3), (0, 2))
_HIPS = tuple(np.array([hx, hy, 0.0]) for hx, hy in const.HIP_OFFSETS)
_FOOT_LATERAL = const.HIP_Y + const.ABDUCTION  # a foot's nominal offset from the centre line
# Each foot's place under its hip (trunk frame, x and y).
_PLACES = np.array(const.HIP_OFFSETS) + np.outer(const.LEG_SIDE, (0.0, const.ABDUCTION))
_WEIGHT = np.array([0.0, 0.0, const.TOTAL_MASS * 9.81])
_SCAN_REACH = 0.3  # m each way along the walking direction searched for a safe foothold
_SHIFT_GIVE_UP = 2.5  # s: a foot lifts after this long even if the shift fell short
_LAND_FROM = 0.6  # share of the swing time after which a touch lands the foot
_REACH_ON = 2.0  # swing times after which a foot that found no ground stands anyway
_SQUARE_OFF = 0.02  # m: a foot this far from its place under the hip is stepped there first


class CrawlGait:
    """Stair crawl: twist in, 12 joint targets out, on the calling pattern of the other gaits.

    :meth:`start`, :meth:`step` every control tick, :meth:`request_stop`; ``walking`` turns
    false once all four feet are down after a stop. The sign of ``vx`` chooses the walking
    direction along the heading (its size is the crawl's own), ``wz`` turns the heading.

    Args:
        gains: The crawl's gains.
        model: The compiled world.
        data: The robot's data (trunk state, joint angles and contacts are read from it).
        trunk_id: Body id of the trunk.
        joint_qadr: qpos addresses of the 12 leg joints.
        joint_dadr: dof addresses of the 12 leg joints.
        foot_geoms: The 4 foot geom ids.
        scan: The height scan of the terrain.
    """

    def __init__(
        self,
        gains: CrawlGains,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        trunk_id: int,
        joint_qadr: list[int],
        joint_dadr: list[int],
        foot_geoms: list[int],
        scan: HeightScan,
    ) -> None:
        self.g, self.model, self.data, self.scan = gains, model, data, scan
        self._window = np.linspace(-gains.ground_window, gains.ground_window, 7).tolist()
        self.trunk_id = trunk_id
        self._dof = int(model.jnt_dofadr[model.body_jntadr[trunk_id]])  # the free joint's
        self.joint_qadr, self.joint_dadr, self.foot_geoms = joint_qadr, joint_dadr, foot_geoms
        self.walking = False
        self.stance = [True] * 4
        self._f6 = np.zeros(6)
        self.reset()

    def reset(self) -> None:
        """Forgets the walk (after a teleport): all feet down, references from the trunk."""
        self.walking, self._stop = False, False
        self.stance = [True] * 4
        self._swing: tuple | None = None  # (leg, start time, lift-off point, foothold)
        self._phase, self._pair, self._idx, self._since = "shift", 0, 0, 0.0
        self._goal: np.ndarray | None = None  # centre-of-mass goal (world)
        self._next: np.ndarray | None = None  # foothold of the leg that swings next
        self._z = self._pitch = None
        self._direction = 0  # set by the first twist: +1 forwards, -1 backwards
        self._squaring = 0  # swings left that step feet back under their hips
        self._time = 0.0
        self._yaw = quat_yaw(*self.data.xquat[self.trunk_id])
        self._origin = self.data.xpos[self.trunk_id][:2].copy()
        self._line_yaw = self._yaw

    def start(self) -> None:
        """Starts walking along the trunk's current heading.

        Feet that stand off their places under the hips (after a turn, or another gait's
        walk) are first stepped there, one at a time: the walk then starts from the same
        stance whatever came before it.
        """
        if not self.walking:
            self.reset()
            self.walking = True
            d = self.data
            rot = d.xmat[self.trunk_id].reshape(3, 3)
            feet = np.array([d.geom_xpos[g] for g in self.foot_geoms])
            local = (feet - d.xpos[self.trunk_id]) @ rot
            if np.hypot(*(local[:, :2] - _PLACES).T).max() > _SQUARE_OFF:
                self._squaring = 4

    def request_stop(self) -> None:
        """Ends the walk once the foot in the air is down."""
        self._stop = True

    # ------------------------------------------------------------------ the tick

    def step(self, dt: float, vx: float, vy: float, wz: float, *_) -> list[float]:
        """Joint targets for this tick, following the twist's direction and turn."""
        self._time += dt
        d = self.data
        rot = d.xmat[self.trunk_id].reshape(3, 3)
        pos = d.xpos[self.trunk_id]
        feet = np.array([d.geom_xpos[g] for g in self.foot_geoms])
        if self.walking:
            # The walk keeps the direction it started in: a sign change of vx (an overshoot
            # near the target) holds it, as the leg sequence must not reverse mid-cycle.
            if self._direction == 0 and abs(vx) > 1e-3:
                self._direction = 1 if vx > 0 else -1
            along = vx * self._direction > 1e-3
            # The heading leads the trunk's by the asked turn (no integrator to wind up).
            turn = max(-self.g.yaw_rate, min(self.g.yaw_rate, wz))
            self._yaw = math.atan2(rot[1, 0], rot[0, 0]) + turn * self.g.yaw_lead
            self._sequence(pos, rot, feet, moving=along or abs(wz) > 1e-3)
        targets = self._stance_targets(dt, pos, rot, feet)
        if self._swing is not None:
            self._swing_targets(pos, rot, targets)
        return [v for leg in range(4) for v in clip_joints(targets[3 * leg : 3 * leg + 3])]

    def _sequence(self, pos, rot, feet: np.ndarray, moving: bool) -> None:
        """Moves the walk on: a shift ends in a lift-off, a swing in a touch-down."""
        leg = self._pairs()[self._pair][self._idx]
        if self._phase == "shift":
            if self._goal is None:
                self._plan(leg, pos, rot, feet)
            else:  # the foothold follows the trunk as it shifts: where the hip is at lift-off
                self._next = self._foothold(leg, pos, rot, feet[leg])
            if self._stop or not moving:
                if self._stop:
                    self.walking = False
                return
            triangle = feet[[i for i in range(4) if i != leg]]
            com = self.data.subtree_com[self.trunk_id]
            ready = support_margin(com, triangle) > self.g.lift_margin
            waited = self._time - self._since
            if (waited >= self.g.shift_time and ready) or waited > _SHIFT_GIVE_UP:
                self._swing = (leg, self._time, feet[leg].copy(), self._next.copy())
                self.stance[leg] = False
                self._phase, self._since = "swing", self._time
            return
        s = (self._time - self._since) / self.g.swing_time
        landed = s > _LAND_FROM and self._foot_force(leg) > self.g.touch_force
        if landed or s > _REACH_ON:
            self.stance[leg] = True
            self._swing = None
            self._phase, self._since = "shift", self._time
            if self._idx == 0:
                self._idx = 1
            else:
                self._idx, self._pair = 0, 1 - self._pair
            feet[leg] = self.data.geom_xpos[self.foot_geoms[leg]]
            self._squaring = max(0, self._squaring - 1)
            self._plan(self._pairs()[self._pair][self._idx], pos, rot, feet)

    def _pairs(self) -> tuple:
        return _BACKWARD_PAIRS if self._direction < 0 else _FORWARD_PAIRS

    def _plan(self, leg: int, pos, rot, feet: np.ndarray) -> None:
        """The next swing leg's foothold and the centre-of-mass goal before it lifts."""
        self._next = self._foothold(leg, pos, rot, feet[leg])
        triangle = feet[[i for i in range(4) if i != leg]]
        ahead = self._direction * self.g.lead * self._heading()
        self._goal = support_target(triangle, ahead, self.g.target_margin)

    def _heading(self) -> np.ndarray:
        return np.array([math.cos(self._yaw), math.sin(self._yaw), 0.0])

    # ------------------------------------------------------------ footholds

    def _foothold(self, leg: int, pos, rot, foot: np.ndarray) -> np.ndarray:
        """Where leg ``leg`` steps next: on along the walk, in reach, off edges."""
        g = self.g
        heading = self._heading()
        left = np.array([-heading[1], heading[0], 0.0])
        walk = self._direction * heading
        hip = pos + rot @ _HIPS[leg]
        leading = (leg < 2) == (self._direction > 0)
        reach = g.lead_reach if leading else g.trail_reach
        along = float((foot + g.stride * walk - hip) @ walk) if not self._squaring else 0.0
        target = hip + walk * max(-0.05, min(reach, along))
        # Laterally on the walk's line: the line through the start along the heading.
        line_left = np.array([-math.sin(self._line_yaw), math.cos(self._line_yaw), 0.0])
        origin = np.array([*self._origin, 0.0])
        if abs(math.remainder(self._yaw - self._line_yaw, math.tau)) > 0.05:
            line_left, origin = left, np.array([pos[0], pos[1], 0.0])  # turning: about the trunk
        side = const.LEG_SIDE[leg] * _FOOT_LATERAL
        target = target + line_left * (float((origin - target) @ line_left) + side)
        s, ground = self.safe_spot(target, walk, pos[2])
        out = target + walk * s
        out[2] = ground + const.FOOT_RADIUS
        return out

    def safe_spot(self, point: np.ndarray, walk: np.ndarray, top: float) -> tuple[float, float]:
        """Offset along ``walk`` to the nearest safe spot near ``point``, and its ground.

        The ground within ``±0.3 m`` along ``walk`` is cut into flat pieces at its edges;
        a spot keeps ``drop_gap`` from a piece's edge over a drop, ``face_gap`` from one at
        the foot of a riser. Returns ``(0, ground at point)`` where no piece has room.
        """
        g = self.g
        n = round(_SCAN_REACH / 0.01)
        offsets = [0.01 * k for k in range(-n, n + 1)]
        x, y = point[0], point[1]
        heights = [self.scan.height(x + s * walk[0], y + s * walk[1], top) for s in offsets]
        pieces, start = [], 0
        for k in range(1, len(heights) + 1):
            if k == len(heights) or not _same_level(heights[k - 1], heights[k], g.edge_jump):
                pieces.append((start, k - 1))
                start = k
        best, best_height = None, heights[n]
        for a, b in pieces:
            if not math.isfinite(heights[a]):
                continue
            lo = offsets[a] + (_gap(heights, a, -1, g) if a > 0 else 0.0)
            hi = offsets[b] - (_gap(heights, b, 1, g) if b < len(heights) - 1 else 0.0)
            if lo > hi:
                continue
            s = min(max(0.0, lo), hi)
            if best is None or abs(s) < abs(best):
                best, best_height = s, heights[a]
        return (best or 0.0), best_height

    # ---------------------------------------------------------------- stance

    def _stance_targets(self, dt: float, pos, rot, feet: np.ndarray) -> list[float]:
        """Targets of all legs; the stance legs' push their share of the trunk's wrench."""
        g, d = self.g, self.data
        com = d.subtree_com[self.trunk_id]
        if self._goal is None:
            self._goal = com.copy()
        z_goal, pitch_goal = self._posture(pos, rot, feet)
        if self._z is None:
            self._z, self._pitch = z_goal, pitch_goal
        self._z += max(-g.height_rate * dt, min(g.height_rate * dt, z_goal - self._z))
        self._pitch += max(-g.pitch_rate * dt, min(g.pitch_rate * dt, pitch_goal - self._pitch))
        err = np.array([self._goal[0] - com[0], self._goal[1] - com[1], self._z - com[2]])
        err[:2] = np.clip(err[:2], -g.error_cap, g.error_cap)
        vel = d.qvel[self._dof : self._dof + 3]
        kp = np.array([g.kp_xy, g.kp_xy, g.kp_z])
        kd = np.array([g.kd_xy, g.kd_xy, g.kd_z])
        force = kp * err - kd * vel + _WEIGHT
        turn = np.reshape(rotation(0.0, self._pitch, self._yaw), (3, 3)) @ rot.T
        angle = 0.5 * np.array(
            [turn[2, 1] - turn[1, 2], turn[0, 2] - turn[2, 0], turn[1, 0] - turn[0, 1]]
        )
        omega = rot @ d.qvel[self._dof + 3 : self._dof + 6]
        moment = g.kp_attitude * angle - g.kd_attitude * omega
        down = {leg: feet[leg] for leg in range(4) if self.stance[leg]}
        shares = distribute(force, moment, com, down, g.friction)
        q = [float(d.qpos[a]) for a in self.joint_qadr]
        out = list(q)
        for leg, f in shares.items():
            local = rot.T @ f
            a, b, c = q[3 * leg : 3 * leg + 3]
            torque = leg_jacobian_t(leg, a, b, c, (local[0], local[1], local[2]))
            for j in range(3):
                bias = d.qfrc_bias[self.joint_dadr[3 * leg + j]]
                out[3 * leg + j] = q[3 * leg + j] + (bias - torque[j]) / KP
        return out

    def _posture(self, pos, rot, feet: np.ndarray) -> tuple[float, float]:
        """Trunk height and pitch goals: hips over the ground, each in reach of its foot."""
        g = self.g
        heading = self._heading()
        upcoming = self._pairs()[self._pair][self._idx]
        ground, lo, hi = [], [], []
        for leg in range(4):
            hip = pos + rot @ _HIPS[leg]
            samples = [
                self.scan.height(hip[0] + s * heading[0], hip[1] + s * heading[1], pos[2])
                for s in self._window
            ]
            finite = [h for h in samples if math.isfinite(h)]
            foot_ground = feet[leg][2] - const.FOOT_RADIUS
            z = sum(finite) / len(finite) if finite else foot_ground
            low, high = -math.inf, math.inf
            if self.stance[leg]:
                low, high = foot_ground - g.below_foot, foot_ground + g.above_foot
            if leg == upcoming and self._next is not None:
                nxt = self._next[2] - const.FOOT_RADIUS
                low, high = max(low, nxt - g.below_next), min(high, nxt + g.above_next)
            ground.append(min(max(z, low), high))
            lo.append(low)
            hi.append(high)
        pitch = -math.atan2(
            0.5 * (ground[0] + ground[1] - ground[2] - ground[3]), 2.0 * const.HIP_X
        )
        z = sum(ground) / 4.0
        z_lo, z_hi = -math.inf, math.inf
        for leg in range(4):  # every hip within its band at this pitch
            off = const.HIP_OFFSETS[leg][0] * math.sin(-pitch)
            z_lo, z_hi = max(z_lo, lo[leg] - off), min(z_hi, hi[leg] - off)
        z = min(max(z, z_lo), z_hi) if z_lo <= z_hi else z_hi
        return z + const.FOOT_RADIUS + g.height, pitch

    # ----------------------------------------------------------------- swing

    def _swing_targets(self, pos, rot, out: list[float]) -> None:
        """The swing leg's targets: up over the higher end, across, down until it touches."""
        g, d = self.g, self.data
        leg, t0, lift, hold = self._swing
        s = (self._time - t0) / g.swing_time
        top = max(lift[2], hold[2]) + g.clearance
        if s < 0.3:
            w = lift.copy()
            w[2] += (top - lift[2]) * s / 0.3
        elif s < 0.7:
            w = lift + (hold - lift) * (s - 0.3) / 0.4
            w[2] = top
        else:
            w = hold.copy()
            w[2] = top + (hold[2] - top) * min(1.0, (s - 0.7) / 0.3) - 0.05 * max(0.0, s - 1.0)
        local = rot.T @ (w - pos) - _HIPS[leg]
        want = leg_ik(leg, local[0], local[1], local[2])
        for j in range(3):
            k = 3 * leg + j
            q = d.qpos[self.joint_qadr[k]]
            dof = self.joint_dadr[k]
            torque = g.kp_swing * (want[j] - q) - g.kd_swing * d.qvel[dof] + d.qfrc_bias[dof]
            out[k] = q + torque / KP

    def _foot_force(self, leg: int) -> float:
        """Normal force (N) on foot ``leg`` from its contacts."""
        d, g, total = self.data, self.foot_geoms[leg], 0.0
        for i in range(d.ncon):
            c = d.contact[i]
            if c.geom1 == g or c.geom2 == g:
                mujoco.mj_contactForce(self.model, d, i, self._f6)
                total += self._f6[0]
        return total


def _same_level(a: float, b: float, jump: float) -> bool:
    if math.isfinite(a) and math.isfinite(b):
        return abs(a - b) <= jump
    return a == b


def _gap(heights: list[float], k: int, side: int, g: CrawlGains) -> float:
    """The gap a foothold keeps from the edge at sample ``k`` toward ``side`` (±1)."""
    return g.drop_gap if heights[k + side] < heights[k] else g.face_gap
