"""Motion recipes: each returns a looping :class:`~havln_mj.humans.clip.Clip` in the anchor frame.

The anchor frame has its origin on the floor at the person's spot, z up, and the person
facing +y. Standing recipes keep both feet planted (the legs follow the pelvis by IK), so
no foot slides; walking recipes plant their footsteps (:mod:`~havln_mj.humans.motion.gait`). Every
recipe draws its small per-person variations (amplitudes, phases, rates) from the ``rng`` it is
given, so one seed always gives the same clip and two seeds give different ones. Periodic
motions use whole numbers of cycles per loop so the loop is seamless.
"""

from __future__ import annotations

import math

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.humans import rotations as rot
from havln_mj.humans.clip import Clip
from havln_mj.humans.motion import joints as jt
from havln_mj.humans.motion.gait import FPS, PHONE_ARM, GaitStyle, walk
from havln_mj.humans.motion.posing import (
    BOOK,
    COUNTER,
    GESTURE,
    HANG,
    OVERHEAD,
    STANCE_X,
    STANCE_Y,
    THIGHS,
    PoseBuilder,
    check_choice,
    check_height,
    loop_times,
    minjerk,
    wave,
)
from havln_mj.humans.motion.route import loop_route
from havln_mj.humans.skeleton import JOINT

SEAT_CLEARANCE = 0.08
"""Height of the pelvis joint above the seat when sitting, as a fraction of body height."""
REACH_KINDS = ("up", "down", "forward")
EXERCISE_KINDS = ("squat", "stretch", "jumping_jacks")
SIT_POSES = ("rest", "read", "talk")


def _idle_sway(body: PoseBuilder, rng: np.random.Generator, t: np.ndarray, period: float) -> None:
    """Weight shift, breathing and a wandering gaze: the base of every standing recipe."""
    h = body.height
    shift = wave(rng, t, period, rng.uniform(0.2, 0.3), rng.uniform(0.01, 0.02))
    body.root[:, 0] += shift
    body.set_pelvis(jt.trunk(bend=-1.2 * shift / h, twist=wave(rng, t, period, 0.1, 0.03)))
    breath = wave(rng, t, period, rng.uniform(0.22, 0.3), math.radians(1.0))
    drift = wave(rng, t, period, 0.12, math.radians(rng.uniform(2.0, 4.0)))
    chest = jt.trunk(flex=0.03 - breath, bend=0.5 * drift)
    look = wave(rng, t, period, 0.1, math.radians(rng.uniform(3.0, 8.0)))
    nod = wave(rng, t, period, 0.15, math.radians(rng.uniform(2.0, 4.0)))
    body.set_trunk(chest, jt.trunk(flex=0.05 + nod, twist=look))


def idle(height: float, rng: np.random.Generator, duration: float = 8.0) -> Clip:
    """Standing still: weight shifting, breathing, arms hanging, looking around.

    Args:
        height: The person's height (m).
        rng: Source of the person's variations.
        duration: Seconds per loop (at least 2).
    """
    h = check_height(height)
    t = loop_times(duration, 2.0)
    body = PoseBuilder(h, len(t))
    _idle_sway(body, rng, t, t[-1])
    for side in (jt.LEFT, jt.RIGHT):
        body.set_arm(side, HANG, flex=wave(rng, t, t[-1], 0.2, 0.03))
    body.plant_feet()
    return body.clip("idle")


def talk(
    height: float, rng: np.random.Generator, duration: float = 8.0, phone: bool = False
) -> Clip:
    """Standing and talking with hand gestures (or on a phone held to the right ear).

    Args:
        height: The person's height (m).
        rng: Source of the person's variations.
        duration: Seconds per loop (at least 2).
        phone: Hold a phone with the right hand; the left hand gestures now and then.
    """
    h = check_height(height)
    t = loop_times(duration, 2.0)
    period = t[-1]
    body = PoseBuilder(h, len(t))
    _idle_sway(body, rng, t, period)
    turn = wave(rng, t, period, 0.08, math.radians(rng.uniform(8.0, 15.0)))
    nod = wave(rng, t, period, rng.uniform(0.6, 1.0), math.radians(3.0))
    bend = 0.12 if phone else 0.0
    body.set_trunk(body.chest, jt.trunk(flex=0.06 + nod, bend=bend, twist=turn))
    scale = rng.uniform(0.6, 1.2)
    for side in (jt.LEFT, jt.RIGHT):
        if phone and side == jt.RIGHT:
            body.set_arm(side, PHONE_ARM)
            continue
        # Gestures come and go: a slow envelope times a quicker beat.
        env = 0.5 + 0.5 * np.sin(2 * np.pi * t / period + rng.uniform(0, 2 * np.pi))
        beat = wave(rng, t, period, rng.uniform(0.8, 1.5), 1.0)
        base = GESTURE if not phone else HANG
        body.set_arm(
            side,
            base,
            flex=0.15 * scale * env * beat + (0.1 * env if phone else 0.0),
            elbow=0.35 * scale * env * wave(rng, t, period, 1.1, 1.0) + (0.9 * env if phone else 0),
            across=0.15 * scale * env * beat,
        )
    body.plant_feet()
    return body.clip("talk_phone" if phone else "talk")


