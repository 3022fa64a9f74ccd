"""Trunk state estimates for the controller: ground truth, or odometry like the real robot.

``TruthEstimator`` reads the free joint. ``OdometryEstimator`` integrates yaw from the IMU gyro
(sensor ``gyro``; roll and pitch from the attitude, as the robot's IMU filter gives them) and
position from leg kinematics: while a foot is in stance, the trunk moves opposite to that
foot's motion in the trunk frame (joint encoders through forward kinematics). Foot slip,
soft-foot sink and feet that touch late or early make it drift, as on the real robot.
"""

from __future__ import annotations

import math

import mujoco

from havln_mj.frames import wrap_angle
from havln_mj.robot.go1.kinematics import leg_fk

ESTIMATES = ("truth", "odometry")


def quat_yaw(w: float, x: float, y: float, z: float) -> float:
    """Yaw (radians about world z) of the body x axis for a (w, x, y, z) quaternion."""
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def _rotate(q: tuple[float, float, float, float], v: tuple[float, float, float]):
    """Rotates vector ``v`` by unit quaternion ``q`` (w, x, y, z)."""
    w, x, y, z = q
    vx, vy, vz = v
    # t = 2 q_vec × v; v' = v + w t + q_vec × t
    tx = 2.0 * (y * vz - z * vy)
    ty = 2.0 * (z * vx - x * vz)
    tz = 2.0 * (x * vy - y * vx)
    return (
        vx + w * tx + (y * tz - z * ty),
        vy + w * ty + (z * tx - x * tz),
        vz + w * tz + (x * ty - y * tx),
    )


class TruthEstimator:
    """The simulator's trunk pose and velocity.

    After :meth:`update`: ``x``, ``y``, ``z``, ``yaw`` (world); ``vx``, ``vy`` (m/s in the
    yaw-aligned trunk frame); ``wz`` (yaw rate, rad/s).
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, qadr: int, dadr: int) -> None:
        self.model, self.data = model, data
        self.qadr, self.dadr = qadr, dadr
        self.x = self.y = self.z = self.yaw = 0.0
        self.vx = self.vy = self.wz = 0.0
        self.quat = (1.0, 0.0, 0.0, 0.0)

    def truth(self) -> list[float]:
        """(x, y, z, qw, qx, qy, qz) of the trunk from the simulator."""
        a = self.qadr
        return self.data.qpos[a : a + 7].tolist()

    def reset(self) -> None:
        """Starts over from the simulator's state (after a teleport)."""
        x, y, z, *q = self.truth()
        self.quat = tuple(q)
        self.x, self.y, self.z = x, y, z
        self.yaw = quat_yaw(*q)
        self.vx = self.vy = self.wz = 0.0

    def update(self, dt: float, stance: list[bool]) -> None:
        """Reads the new state (``dt`` and ``stance`` are for the odometry estimator)."""
        x, y, z, *q = self.truth()
        self.quat = tuple(q)
        self.x, self.y, self.z = x, y, z
        self.yaw = quat_yaw(*q)
        d = self.dadr
        vx, vy, _, ox, oy, oz = self.data.qvel[d : d + 6].tolist()
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        self.vx, self.vy = c * vx + s * vy, -s * vx + c * vy
        self.wz = _rotate(self.quat, (ox, oy, oz))[2]


class OdometryEstimator(TruthEstimator):
    """Dead reckoning from the gyro and leg kinematics, started from the true pose at reset.

    Height (``z``) is read from the simulator; it does not feed the controller.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        qadr: int,
        dadr: int,
        gyro_adr: int,
        joint_qadr: list[int],
    ) -> None:
        super().__init__(model, data, qadr, dadr)
        self.gyro_adr = gyro_adr
        self.joint_qadr = joint_qadr
        self._feet: list[tuple[float, float, float] | None] = [None] * 4

    def _foot_positions(self) -> list[tuple[float, float, float]]:
        qpos = self.data.qpos
        out = []
        for leg in range(4):
            a = self.joint_qadr[3 * leg]
            q1, q2, q3 = qpos[a : a + 3].tolist()
            out.append(leg_fk(leg, q1, q2, q3))
        return out

    def reset(self) -> None:
        """Starts dead reckoning from the simulator's current pose."""
        super().reset()
        self._feet = [None] * 4

    def update(self, dt: float, stance: list[bool]) -> None:
        """Integrates the gyro and the stance legs' motion over the last ``dt`` seconds."""
        if dt <= 0.0:
            return
        _, _, z, *q = self.truth()
        # Attitude: keep the true roll and pitch, replace yaw by the integrated one.
        true_yaw = quat_yaw(*q)
        self.quat = tuple(q)
        self.z = z
        g = self.gyro_adr
        ox, oy, oz = self.data.sensordata[g : g + 3].tolist()
        self.wz = _rotate(self.quat, (ox, oy, oz))[2]
        self.yaw = wrap_angle(self.yaw + self.wz * dt)
        feet = self._foot_positions()
        sx = sy = sz = 0.0
        n = 0
        for leg in range(4):
            prev = self._feet[leg]
            now = feet[leg]
            if stance[leg] and prev is not None:
                # Trunk displacement in its own frame: the foot's apparent motion, reversed,
                # minus the part due to the trunk's rotation (ω × p dt).
                rx = oy * now[2] - oz * now[1]
                ry = oz * now[0] - ox * now[2]
                rz = ox * now[1] - oy * now[0]
                sx += prev[0] - now[0] - rx * dt
                sy += prev[1] - now[1] - ry * dt
                sz += prev[2] - now[2] - rz * dt
                n += 1
            self._feet[leg] = now if stance[leg] else None
        if n == 0:
            self.vx = self.vy = 0.0
            return
        wx, wy, _ = _rotate(self.quat, (sx / n, sy / n, sz / n))
        # World displacement with the true attitude, then turned by the yaw estimate's error.
        e = self.yaw - true_yaw
        ce, se = math.cos(e), math.sin(e)
        dx, dy = ce * wx - se * wy, se * wx + ce * wy
        self.x += dx
        self.y += dy
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        self.vx = (c * dx + s * dy) / dt
        self.vy = (-s * dx + c * dy) / dt
