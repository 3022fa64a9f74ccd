"""Joint targets that make the GO1's position actuators reach the joint angles asked for.

A position actuator's torque is ``kp (target − q)``, less the joint's damping and friction:
aimed straight at a moving joint angle it lags behind (a swing foot 5–10 cm behind its path),
and a loaded leg sags. :class:`Tracker` moves each target by the torque the joint needs over
``kp``: damping and friction at the angle's speed, gravity and bias forces, and for a stance
leg ``−Jᵀf`` to bear the ground's force ``f`` on its foot.
"""

from __future__ import annotations

import math

import mujoco

from havln_mj.robot.go1 import constants as const
from havln_mj.robot.go1.kinematics import leg_jacobian_t

KP = 100.0  # actuator position gain of the model
DAMPING = (1.0, 2.0, 2.0)  # joint damping of (abduction, thigh, knee)
FRICTIONLOSS = 0.2
_QD_MAX = 8.0  # rad/s: faster target steps are jumps, not motion to feed forward
_JOINT_LO = tuple(const.JOINT_RANGES[p][0] for p in const.LEG_PARTS)
_JOINT_HI = tuple(const.JOINT_RANGES[p][1] for p in const.LEG_PARTS)


def clip_joints(q) -> tuple[float, float, float]:
    """A leg's (abduction, thigh, knee) angles clipped to the joint ranges."""
    return tuple(
        lo if v < lo else hi if v > hi else v
        for v, lo, hi in zip(q, _JOINT_LO, _JOINT_HI, strict=True)
    )


class Tracker:
    """Actuator targets for the four legs' joint angles, tick after tick.

    Args:
        data: The robot's data (``qfrc_bias`` is read from it).
        joint_dadr: dof addresses of the 12 leg joints.
    """

    def __init__(self, data: mujoco.MjData, joint_dadr: list[int]) -> None:
        self.data, self.joint_dadr = data, joint_dadr
        self._prev: list[tuple | None] = [None] * 4

    def forget(self, leg: int | None = None) -> None:
        """Drops a leg's last angles (all legs by default): its next target is a jump."""
        if leg is None:
            self._prev = [None] * 4
        else:
            self._prev[leg] = None

    def __call__(self, leg: int, q, dt: float, grf) -> tuple[float, float, float]:
        """Targets for leg ``leg`` to reach angles ``q`` this tick (``dt`` after the last).

        ``grf`` is the ground's force on a stance foot (trunk frame), None for a swing leg.
        """
        prev = self._prev[leg]
        self._prev[leg] = q
        bias = self.data.qfrc_bias
        load = leg_jacobian_t(leg, q[0], q[1], q[2], grf) if grf is not None else (0.0,) * 3
        out = []
        for j in range(3):
            qd = (q[j] - prev[j]) / dt if prev is not None else 0.0
            qd = -_QD_MAX if qd < -_QD_MAX else _QD_MAX if qd > _QD_MAX else qd
            tau = DAMPING[j] * qd + FRICTIONLOSS * math.tanh(qd / 0.2) - load[j]
            out.append(q[j] + (tau + bias[self.joint_dadr[3 * leg + j]]) / KP)
        return clip_joints(out)