def reach(height: float, rng: np.random.Generator, kind: str = "up", duration: float = 6.0) -> Clip:
    """Reaching up to a shelf, bending down to the floor, or working at a counter; loops.

    Args:
        height: The person's height (m).
        rng: Source of the person's variations.
        kind: ``"up"``, ``"down"`` or ``"forward"`` (hands busy at waist height).
        duration: Seconds per loop (at least 4).
    """
    h = check_height(height)
    check_choice("reach kind", kind, REACH_KINDS)
    t = loop_times(duration, 4.0)
    period = t[-1]
    body = PoseBuilder(h, len(t))
    _idle_sway(body, rng, t, period)
    if kind == "forward":
        busy = [wave(rng, t, period, rng.uniform(1.0, 2.0), 1.0) for _ in range(3)]
        body.set_trunk(
            rot.mul(body.chest, jt.trunk(flex=rng.uniform(0.1, 0.2))), jt.trunk(flex=0.45)
        )
        for side in (jt.LEFT, jt.RIGHT):
            body.set_arm(
                side, COUNTER, flex=0.08 * busy[0], elbow=0.15 * busy[1], across=0.1 * busy[2]
            )
        body.plant_feet()
        return body.clip("reach_forward")
    # Go (1.2 s), hold (1 s, hands busy), come back (1.2 s), rest for the remainder.
    go, hold = rng.uniform(1.0, 1.4), rng.uniform(0.8, 1.4)
    squeeze = min(1.0, (period - 0.5) / (2 * go + hold))  # leave ≥ 0.5 s at rest
    go, hold = go * squeeze, hold * squeeze
    e = minjerk(t / go) - minjerk((t - go - hold) / go)
    busy = 0.08 * np.sin(2 * np.pi * 1.5 * t) * np.clip(e, 0, 1) ** 4
    if kind == "up":
        both = rng.random() < 0.4
        body.set_trunk(
            rot.mul(body.chest, jt.trunk(flex=-0.08 * e)), jt.trunk(flex=0.05 - 0.35 * e)
        )
        for side in (jt.LEFT, jt.RIGHT):
            if side == jt.RIGHT or both:
                body.set_arm(side, HANG, flex=(OVERHEAD[0] - HANG[0]) * e + busy, elbow=0.1 * e)
            else:
                body.set_arm(side, HANG)
        toes = -0.3 * e  # up on the toes
        body.root[:, 2] += _heel_raise(h, toes)
        body.plant_feet(pitch=toes)
        return body.clip("reach_up")
    # Down: hips back and down, trunk folds, knees bend, hands go toward the floor.
    body.root[:, 1] -= 0.08 * h * e
    body.root[:, 2] -= 0.14 * h * e
    body.set_pelvis(rot.mul(body.pelvis, jt.trunk(flex=0.55 * e)))
    body.set_trunk(rot.mul(body.chest, jt.trunk(flex=1.2 * e)), jt.trunk(flex=0.05 + 0.9 * e))
    for side in (jt.LEFT, jt.RIGHT):
        body.set_arm(side, HANG, flex=0.5 * e + busy, elbow=0.2 * e)
    body.plant_feet()
    return body.clip("reach_down")


def _heel_raise(height: float, pitch: np.ndarray) -> np.ndarray:
    """How much the ankle (and so the pelvis) rises when standing on the toes at ``pitch``."""
    ankle, _ = jt.ankle_from_contact(height, np.zeros((len(pitch), 2)), np.zeros(len(pitch)), pitch)
    return ankle[:, 2] - 0.039 * height


