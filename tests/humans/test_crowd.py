"""People as a function of time: kinematics, placement in the world, bodies in MuJoCo."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from havln_mj import groups
from havln_mj.errors import InvalidArgumentError
from havln_mj.humans import rotations as rot
from havln_mj.humans.body import BodyShape, random_body
from havln_mj.humans.clip import Clip
from havln_mj.humans.crowd import Crowd, Person
from havln_mj.humans.mujoco_people import PeopleWriter, add_people, body_name
from havln_mj.humans.segments import segment_orientations
from havln_mj.humans.skeleton import (
    JOINT,
    NUM_JOINTS,
    PARENTS,
    forward_kinematics,
    rest_offsets,
    rest_positions,
)


def _walk_clip(speed: float = 1.0, seconds: float = 4.0, fps: float = 30.0) -> Clip:
    """The rest pose gliding along the anchor's +y (a stand-in motion with known root)."""
    t = np.arange(round(seconds * fps) + 1) / fps
    root = np.zeros((len(t), 3))
    root[:, 1] = speed * t
    root[:, 2] = rest_positions(1.7)[0, 2]
    return Clip(root, fps, local=rot.identity((len(t), NUM_JOINTS)), name="glide")


def _random_pose(rng: np.random.Generator, n: int = 1) -> np.ndarray:
    return rot.from_axis_angle(rng.normal(scale=0.4, size=(n, NUM_JOINTS, 3)))


def test_rest_pose_proportions_follow_height():
    tall, short = rest_positions(1.9), rest_positions(1.5)
    np.testing.assert_allclose(tall / 1.9, short / 1.5)
    head_top = rest_positions(1.7)[JOINT["head"], 2] + 0.068 * 1.7
    assert 1.6 < head_top < 1.8
    # Right side is +x, the person faces +y.
    assert rest_positions(1.7)[JOINT["right_hand"], 0] > 0.7
    assert rest_positions(1.7)[JOINT["left_foot"], 1] > rest_positions(1.7)[JOINT["left_ankle"], 1]


def test_fk_of_rotated_elbow_moves_only_the_forearm():
    off = rest_offsets(1.7)
    local = rot.identity((NUM_JOINTS,))
    local[JOINT["right_elbow"]] = rot.from_axis((0, 0, 1), math.pi / 2)  # fold forward
    pos, quat = forward_kinematics(off, local, off[0])
    rest = rest_positions(1.7)
    moved = np.flatnonzero(np.linalg.norm(pos - rest, axis=1) > 1e-9)
    assert set(moved) == {JOINT["right_wrist"], JOINT["right_hand"]}
    forearm = pos[JOINT["right_wrist"]] - pos[JOINT["right_elbow"]]
    assert forearm[1] == pytest.approx(np.linalg.norm(off[JOINT["right_wrist"]]))  # now +y
    np.testing.assert_allclose(np.linalg.norm(quat, axis=-1), 1.0)


def test_segment_orientations_point_each_piece_along_its_bone():
    rng = np.random.default_rng(0)
    off = rest_offsets(1.7)
    pos, _ = forward_kinematics(off, _random_pose(rng, 5), rng.normal(size=(5, 3)))
    quats = segment_orientations(pos, off)
    for j in range(1, NUM_JOINTS):
        p = PARENTS[j]
        if p in (JOINT["pelvis"], JOINT["spine3"]) and j != {0: 3, 9: 12}[p]:
            continue  # side branches of the trunk pieces
        along = rot.rotate(quats[:, p], off[j])
        np.testing.assert_allclose(along, pos[:, j] - pos[:, p], atol=1e-9)


