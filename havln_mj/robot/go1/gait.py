"""Phase-based trot: foot targets from a commanded twist, then leg IK into joint targets.

Diagonal pairs (FR+RL, FL+RR) alternate. A stance foot moves in the trunk frame opposite the
commanded twist, −(v + ω×r)·dt, so it stays put on the ground when the trunk follows the
command; a swing foot travels from its lift-off point to the Raibert touch-down point
(v + ω×r)·T_stance/2 plus a balance term on the velocity error, lifted on a smooth profile.
Targets are in the trunk frame, so equal leg lengths keep the trunk level on flat ground.
"""

from __future__ import annotations

from havln_mj.robot.go1.constants import ABDUCTION, HIP_OFFSETS, HOME_LEG, LEG_SIDE, LEGS
from havln_mj.robot.go1.gains import Go1Gains
from havln_mj.robot.go1.kinematics import leg_ik

PHASE_OFFSET = (0.0, 0.5, 0.5, 0.0)  # FR, FL, RR, RL: diagonal pairs half a cycle apart
HOME_CTRL = HOME_LEG * len(LEGS)


def smoothstep(s: float) -> float:
    """0 below 0, 1 above 1, and the cubic ``3s² − 2s³`` between: a swing's lift profile."""
    if s <= 0.0:
        return 0.0
    if s >= 1.0:
        return 1.0
    return s * s * (3.0 - 2.0 * s)


class TrotGait:
    """Trot pattern generator: twist in, 12 joint targets out.

    Call :meth:`start` to begin walking, :meth:`step` every control tick, :meth:`request_stop`
    to end with every foot down (each pair swings once more); ``walking`` turns false
    when they have.
    """

    def __init__(self, gains: Go1Gains) -> None:
        self.gains = gains
        self.walking = False
        self.phase = 0.0
        self.offsets = [[0.0, 0.0] for _ in LEGS]  # foot xy offset from nominal (trunk frame)
        self.lift = [[0.0, 0.0] for _ in LEGS]  # offset at lift-off
        self.stance = [True] * len(LEGS)
        self._stop_at: float | None = None
        self._cycle = 0.0  # phase accumulated since start (cycles), for the stop point

    def start(self) -> None:
        """Begins trotting from the current stance (FL and RR swing first)."""
        self.walking = True
        self.phase = 0.0
        self._cycle = 0.0
        self._stop_at = None
        self.stance = [self._leg_phase(i) < self.gains.duty for i in range(len(LEGS))]

    def home(self) -> None:
        """Puts the foot targets back under the hips (use only when teleporting)."""
        self.walking = False
        self._stop_at = None
        for o in self.offsets:
            o[0] = o[1] = 0.0

    def request_stop(self) -> None:
        """Finishes the current half-cycle, then swings the other pair once more.

        The caller keeps commanding a small holding twist meanwhile; the feet stay where
        they land, so standing and the next start need no jump of the foot targets.
        """
        if self.walking and self._stop_at is None:
            half = 0.5
            next_half = (int(self._cycle / half) + 1) * half
            self._stop_at = next_half + half

    @property
    def stopping(self) -> bool:
        """Whether a stop was requested and the feet are still on their way home."""
        return self._stop_at is not None

    def _leg_phase(self, leg: int) -> float:
        return (self.phase + PHASE_OFFSET[leg]) % 1.0

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
        g = self.gains
        depth = -g.foot_depth
        if not self.walking:
            return self._ik_all(depth, [0.0] * 4)
        self._cycle += dt / g.period
        self.phase = self._cycle % 1.0
        if self._stop_at is not None and self._cycle >= self._stop_at:
            self.walking = False
            self._stop_at = None
            return self._ik_all(depth, [0.0] * 4)
        t_stance = g.duty * g.period
        lift = [0.0] * 4
        for i in range(4):
            psi = self._leg_phase(i)
            o = self.offsets[i]
            hx, hy = HIP_OFFSETS[i]
            rx = hx + o[0]
            ry = hy + LEG_SIDE[i] * ABDUCTION + o[1]
            # Foot velocity in the trunk frame of a point fixed on the ground.
            fx = vx - wz * ry
            fy = vy + wz * rx
            if psi < g.duty:
                self.stance[i] = True
                o[0] -= fx * dt
                o[1] -= fy * dt
            else:
                if self.stance[i]:
                    self.stance[i] = False
                    self.lift[i][0], self.lift[i][1] = o[0], o[1]
                s = (psi - g.duty) / (1.0 - g.duty)
                tx = 0.5 * fx * t_stance + g.raibert_gain * ex
                ty = 0.5 * fy * t_stance + g.raibert_gain * ey
                h = smoothstep((s - 0.1) / 0.75)
                lx, ly = self.lift[i]
                o[0] = lx + (tx - lx) * h
                o[1] = ly + (ty - ly) * h
                if s < 0.4:
                    lift[i] = g.swing_height * smoothstep(s / 0.4)
                else:
                    drop = g.swing_height + g.touchdown_depth
                    lift[i] = g.swing_height - drop * smoothstep((s - 0.4) / 0.6)
        return self._ik_all(depth, lift)

    def _ik_all(self, depth: float, lift: list[float]) -> list[float]:
        out: list[float] = []
        for i in range(4):
            o = self.offsets[i]
            out.extend(
                leg_ik(
                    i,
                    o[0] + self.gains.foot_x_offset,
                    LEG_SIDE[i] * ABDUCTION + o[1],
                    depth + lift[i],
                )
            )
        return out