def exercise(
    height: float, rng: np.random.Generator, kind: str = "squat", duration: float = 9.0
) -> Clip:
    """Exercising on the spot: squats, side stretches or jumping jacks; loops.

    Args:
        height: The person's height (m).
        rng: Source of the person's variations.
        kind: ``"squat"``, ``"stretch"`` or ``"jumping_jacks"``.
        duration: Seconds per loop (at least 3); whole repetitions are fitted into it.
    """
    h = check_height(height)
    check_choice("exercise kind", kind, EXERCISE_KINDS)
    t = loop_times(duration, 3.0)
    period = t[-1]
    body = PoseBuilder(h, len(t))
    if kind == "squat":
        reps = max(1, round(period / rng.uniform(2.6, 3.4)))
        e = 0.5 - 0.5 * np.cos(2 * np.pi * reps * t / period)
        body.root[:, 1] -= 0.07 * h * e
        body.root[:, 2] -= rng.uniform(0.17, 0.22) * h * e
        body.set_pelvis(jt.trunk(flex=0.45 * e))
        body.set_trunk(jt.trunk(flex=0.6 * e), jt.trunk(flex=0.35 * e))
        for side in (jt.LEFT, jt.RIGHT):
            body.set_arm(side, HANG, flex=1.5 * e, elbow=-0.1 * e)
        body.plant_feet(spread=0.075)
        return body.clip("squat")
    if kind == "stretch":
        reps = max(1, round(period / rng.uniform(7.0, 9.0)))
        s = np.sin(2 * np.pi * reps * t / period)  # > 0: leaning to the right
        bend = rng.uniform(0.3, 0.45) * s
        body.set_trunk(jt.trunk(bend=bend), jt.trunk(bend=0.5 * bend))
        for side in (jt.LEFT, jt.RIGHT):
            up = np.clip(-side * s, 0.0, 1.0) ** 0.7  # the arm on the outside goes overhead
            body.set_arm(side, HANG, flex=(OVERHEAD[0] - HANG[0]) * up, abduct=0.3 * up)
        body.root[:, 0] -= 0.02 * h * s  # hips shift away from the lean
        body.plant_feet(spread=0.07)
        return body.clip("stretch")
    # Jumping jacks: airborne 30 % of each half-cycle while the feet move apart or together.
    reps = max(1, round(period / rng.uniform(1.1, 1.4)))
    ph = np.mod(reps * t / period, 1.0)
    hop = np.sin(np.pi * np.clip(np.mod(ph, 0.5) / 0.3, 0.0, 1.0))  # 0 on the ground
    apart = np.where(ph < 0.5, minjerk(ph / 0.3), 1.0 - minjerk((ph - 0.5) / 0.3))
    jump, arms, wide = rng.uniform(0.02, 0.035), rng.uniform(2.3, 2.7), rng.uniform(0.06, 0.1)
    body.root[:, 2] += jump * h * hop
    for side in (jt.LEFT, jt.RIGHT):
        body.set_arm(side, HANG, abduct=arms * apart, elbow=0.2 * apart)
    body.set_trunk(rot.identity((len(t),)), jt.trunk(flex=0.05))
    spread = STANCE_X + wide * apart
    body.plant_feet(spread=spread, lift=0.025 * h * hop, pitch=-0.25 * hop)
    return body.clip("jumping_jacks")