def test_positions_states_and_pose_agree():
    clip = _walk_clip(speed=1.2)
    person = Person(BodyShape(1.7), clip, np.array([1.0, 2.0, 0.5]), math.pi / 2, "walk")
    crowd = Crowd([person])
    # Heading π/2 faces +x: the anchor's +y becomes the world's +x.
    p = crowd.positions(np.array([0.0, 1.0]))
    np.testing.assert_allclose(p[1, 0] - p[0, 0], [1.2, 0.0, 0.0], atol=1e-9)
    pos, _ = crowd.pose(1.0)
    np.testing.assert_allclose(pos[0, JOINT["pelvis"]], p[1, 0], atol=1e-9)
    assert pos[0, JOINT["head"], 2] > pos[0, JOINT["pelvis"], 2] > 0.5
    (state,) = crowd.states(1.0)
    assert state.heading == pytest.approx(math.pi / 2)
    np.testing.assert_allclose(state.velocity, [1.2, 0.0, 0.0], atol=1e-6)
    assert state.activity == "walk"


def test_clips_loop_from_loop_start():
    clip = _walk_clip(seconds=2.0)
    looped = Clip(clip.root, clip.fps, local=clip.local, loop_start=30)
    np.testing.assert_allclose(looped.root_at(2.5), looped.root_at(1.5))
    np.testing.assert_allclose(clip.root_at(2.5), clip.root_at(0.5))
    with pytest.raises(InvalidArgumentError, match="loop_start"):
        Clip(clip.root, 30.0, local=clip.local, loop_start=999)


def test_segment_mode_people_are_posed_from_positions():
    rng = np.random.default_rng(1)
    off = rest_offsets(1.7)
    joints, _ = forward_kinematics(off, _random_pose(rng, 3), np.array([[0, 0, 1.0]] * 3))
    clip = Clip(joints[:, 0], 10.0, positions=joints)
    crowd = Crowd([Person(BodyShape(1.7), clip, np.zeros(3), 0.0, "mdm")])
    pos, quat = crowd.pose(0.1)
    np.testing.assert_allclose(pos[0], joints[1], atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(quat[0], axis=-1), 1.0)


def test_bodies_are_deterministic_and_varied():
    a = [random_body(np.random.default_rng(3)) for _ in range(2)]
    assert a[0] == a[1]
    many = [random_body(np.random.default_rng(s)) for s in range(20)]
    assert len({b.top for b in many}) > 3 and len({round(b.height, 3) for b in many}) > 15
    assert all(1.5 <= b.height <= 1.95 for b in many)
    with pytest.raises(InvalidArgumentError, match="height"):
        BodyShape(2.3)


def test_mujoco_people_make_no_contacts_and_follow_their_poses():
    rng = np.random.default_rng(2)
    shapes = [random_body(rng) for _ in range(2)]
    spec = mujoco.MjSpec()
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=(5, 5, 0.1))
    robot = spec.worldbody.add_body(name="robot", pos=(0, 0, 0.3))
    robot.add_freejoint()
    robot.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=(0.3, 0.15, 0.15), mass=12.0)
    add_people(spec, shapes)
    model = spec.compile()
    human = model.geom_group == groups.HUMANS
    assert human.sum() >= 2 * 20
    assert not model.geom_contype[human].any() and not model.geom_conaffinity[human].any()
    data = mujoco.MjData(model)
    crowd = Crowd(
        [
            Person(shapes[k], _walk_clip(), np.array([0.3 * k, 0.0, 0.0]), 0.0, "glide")
            for k in range(2)
        ]
    )  # both people stand right on the robot
    writer = PeopleWriter(model, 2)
    for step in range(50):
        writer.write(data, *crowd.pose(step * model.opt.timestep))
        mujoco.mj_step(model, data)
    assert all(human[c.geom1] == human[c.geom2] is False for c in data.contact[: data.ncon])
    pos, _ = crowd.pose(0.0)
    writer.write(data, pos, crowd.pose(0.0)[1])
    mujoco.mj_kinematics(model, data)
    np.testing.assert_allclose(data.xpos[model.body(body_name(1, JOINT["head"])).id], pos[1, 15])
