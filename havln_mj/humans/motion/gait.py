"""Walking: footsteps planted along a route, legs by IK, a gait shaped by measured curves.

The walker's pelvis follows a :class:`~havln_mj.humans.motion.route.Route`. Feet alternate
at a constant cadence (cycle time from speed and height, so stride = speed × cycle); each
foot is planted for 60 % of the cycle at a footprint beside the route, swings 40 % to the
next one, and rolls heel-to-toe while planted
(:func:`~havln_mj.humans.motion.joints.ankle_from_contact`), so the planted foot does not slide. The
foot's pitch over the cycle comes from the myosuite sample gait cycle (hip − knee + ankle sagittal
angles, facts in the project's SMPL reference), scaled by the step length; hip and knee follow from
leg IK. The pelvis bobs, sways, rolls, tilts and yaws with the published amplitudes, and is lowered
where a leg could not reach. Arms swing opposite the legs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from havln_mj.humans import rotations as rot
from havln_mj.humans.clip import Clip
from havln_mj.humans.motion import joints as jt
from havln_mj.humans.motion.route import Route
from havln_mj.humans.skeleton import JOINT, NUM_JOINTS, rest_offsets, rest_positions

FPS = 30.0
"""Frames per second of the procedural clips."""
STANCE = 0.6  # fraction of the cycle a foot is planted
FOOTPRINT_PHASE = 0.25  # the planted ankle is under the hip here (fits the hip range best)
REFERENCE_HEIGHT = 1.75  # metres; cadence scales with sqrt(height / this)

# Myosuite sample gait cycle, left leg, degrees at % of the cycle (0 = initial contact).
_CYCLE_PCT = np.array([0, 10, 20, 30, 40, 50, 60, 65, 70, 75, 80, 90])
_HIP_FLEX = np.array([27.6, 28.1, 19.7, 5.5, -7.3, -16.3, -18.2, -11.4, -1.5, 6.8, 17.3, 25.8])
_KNEE_FLEX = np.array([-3.0, 12.3, 19.9, 13.7, 5.0, 3.2, 20.8, 39.0, 55.1, 61.2, 61.4, 30.8])
_ANKLE_DF = np.array([6.1, -2.5, 1.0, 5.3, 8.6, 15.9, -0.4, -12.2, -21.8, -10.3, -1.2, 3.0])
_CYCLE_STRIDE = 0.70  # stride of that cycle as a fraction of height (1.22 m)
PELVIS_ROLL = math.radians(4.8)
PELVIS_TILT = (math.radians(0.6), math.radians(5.7))
PELVIS_YAW = math.radians(3.8)
ARM_ARC = math.radians(30.0)  # total arc of each arm at normal speed


class PeriodicSpline:
    """The periodic cubic spline through ``(x, y)`` (``y[-1] == y[0]``), C² all round.

    What ``scipy.interpolate.CubicSpline(x, y, bc_type="periodic")`` computes (the same
    unique curve, to rounding), in a few lines of numpy: gait needs one small spline, and
    scipy's interpolation package is a large import.
    """

    def __init__(self, x: np.ndarray, y: np.ndarray) -> None:
        x, y = np.asarray(x, float), np.asarray(y, float)
        h = np.diff(x)
        n = len(h)
        slope = np.diff(y) / h
        # Second derivatives m_i at x_0..x_{n-1} (m_n = m_0): a cyclic tridiagonal system.
        a = np.zeros((n, n))
        i = np.arange(n)
        a[i, i] = 2.0 * (h + np.roll(h, 1))
        a[i, (i + 1) % n] += h
        a[i, (i - 1) % n] += np.roll(h, 1)
        m = np.linalg.solve(a, 6.0 * (slope - np.roll(slope, 1)))
        m1 = np.roll(m, -1)
        self._x, self._period = x, x[-1] - x[0]
        self._coef = (y[:-1], slope - h * (2.0 * m + m1) / 6.0, m / 2.0, (m1 - m) / (6.0 * h))

    def __call__(self, u: np.ndarray) -> np.ndarray:
        """Values at ``u`` (any shape; outside the knots the curve repeats)."""
        x = self._x
        u = x[0] + np.mod(np.asarray(u, float) - x[0], self._period)
        k = np.clip(np.searchsorted(x, u, side="right") - 1, 0, len(x) - 2)
        t = u - x[k]
        y0, b, c, d = (c[k] for c in self._coef)
        return y0 + t * (b + t * (c + t * d))


def _foot_pitch_spline() -> PeriodicSpline:
    # The foot's angle to the floor is the sum of the sagittal joint angles down the leg;
    # the offset makes it zero on average while the foot is flat (20–50 %).
    pitch = _HIP_FLEX - _KNEE_FLEX + _ANKLE_DF
    flat = (_CYCLE_PCT >= 20) & (_CYCLE_PCT <= 50)
    pitch = np.radians(pitch - pitch[flat].mean())
    return PeriodicSpline(np.append(_CYCLE_PCT, 100) / 100.0, np.append(pitch, pitch[0]))


FOOT_PITCH = _foot_pitch_spline()
"""Foot pitch (rad, toes up positive) over the gait cycle, 0 = heel strike."""


@dataclass(frozen=True)
class GaitStyle:
    """One person's way of walking (drawn once per person from the rng).

    Attributes:
        cadence: Multiplies the nominal cycle time (below 1: quicker steps).
        arm_swing: Multiplies the arms' swing arc.
        elbow: Elbow flexion while walking (rad).
        bob: Vertical pelvis bob amplitude, fraction of height.
        width: Half the step width (foot centre to route), fraction of height.
        lift: Swing-foot clearance at normal speed, fraction of height.
        pelvis: Multiplies the pelvis rotations.
        lean: Forward lean of the trunk at normal speed (rad).
        toe_out: Feet turned out from the walking direction (rad).
    """

    cadence: float = 1.0
    arm_swing: float = 1.0
    elbow: float = 0.3
    bob: float = 0.008
    width: float = 0.04
    lift: float = 0.022
    pelvis: float = 1.0
    lean: float = 0.05
    toe_out: float = 0.08

    @classmethod
    def sample(cls, rng: np.random.Generator) -> GaitStyle:
        """A random style around the defaults."""
        u = rng.uniform(-1.0, 1.0, 9)
        return cls(
            cadence=1.0 + 0.04 * u[0],
            arm_swing=1.0 + 0.25 * u[1],
            elbow=0.3 + 0.1 * u[2],
            bob=0.008 + 0.002 * u[3],
            width=0.04 + 0.006 * u[4],
            lift=0.022 + 0.004 * u[5],
            pelvis=1.0 + 0.2 * u[6],
            lean=0.05 + 0.03 * u[7],
            toe_out=0.08 + 0.04 * u[8],
        )


def cycle_time(speed: float, height: float, style: GaitStyle | None = None) -> float:
    """Seconds per gait cycle (two steps) at ``speed``.

    1.25 s at 0.6 m/s down to 1.0 s at 1.4 m/s for a 1.75 m person (96–120 steps/min), so
    the stride ``speed × cycle`` grows from 0.75 m to 1.4 m.
    """
    base = 1.25 - 0.25 * float(np.clip((speed - 0.6) / 0.8, 0.0, 1.25))
    return base * math.sqrt(height / REFERENCE_HEIGHT) * (style.cadence if style else 1.0)


def walk(
    route: Route,
    height: float,
    style: GaitStyle,
    speed: float,
    *,
    phone: bool = False,
    name: str = "walk",
) -> Clip:
    """A looping walking clip along ``route``.

    Args:
        route: The pelvis route; its period should be a whole number of frames at :data:`FPS`.
        height: The person's height (m).
        style: How they walk.
        speed: The commanded speed (sets the cadence).
        phone: Hold a phone to the right ear (right arm still, head tilted, less arm swing).
        name: The clip's name.
    """
    n = max(2, round(route.period * FPS) + 1)
    t = np.arange(n) * (route.period / (n - 1))
    cycles = max(1, round(route.period / cycle_time(speed, height, style)))
    period = route.period / cycles
    offsets = rest_offsets(height)
    xy, yaw, v = route.at(t)
    amp = np.clip(v / 1.24, 0.0, 1.2)  # how much of the normal gait's sway and swing
    phase = np.mod(t / period, 1.0)  # 0 = left heel strike

    feet = {}
    for side, start in ((jt.LEFT, 0.0), (jt.RIGHT, 0.5)):
        feet[side] = _foot_track(route, t, height, style, side, start * period, period)

    # Pelvis: sway toward the planted foot, bob lowest in double support, roll, tilt, yaw.
    s = style.pelvis * amp
    sway = -0.008 * height * amp * np.sin(2 * np.pi * phase)
    bob = -style.bob * height * amp * np.cos(4 * np.pi * (phase - 0.05))
    roll = PELVIS_ROLL * s * np.sin(2 * np.pi * phase)
    tilt_mid, tilt_amp = np.mean(PELVIS_TILT), np.ptp(PELVIS_TILT) / 2
    tilt = (tilt_mid + tilt_amp * np.cos(4 * np.pi * phase)) * s
    pyaw = -PELVIS_YAW * s * np.cos(2 * np.pi * phase)
    heading = rot.from_axis(jt.Z_AXIS, yaw)
    pelvis_q = rot.mul(heading, jt.trunk(flex=tilt, bend=roll, twist=pyaw))
    root = np.zeros((n, 3))
    root[:, :2] = xy + rot.rotate(heading, np.stack([sway, 0 * sway, 0 * sway], -1))[:, :2]
    root[:, 2] = rest_positions(height)[0, 2] - 0.01 * height + bob
    root[:, 2] -= _reach_deficit(offsets, root, pelvis_q, feet, height)

    local = np.tile(rot.identity(), (n, NUM_JOINTS, 1))
    local[:, 0] = pelvis_q
    for side, (ankle, foot_q) in feet.items():
        hip_name = "right_hip" if side > 0 else "left_hip"
        hip = root + rot.rotate(pelvis_q, offsets[JOINT[hip_name]])
        hq, kq, aq = jt.leg_ik(offsets, side, hip, pelvis_q, ankle, foot_q)
        prefix = "right" if side > 0 else "left"
        local[:, JOINT[hip_name]] = hq
        local[:, JOINT[f"{prefix}_knee"]] = kq
        local[:, JOINT[f"{prefix}_ankle"]] = aq

    # Trunk upright (a little lean with speed), counter-rotating the pelvis; head level.
    chest = rot.mul(heading, jt.trunk(flex=style.lean * amp, twist=-0.6 * pyaw))
    jt.set_spine(local, rot.mul(rot.conj(pelvis_q), chest))
    head_bend, head_flex = (0.12, 0.08) if phone else (0.0, 0.04)
    head = rot.mul(heading, jt.trunk(flex=head_flex, bend=head_bend))
    jt.set_neck(local, rot.mul(rot.conj(chest), head))

    # Arms: reciprocal to the legs, the left arm furthest back at left heel strike.
    swing = 0.5 * ARM_ARC * style.arm_swing * np.clip(amp, 0.25, 1.2) * np.cos(2 * np.pi * phase)
    for side, sign in ((jt.LEFT, -1.0), (jt.RIGHT, 1.0)):
        if phone and side == jt.RIGHT:
            jt.set_arm(local, side, *PHONE_ARM)
            continue
        flex = 0.05 + sign * swing * (0.4 if phone else 1.0)
        jt.set_arm(local, side, flex, style.elbow + 0.6 * np.maximum(flex, 0.0))
    return Clip(root, FPS, local=rot.normalize(local), name=name)


PHONE_ARM = (1.02, 2.55, 0.2, 0.75)
"""(flex, elbow, abduct, across) of an arm holding a phone to the ear."""


def _foot_track(
    route: Route,
    t: np.ndarray,
    height: float,
    style: GaitStyle,
    side: float,
    first_strike: float,
    period: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Ankle positions ``(n, 3)`` and foot orientations ``(n, 4)`` of one foot."""
    cyc = (t - first_strike) / period
    k = np.floor(cyc).astype(int)
    u = cyc - k  # phase within this foot's cycle: planted for u < STANCE
    steps = np.arange(k.min() - 1, k.max() + 2)
    # Footprint k: beside the route where the pelvis is at mid-stance.
    mid_xy, mid_yaw, _ = route.at(first_strike + (steps + FOOTPRINT_PHASE) * period)
    beside = np.stack(
        [
            np.full(len(steps), side * style.width * height),
            np.full(len(steps), rest_positions(height)[JOINT["left_ankle"], 1]),
        ],
        -1,
    )
    ground = (
        mid_xy
        + rot.rotate(rot.from_axis(jt.Z_AXIS, mid_yaw), np.pad(beside, ((0, 0), (0, 1))))[:, :2]
    )
    foot_yaw = mid_yaw - side * style.toe_out
    # Each swing's size scales the foot roll and the clearance (turning steps are small).
    reach = np.linalg.norm(np.diff(ground, axis=0), axis=1)  # swing from step i to i+1
    amp = np.clip(reach / (_CYCLE_STRIDE * height), 0.1, 1.15)
    i = k - steps[0]  # index of the current footprint
    stance = u < STANCE
    a_in = amp[np.maximum(i - 1, 0)]
    a_out = amp[np.minimum(i, len(amp) - 1)]
    ramp = np.clip(u / STANCE, 0.0, 1.0)
    a = np.where(stance, a_in + (a_out - a_in) * ramp * ramp * (3 - 2 * ramp), a_out)
    pitch = FOOT_PITCH(u) * a
    # Swing: leave the floor, move across (min-jerk) with the lift above the floor, land.
    w = np.clip((u - STANCE) / (1 - STANCE), 0.0, 1.0)
    p = np.clip((w - 0.1) / 0.9, 0.0, 1.0)
    p = p**3 * (10 - 15 * p + 6 * p**2)
    nxt = np.minimum(i + 1, len(ground) - 1)
    g = ground[i] + p[:, None] * (ground[nxt] - ground[i])
    fy = foot_yaw[i] + p * (foot_yaw[nxt] - foot_yaw[i])
    clearance = height * np.maximum(0.012, style.lift * a_out)
    lift = np.where(stance, 0.0, clearance * np.sin(np.pi * w) ** 1.5)
    return jt.ankle_from_contact(height, g, fy, pitch, lift)


