"""Procedural motion: joint signs, leg IK, gait (no sliding, no sinking), recipes, blending."""

from __future__ import annotations

import math

import numpy as np
import pytest

import havln_mj.humans.motion as motion
from havln_mj.errors import InvalidArgumentError
from havln_mj.humans import rotations as rot
from havln_mj.humans.motion import joints as jt
from havln_mj.humans.motion.gait import PHONE_ARM, GaitStyle, cycle_time, walk
from havln_mj.humans.motion.route import loop_route
from havln_mj.humans.skeleton import JOINT, forward_kinematics, rest_offsets

H = 1.75


def _fk(clip, height=H):
    return forward_kinematics(rest_offsets(height), clip.local, clip.root)


def _soles(clip, height=H):
    """Heel and ball points of both feet ``(T, 4, 3)``, and the lowest foot-joint height."""
    pos, quat = _fk(clip, height)
    pts = [
        jt.sole_points(height, pos[:, JOINT[f"{s}_ankle"]], quat[:, JOINT[f"{s}_ankle"]])
        for s in ("left", "right")
    ]
    toes = min(pos[:, JOINT["left_foot"], 2].min(), pos[:, JOINT["right_foot"], 2].min())
    return np.concatenate(pts, axis=1), toes


def _contact_slides(points: np.ndarray, touch: float = 0.003) -> list[float]:
    """For each run of frames a sole point touches the floor: how far it moved during it."""
    slides = []
    for c in range(points.shape[1]):
        on = points[:, c, 2] < touch
        start = None
        for i, flag in enumerate([*on, False]):
            if flag and start is None:
                start = i
            elif not flag and start is not None:
                run = points[start:i, c, :2]
                slides.append(float(np.linalg.norm(run - run[0], axis=1).max()))
                start = None
    return slides


def _moved(local: np.ndarray, parent_joint: str, joint: str, q: np.ndarray) -> np.ndarray:
    base = rot.identity((24,))
    posed = base.copy()
    posed[JOINT[parent_joint]] = q
    root = np.array([0.0, 0.0, 1.0])
    p0 = forward_kinematics(rest_offsets(H), base, root)[0][JOINT[joint]]
    p1 = forward_kinematics(rest_offsets(H), posed, root)[0][JOINT[joint]]
    return p1 - p0


def test_anatomical_signs_in_our_body_frame():
    # +x is the person's right, +y forward, +z up.
    assert _moved(None, "left_hip", "left_knee", jt.rx(0.5))[1] > 0.1  # hip flexion: knee fwd
    assert _moved(None, "right_knee", "right_ankle", jt.rx(-0.5))[1] < -0.1  # knee flexion
    assert _moved(None, "left_ankle", "left_foot", jt.rx(0.3))[2] > 0.02  # dorsiflexion: toes up
    assert _moved(None, "spine1", "head", jt.trunk(flex=0.3))[1] > 0.1  # bending forward
    assert _moved(None, "spine1", "head", jt.trunk(bend=0.3))[0] > 0.1  # bending right
    assert _moved(None, "spine1", "right_shoulder", jt.trunk(twist=0.3))[1] > 0.03  # turn left
    for side, name in ((jt.RIGHT, "right"), (jt.LEFT, "left")):
        local = rot.identity((24,))
        jt.set_arm(local, side, 0.0, 0.0)
        pos = forward_kinematics(rest_offsets(H), local, np.zeros(3))[0]
        arm = pos[JOINT[f"{name}_wrist"]] - pos[JOINT[f"{name}_shoulder"]]
        assert arm[2] < -0.45 and side * arm[0] > 0  # hangs down, on its own side
        jt.set_arm(local, side, 0.6, 1.4)
        pos = forward_kinematics(rest_offsets(H), local, np.zeros(3))[0]
        assert pos[JOINT[f"{name}_elbow"], 1] > 0.1  # shoulder flexion: elbow forward
        assert pos[JOINT[f"{name}_wrist"], 1] > pos[JOINT[f"{name}_elbow"], 1] + 0.15  # elbow