def sit(
    height: float,
    seat_height: float,
    rng: np.random.Generator,
    duration: float = 8.0,
    pose: str = "rest",
) -> Clip:
    """Sitting down from standing, then a seated loop (``Clip.loop_start`` marks it).

    The anchor is the floor point under the seated pelvis, facing away from the seat's back;
    the person starts standing in front of the seat with their feet where they stay. The
    pelvis ends :data:`SEAT_CLEARANCE` × height above the seat (lower only on seats so high
    the feet could not reach the floor).

    Args:
        height: The person's height (m).
        seat_height: Height of the seat surface above the floor (0.15–1.2 m).
        rng: Source of the person's variations.
        duration: Seconds per seated loop (at least 2).
        pose: ``"rest"`` (hands on the thighs), ``"read"`` (holding something, head down)
            or ``"talk"`` (gesturing).
    """
    h = check_height(height)
    check_choice("sitting pose", pose, SIT_POSES)
    if not (math.isfinite(seat_height) and 0.15 <= seat_height <= 1.2):
        raise InvalidArgumentError(f"seat_height must be in 0.15..1.2 m, got {seat_height!r}")
    n_down = round(rng.uniform(1.6, 2.2) * FPS)
    down = n_down / FPS
    loop = loop_times(duration, 2.0)
    t = np.arange(n_down + len(loop)) / FPS
    body = PoseBuilder(h, len(t))
    offsets = body.offsets
    reach = 0.95 * jt.leg_reach(offsets)
    hip_below = offsets[JOINT["left_hip"], 2]  # negative: hips sit below the pelvis joint
    ankle_z = 0.039 * h
    # Where the feet go: ~0.2 h ahead of the hips, closer in if the seat is high.
    seat_hip = seat_height + (SEAT_CLEARANCE * h + hip_below)
    rise = min(seat_hip - ankle_z, reach)
    feet_y = min(0.2 * h, math.sqrt(max(reach**2 - rise**2, 0.0)))
    seated_z = ankle_z + rise - hip_below
    stand_y = feet_y - STANCE_Y * h
    s = minjerk(t / down)
    sz = minjerk((t / down - 0.1) / 0.9)
    lean = np.sin(np.pi * s) ** 1.5
    body.root[:, 1] = stand_y * (1 - s)
    body.root[:, 2] = body.root[:, 2] * (1 - sz) + seated_z * sz
    # Seated movements fade in while sitting down; they are periodic over the loop.
    sway, tl = s, t
    breath = wave(rng, tl, loop[-1], rng.uniform(0.22, 0.3), math.radians(1.0)) * sway
    look = wave(rng, tl, loop[-1], 0.1, math.radians(rng.uniform(4.0, 10.0))) * sway
    body.set_pelvis(jt.trunk(flex=0.35 * lean - 0.08 * s))
    head_flex = {"rest": 0.05, "read": 0.4, "talk": 0.05}[pose] * s
    nod = wave(rng, tl, loop[-1], 0.7, math.radians(3.0)) * sway * (pose == "talk")
    body.set_trunk(
        jt.trunk(flex=0.45 * lean + 0.05 * s - breath),
        jt.trunk(flex=0.1 * lean + head_flex + nod, twist=look),
    )
    for side in (jt.LEFT, jt.RIGHT):
        target = {"rest": THIGHS, "read": BOOK, "talk": GESTURE}[pose]
        delta = {
            k: (b - a) * s
            for k, a, b in zip(("flex", "elbow", "abduct", "across"), HANG, target, strict=True)
        }
        if pose == "talk":
            env = 0.5 + 0.5 * np.sin(2 * np.pi * tl / loop[-1] + rng.uniform(0, 2 * np.pi))
            delta["flex"] = delta["flex"] + 0.12 * env * wave(rng, tl, loop[-1], 1.0, 1.0) * sway
            delta["elbow"] = delta["elbow"] + 0.3 * env * wave(rng, tl, loop[-1], 1.2, 1.0) * sway
        body.set_arm(side, HANG, **delta)
    body.plant_feet(forward=feet_y / h)
    return body.clip(f"sit_{pose}", loop_start=n_down)


def walk_path(
    height: float,
    waypoints: np.ndarray,
    rng: np.random.Generator,
    speed: float = 1.0,
    closed: bool = True,
) -> Clip:
    """Walking along ``waypoints`` (anchor frame, metres), round and round or back and forth.

    Gentle corners are rounded and walked a little slower; sharp ones and the ends of an
    open path are turned on the spot. See :func:`.route.loop_route` for where the loop starts.

    Args:
        height: The person's height (m).
        waypoints: Ground points ``(K, 2)``, K ≥ 2.
        rng: Source of the person's gait style and turn directions.
        speed: Walking speed on straight stretches (m/s).
        closed: Whether the path returns from its last point to its first.
    """
    h = check_height(height)
    style = GaitStyle.sample(rng)
    route = loop_route(waypoints, speed, rng, closed=closed, fps=FPS)
    return walk(route, h, style, speed, name="walk")


def pace(
    height: float,
    a: np.ndarray,
    b: np.ndarray,
    rng: np.random.Generator,
    speed: float = 0.8,
    phone: bool = False,
) -> Clip:
    """Pacing back and forth between two ground points, turning on the spot at each end.

    Args:
        height: The person's height (m).
        a: Ground point ``(2,)`` where the loop starts (facing ``b``).
        b: The other end.
        rng: Source of the person's gait style and turns (1.1–1.5 s per 180° turn).
        speed: Walking speed between the turns (m/s).
        phone: Talk on a phone held to the right ear while pacing.
    """
    h = check_height(height)
    style = GaitStyle.sample(rng)
    pts = np.stack([np.asarray(a, float), np.asarray(b, float)])
    route = loop_route(pts, speed, rng, closed=False, turn_time=rng.uniform(1.1, 1.5), fps=FPS)
    return walk(route, h, style, speed, phone=phone, name="pace_phone" if phone else "pace")