def _reach_deficit(
    offsets: np.ndarray,
    root: np.ndarray,
    pelvis_q: np.ndarray,
    feet: dict,
    height: float,
) -> np.ndarray:
    """How far to lower the pelvis per frame so both legs reach their feet, smoothed.

    The deficit is spread with a running maximum then a short average over the same window,
    so the smoothed curve never falls below the raw one and the legs never over-stretch.
    """
    reach = 0.997 * jt.leg_reach(offsets)
    need = np.zeros(len(root))
    for side, (ankle, _) in feet.items():
        hip_name = "right_hip" if side > 0 else "left_hip"
        hip = root + rot.rotate(pelvis_q, offsets[JOINT[hip_name]])
        horiz = np.linalg.norm(ankle[:, :2] - hip[:, :2], axis=1)
        top = ankle[:, 2] + np.sqrt(np.maximum(reach**2 - horiz**2, 0.0))
        need = np.maximum(need, hip[:, 2] - top)
    need = np.maximum(need[:-1], 0.0)  # the last frame repeats the first
    half = max(1, round(0.07 * FPS))
    idx = (np.arange(len(need))[:, None] + np.arange(-half, half + 1)) % len(need)
    widened = need[idx].max(axis=1)
    kernel = np.hanning(2 * half + 3)[1:-1]
    smooth = (widened[idx] * kernel).sum(axis=1) / kernel.sum()
    return np.append(smooth, smooth[0])