def test_leg_ik_puts_the_ankle_on_target():
    rng = np.random.default_rng(0)
    off = rest_offsets(H)
    n = 200
    root = np.column_stack([rng.uniform(-1, 1, (n, 2)), rng.uniform(0.75, 1.0, n)])
    pelvis = rot.normalize(rot.identity((n,)) + 0.1 * rng.normal(size=(n, 4)))
    hip = root + rot.rotate(pelvis, off[JOINT["left_hip"]])
    direction = np.column_stack([rng.uniform(-0.4, 0.4, (n, 2)), -np.ones(n)])
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    target = hip + direction * rng.uniform(0.5, 0.98, (n, 1)) * jt.leg_reach(off)
    foot = jt.foot_orientation(rng.uniform(-1, 1, n), rng.uniform(-0.5, 0.5, n))
    local = np.tile(rot.identity(), (n, 24, 1))
    local[:, 0] = pelvis
    hq, kq, aq = jt.leg_ik(off, jt.LEFT, hip, pelvis, target, foot)
    local[:, JOINT["left_hip"]], local[:, JOINT["left_knee"]] = hq, kq
    local[:, JOINT["left_ankle"]] = aq
    pos, quat = forward_kinematics(off, local, root)
    np.testing.assert_allclose(pos[:, JOINT["left_ankle"]], target, atol=1e-9)
    np.testing.assert_allclose(
        np.abs(np.sum(quat[:, JOINT["left_ankle"]] * foot, -1)), 1, atol=1e-9
    )
    # The knee bends forward (flexion is negative about x) and points where the foot does.
    assert (rot.to_axis_angle(kq)[:, 0] <= 0.06).all()


@pytest.mark.parametrize("speed", [0.6, 1.0, 1.4])
def test_gait_on_a_straight_path(speed):
    rng = np.random.default_rng(7)
    clip = motion.walk_path(H, np.array([[0.0, 0.0], [0.0, 10.0]]), rng, speed=speed)
    soles, toes = _soles(clip)
    slides = _contact_slides(soles)
    assert len(slides) > 10
    assert max(slides) < 0.02  # the planted foot does not slide
    assert soles[..., 2].min() > -0.01 and toes > -0.01  # nothing sinks into the floor
    # Root speed over whole cycles in the middle of the first leg.
    t = np.arange(clip.frames) / clip.fps
    period = cycle_time(speed, H)
    y = clip.root[:, 1]
    start = int(np.argmax(y > 3.0))
    end = start + round(2 * period * clip.fps)
    assert y[end] < 7.0  # still on the straight, away from the turn
    measured = (y[end] - y[start]) / (t[end] - t[start])
    assert measured == pytest.approx(speed, rel=0.05)
    # Cadence and stride as the facts say: 90-130 steps/min, stride = speed x cycle.
    heel, lowest = soles[:, 0], soles[:, :2, 2].min(axis=1)  # left foot
    planted = np.flatnonzero((lowest < 0.003) & (heel[:, 1] > 2.0) & (heel[:, 1] < 8.0))
    runs = np.split(planted, np.flatnonzero(np.diff(planted) > 1) + 1)[1:]  # whole stances
    strikes = [heel[r[0], 1] for r in runs][:3]
    frames = [r[0] for r in runs][:3]
    assert len(strikes) == 3
    stride = np.diff(strikes)
    cycle = np.diff(frames) / clip.fps
    assert 90 <= 120 / cycle.mean() <= 130
    np.testing.assert_allclose(stride, speed * cycle, rtol=0.05)
    if speed >= 1.2:  # free walking: a step (half a stride) of 0.6-0.75 m
        assert 0.55 <= stride.mean() / 2 <= 0.8


def test_gait_joint_ranges_look_like_walking():
    rng = np.random.default_rng(3)
    clip = motion.walk_path(H, np.array([[0.0, 0.0], [0.0, 12.0]]), rng, speed=1.24)
    pos, _ = _fk(clip)
    steady = (clip.root[:, 1] > 3) & (clip.root[:, 1] < 9) & (np.arange(clip.frames) < 300)
    thigh = pos[steady, JOINT["left_knee"]] - pos[steady, JOINT["left_hip"]]
    shank = pos[steady, JOINT["left_ankle"]] - pos[steady, JOINT["left_knee"]]
    hip_flex = np.degrees(np.arctan2(thigh[:, 1], -thigh[:, 2]))
    cos = np.sum(thigh * shank, 1) / np.linalg.norm(thigh, axis=1) / np.linalg.norm(shank, axis=1)
    knee = np.degrees(np.arccos(np.clip(cos, -1, 1)))
    assert 15 < hip_flex.max() < 42 and -30 < hip_flex.min() < -8
    assert 50 < knee.max() < 80  # swing-phase knee flexion (facts: peak ~62 deg)
    drop = 0.575 * H - clip.root[steady, 2]
    assert drop.min() > -0.01 and drop.max() < 0.08  # the pelvis bobs a few cm


