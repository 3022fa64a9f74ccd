"""The outer loops of the GO1's primitives: what trunk twist to ask of the gait, and when to stop.

:class:`ForwardCommand` is P on the remaining distance (clipped to a speed floor and cap, and
speeding up at ``forward_accel`` at most) while holding the start heading and lateral offset;
:class:`TurnCommand` is P on the remaining yaw while holding the start position. Each is
called once per control step with ``hold`` (the gentle twist used while the feet come down)
and returns ``(vx, vy, wz, done)`` in the trunk frame. A :class:`Stall` in each ends a
primitive that stops making progress (a robot pushing on a wall would otherwise rear up and
fall).
"""

from __future__ import annotations

import math
from typing import Any, Protocol

import mujoco

from havln_mj.frames import wrap_angle
from havln_mj.robot.go1.gains import Go1Gains

# Blocked: no progress by this much in this long ends a primitive.
STALL_SECONDS = 1.0
STALL_DISTANCE = 0.02  # m
STALL_ANGLE = 0.05  # rad


def clip(v: float, lo: float, hi: float) -> float:
    """``v`` clipped to [lo, hi]."""
    return lo if v < lo else hi if v > hi else v


class Walker(Protocol):
    """What a command reads of the robot (a :class:`~havln_mj.robot.go1.primitives.Go1Body`)."""

    gains: Go1Gains
    est: Any  # the trunk state estimate (x, y, yaw)
    data: mujoco.MjData

    @property
    def measured_vx(self) -> float:
        """The trunk's filtered forward speed (m/s)."""
        ...

    @property
    def measured_wz(self) -> float:
        """The trunk's filtered yaw rate (rad/s)."""
        ...


class Stall:
    """Flags a primitive whose progress has not grown for a while."""

    def __init__(self, data: mujoco.MjData, seconds: float, amount: float) -> None:
        self.data, self.seconds, self.amount = data, seconds, amount
        self.best = 0.0
        self.since = data.time
        self.stalled = False

    def check(self, progress: float) -> bool:
        """Records progress; True once it has stalled."""
        if progress > self.best + self.amount:
            self.best, self.since = progress, self.data.time
        elif self.data.time - self.since > self.seconds:
            self.stalled = True
        return self.stalled


class ForwardCommand:
    """Walks ``distance`` metres along the start heading (negative: backwards) at ≤ ``v_max``."""

    def __init__(
        self, body: Walker, distance: float, v_max: float, stall_seconds: float = STALL_SECONDS
    ) -> None:
        e = body.est
        self.body, self.distance, self.v_max = body, distance, v_max
        self.x0, self.y0, self.yaw0 = e.x, e.y, e.yaw
        self.c0, self.s0 = math.cos(self.yaw0), math.sin(self.yaw0)
        self.sign = 1.0 if distance >= 0 else -1.0
        self.stall = Stall(body.data, stall_seconds, STALL_DISTANCE)
        self.v, self.t = 0.0, body.data.time  # the speed asked last (from a stand), and when

    def __call__(self, hold: bool) -> tuple[float, float, float, bool]:
        """The twist and whether the target is reached."""
        g, e, sign = self.body.gains, self.body.est, self.sign
        c0, s0 = self.c0, self.s0
        dx, dy = e.x - self.x0, e.y - self.y0
        along = c0 * dx + s0 * dy
        lat = -s0 * dx + c0 * dy
        dyaw = wrap_angle(e.yaw - self.yaw0)
        rem = self.distance - along
        # Stop a little early: the trunk coasts on while the last feet come down.
        done = rem * sign < g.forward_stop + g.forward_lead * abs(self.body.measured_vx)
        done = self.stall.check(sign * along) or done
        if hold or done:  # no speed floor: creep back or forward onto the target
            v = clip(g.forward_kp * rem, -g.forward_v_min, g.forward_v_min)
        else:
            v = sign * clip(g.forward_kp * abs(rem), g.forward_v_min, self.v_max)
        t = self.body.data.time
        step, self.t = g.forward_accel * (t - self.t), t
        if abs(v) > abs(self.v) + step:  # speeding up: at most forward_accel
            v = clip(v, self.v - step, self.v + step)
        self.v = v
        vl = clip(-g.forward_k_lateral * lat, -0.15, 0.15)
        w = clip(-g.forward_k_yaw * dyaw, -0.5, 0.5)
        cd, sd = math.cos(dyaw), math.sin(dyaw)
        return cd * v + sd * vl, -sd * v + cd * vl, w, done


class TurnCommand:
    """Turns in place by ``theta`` radians of heading (positive turns right)."""

    def __init__(self, body: Walker, theta: float, stall_seconds: float = STALL_SECONDS) -> None:
        e = body.est
        self.body = body
        self.x0, self.y0 = e.x, e.y
        self.target = -theta  # yaw grows turning left
        self.sign = 1.0 if self.target >= 0 else -1.0
        self.turned = 0.0
        self.last = e.yaw
        self.stall = Stall(body.data, stall_seconds, STALL_ANGLE)

    def __call__(self, hold: bool) -> tuple[float, float, float, bool]:
        """The twist and whether the target is reached."""
        g, e, sign = self.body.gains, self.body.est, self.sign
        self.turned += wrap_angle(e.yaw - self.last)  # unwrapped, so turns past π work
        self.last = e.yaw
        rem = self.target - self.turned
        done = rem * sign < g.turn_stop + g.turn_lead * abs(self.body.measured_wz)
        done = self.stall.check(sign * self.turned) or done
        if hold or done:
            w = clip(g.turn_kp * rem, -g.turn_w_min, g.turn_w_min)
        else:
            w = sign * clip(g.turn_kp * abs(rem), g.turn_w_min, g.turn_w_max)
        # Hold the start point: world correction velocity into the trunk frame.
        cx, cy = -g.turn_k_hold * (e.x - self.x0), -g.turn_k_hold * (e.y - self.y0)
        c, s = math.cos(e.yaw), math.sin(e.yaw)
        vx = clip(c * cx + s * cy, -0.15, 0.15)
        vy = clip(-s * cx + c * cy, -0.15, 0.15)
        return vx, vy, w, done