@pytest.mark.parametrize(
    ("waypoints", "closed"),
    [
        ([[0, 0], [4, 0], [4, 3], [0, 3]], True),  # rounded 90-degree corners
        ([[0, 0], [2, 0], [2, 2], [0, 0.5], [1, -1]], False),  # sharp turns on the spot
        ([[0, 0], [1.5, 0], [0, 0.3]], True),
    ],
)
def test_corners_and_turns_keep_feet_planted_and_out_of_the_floor(waypoints, closed):
    clip = motion.walk_path(
        H, np.array(waypoints, float), np.random.default_rng(2), speed=1.2, closed=closed
    )
    soles, toes = _soles(clip)
    assert soles[..., 2].min() > -0.01 and toes > -0.01
    assert max(_contact_slides(soles)) < 0.02


def test_route_turns_on_the_spot_for_one_to_one_and_a_half_seconds():
    route = loop_route(
        np.array([[0.0, 0.0], [0.0, 3.0]]),
        0.8,
        np.random.default_rng(0),
        closed=False,
        turn_time=1.3,
    )
    still = np.flatnonzero(route.speed < 1e-9)
    runs = np.split(still, np.flatnonzero(np.diff(still) > 1) + 1)
    spans = [route.times[r[-1]] - route.times[r[0]] for r in runs if len(r) > 1]
    assert len(spans) == 2 and all(1.0 <= s <= 1.5 for s in spans)
    for r in runs:
        if len(r) > 1:  # a half turn, standing on the spot
            assert abs(abs(route.yaw[r[-1]] - route.yaw[r[0]]) - math.pi) < 1e-9
            assert np.ptp(route.xy[r], axis=0).max() < 1e-9
    assert abs(abs(route.winding) - 2 * math.pi) < 1e-9 or abs(route.winding) < 1e-9
    assert route.speed.max() == pytest.approx(0.8, rel=1e-3)


@pytest.mark.parametrize("seat", [0.3, 0.45, 0.6])
def test_sit_ends_on_the_seat_with_feet_on_the_floor(seat):
    h = 1.7
    clip = motion.sit(h, seat, np.random.default_rng(1), pose="rest")
    assert 0 < clip.loop_start < clip.frames - 1
    seated = clip.root[clip.loop_start :, 2]
    assert np.abs(seated - (seat + motion.SEAT_CLEARANCE * h)).max() < 0.03
    pos, _ = _fk(clip, h)
    hips = pos[clip.loop_start :, [JOINT["left_hip"], JOINT["right_hip"]], 2]
    assert hips.min() > seat  # sitting on, not in, the seat
    soles, _ = _soles(clip, h)
    assert np.abs(soles[..., 2]).max() < 0.01  # feet flat on the floor throughout
    assert np.abs(soles[:, :, :2] - soles[0, :, :2]).max() < 0.005  # and not sliding
    assert clip.root[0, 2] > 0.5 * h  # starts standing


def test_phone_pacing_holds_the_hand_at_the_ear():
    clip = motion.pace(H, (0, 0), (0, 3), np.random.default_rng(4), phone=True)
    pos, _ = _fk(clip)
    head = pos[:, JOINT["head"]]
    hand = pos[:, JOINT["right_hand"]]
    right = rot.rotate(clip.local[:, 0], np.array([1.0, 0.0, 0.0]))
    ear = head + 0.045 * H * right
    assert np.linalg.norm(hand - ear, axis=1).max() < 0.12
    assert PHONE_ARM[1] > math.radians(130)  # elbow 130-145 deg flexed (facts)


RECIPES = {
    "idle": lambda r: motion.idle(H, r),
    "talk": lambda r: motion.talk(H, r),
    "talk_phone": lambda r: motion.talk(H, r, phone=True),
    "reach_up": lambda r: motion.reach(H, r, "up"),
    "reach_down": lambda r: motion.reach(H, r, "down"),
    "reach_forward": lambda r: motion.reach(H, r, "forward"),
    "squat": lambda r: motion.exercise(H, r, "squat"),
    "stretch": lambda r: motion.exercise(H, r, "stretch"),
    "jumping_jacks": lambda r: motion.exercise(H, r, "jumping_jacks"),
    "sit_read": lambda r: motion.sit(H, 0.45, r, pose="read"),
    "sit_talk": lambda r: motion.sit(H, 0.5, r, pose="talk"),
    "pace": lambda r: motion.pace(H, (0, 0), (2, 2), r),
    "walk_open": lambda r: motion.walk_path(H, np.array([[0, 0], [3, 0], [3, 3]]), r, closed=False),
    "walk_loop": lambda r: motion.walk_path(H, np.array([[0, 0], [3, 0], [3, 3]]), r),
}


def _same_rotation(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(1 - np.abs(np.sum(a * b, -1))).max())


@pytest.mark.parametrize("name", list(RECIPES))
def test_recipe_is_valid_seamless_and_deterministic(name):
    clip = RECIPES[name](np.random.default_rng(11))
    assert clip.fps == motion.FPS and clip.frames > 30
    assert np.isfinite(clip.local).all() and np.isfinite(clip.root).all()
    np.testing.assert_allclose(np.linalg.norm(clip.local, axis=-1), 1.0, atol=1e-9)
    # Seamless loop: the last frame is the loop start's pose, and the step across the seam
    # is no bigger than the motion's ordinary frame-to-frame steps.
    assert _same_rotation(clip.local[-1], clip.local[clip.loop_start]) < 1e-9
    np.testing.assert_allclose(clip.root[-1], clip.root[clip.loop_start], atol=1e-9)
    steps = np.abs(1 - np.abs(np.sum(clip.local[1:] * clip.local[:-1], -1))).max()
    assert steps < 0.05  # no jumps anywhere
    soles, toes = _soles(clip)
    assert soles[..., 2].min() > -0.01 and toes > -0.01
    again = RECIPES[name](np.random.default_rng(11))
    np.testing.assert_array_equal(clip.local, again.local)
    np.testing.assert_array_equal(clip.root, again.root)
    other = RECIPES[name](np.random.default_rng(12))
    assert other.local.shape != clip.local.shape or not np.allclose(other.local, clip.local)


@pytest.mark.parametrize(
    "name", ["idle", "talk", "reach_down", "reach_forward", "squat", "stretch", "sit_read"]
)
def test_standing_and_sitting_recipes_keep_the_feet_planted(name):
    soles, _ = _soles(RECIPES[name](np.random.default_rng(5)))
    assert np.abs(soles[..., :2] - soles[0, :, :2]).max() < 1e-6
    assert np.abs(soles[..., 2]).max() < 1e-6


def test_blend_is_smooth_and_loops_the_second_clip():
    rng = np.random.default_rng(0)
    a, b = motion.idle(H, rng, duration=4.0), motion.sit(H, 0.45, rng)
    out = motion.blend(a, b, 0.5)
    k = round(0.5 * a.fps)
    assert out.frames == a.frames + b.frames - k
    assert out.loop_start == a.frames - k + b.loop_start
    np.testing.assert_array_equal(out.local[: a.frames - k], a.local[: a.frames - k])
    np.testing.assert_allclose(out.local[-1], b.local[-1])
    cos = np.abs(np.sum(out.local[1:] * out.local[:-1], -1))
    assert (1 - cos).max() < 2e-3  # no pops at the crossfade
    # A clip whose loop starts before the crossfade ends is unrolled to stay seamless.
    c = motion.talk(H, rng, duration=4.0)
    seq = motion.sequence([a, c, a], 1.0)
    assert _same_rotation(seq.local[-1], seq.local[seq.loop_start]) < 1e-9
    assert seq.frames > a.frames + c.frames


def test_bad_arguments_name_the_value():
    rng = np.random.default_rng(0)
    with pytest.raises(InvalidArgumentError, match="height"):
        motion.idle(2.5, rng)
    with pytest.raises(InvalidArgumentError, match=r"'sideways'.*up, down, forward"):
        motion.reach(H, rng, kind="sideways")
    with pytest.raises(InvalidArgumentError, match="squat"):
        motion.exercise(H, rng, kind="running")
    with pytest.raises(InvalidArgumentError, match="speed"):
        motion.walk_path(H, np.array([[0, 0], [1, 0]]), rng, speed=float("nan"))
    with pytest.raises(InvalidArgumentError, match="two points"):
        motion.walk_path(H, np.array([[0, 0], [0.01, 0]]), rng)
    with pytest.raises(InvalidArgumentError, match="seat_height"):
        motion.sit(H, 2.0, rng)
    with pytest.raises(InvalidArgumentError, match="blend seconds"):
        motion.blend(motion.idle(H, rng), motion.idle(H, rng), -1.0)


def test_gait_style_varies_people_but_not_seeds():
    a = GaitStyle.sample(np.random.default_rng(1))
    assert a == GaitStyle.sample(np.random.default_rng(1))
    assert a != GaitStyle.sample(np.random.default_rng(2))
    route = loop_route(np.array([[0, 0], [0, 4.0]]), 1.0, np.random.default_rng(0), fps=30)
    assert not np.allclose(walk(route, H, a, 1.0).local, walk(route, H, GaitStyle(), 1.0).local)
