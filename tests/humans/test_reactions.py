import math

import numpy as np
import pytest

from havln_mj.humans import rotations as rot
from havln_mj.humans.body import BodyShape
from havln_mj.humans.catalog import load_catalog, make_clip
from havln_mj.humans.crowd import Crowd, Person
from havln_mj.humans.reactions import Reactions, ReactiveCrowd


def _corridor_crowd(seed: int = 0) -> Crowd:
    """A walker pacing 6 m along +y from the origin, and a person standing aside."""
    rng = np.random.default_rng(seed)
    catalog = load_catalog()
    pace = catalog.get("hallway/hall-call")
    idle = catalog.get("hallway/mirror-check")
    shape = BodyShape(1.7)
    walker = make_clip(pace, 1.7, rng, path=np.array([[0.0, 0.0], [0.0, 6.0]]))
    still = make_clip(idle, 1.7, rng)
    return Crowd(
        [
            Person(shape, walker, np.zeros(3), 0.0, pace.id, start=0.0),
            Person(shape, still, np.array([2.5, 3.0, 0.0]), -math.pi / 2, idle.id),
        ]
    )


def test_walker_yields_to_a_robot_standing_in_the_corridor():
    base = _corridor_crowd()
    crowd = ReactiveCrowd(base, Reactions(comfort=1.5))
    robot = np.array([0.0, 3.0])
    crowd.observe_agent(np.array([0.0]), robot[None])
    times = np.arange(0.0, 60.0, 0.05)
    walker = crowd.positions(times, np.array([0]))[:, 0, :2]
    d = np.linalg.norm(walker - robot, axis=1)
    assert d.min() >= 1.5 - 1e-9
    # Without reactions the same walker walks right through the robot.
    free = base.positions(times, np.array([0]))[:, 0, :2]
    assert np.linalg.norm(free - robot, axis=1).min() < 0.5
    # It stays on its own track: every yielding position is one the free walker passes.
    gaps = np.linalg.norm(walker[:, None] - free[None, ::2], axis=2).min(axis=1)
    assert gaps.max() < 0.05


def test_walker_resumes_once_the_robot_leaves():
    crowd = ReactiveCrowd(_corridor_crowd())
    crowd.observe_agent(np.array([0.0, 20.0, 20.5]), np.array([[0.0, 3.0], [0.0, 3.0], [9.0, 9.0]]))
    clocks = crowd.clocks(np.array([19.0, 40.0]))[:, 0]
    assert clocks[0] < 19.0  # held back while the robot stood there
    assert clocks[1] - clocks[0] > 19.0  # running again once the robot left at 20.5 s


def test_no_track_or_reactions_off_is_the_plain_crowd():
    base = _corridor_crowd()
    times = np.linspace(0, 30, 61)
    plain = base.positions(times)
    assert np.array_equal(ReactiveCrowd(base).positions(times), plain)
    off = ReactiveCrowd(base, Reactions(enabled=False))
    off.observe_agent(np.array([0.0]), np.array([[0.0, 3.0]]))
    assert np.array_equal(off.positions(times), plain)
    np.testing.assert_array_equal(off.pose(3.0)[0], base.pose(3.0)[0])


def test_same_track_same_people_and_order_is_checked():
    a, b = ReactiveCrowd(_corridor_crowd()), ReactiveCrowd(_corridor_crowd())
    for crowd in (a, b):
        crowd.observe_agent(np.array([0.0, 5.0]), np.array([[0.0, 3.0], [0.5, 3.0]]))
    t = np.linspace(0, 25, 51)
    np.testing.assert_array_equal(a.positions(t), b.positions(t))
    np.testing.assert_array_equal(a.pose(7.0)[1], b.pose(7.0)[1])
    with pytest.raises(Exception, match="time order"):
        a.observe_agent(np.array([1.0]), np.array([[0.0, 0.0]]))


def test_a_person_glances_at_a_near_agent():
    base = _corridor_crowd()
    crowd = ReactiveCrowd(base, Reactions(glance=3.5))
    # The standing person at (2.5, 3) faces −x; the agent comes close in front, to their right.
    crowd.observe_agent(np.array([0.0]), np.array([[1.2, 1.8]]))
    _, q_base = base.pose(2.0)
    pos, q = crowd.pose(2.0)
    head = 15
    before = rot.rotate(q_base[1, head], np.array([0.0, 1.0, 0.0]))[:2]
    after = rot.rotate(q[1, head], np.array([0.0, 1.0, 0.0]))[:2]
    to_agent = np.array([1.2, 1.8]) - pos[1, head, :2]
    cos = lambda u, v: u @ v / np.linalg.norm(u) / np.linalg.norm(v)  # noqa: E731
    assert cos(after, to_agent) > cos(before, to_agent) + 0.1


def test_same_seed_same_crowd_motions_and_groups():
    from havln_mj.humans.population import populate
    from havln_mj.scene.scan import load_scan

    scan = load_scan("proc-0")
    a = populate(scan, np.random.default_rng(5), together=1.0)
    b = populate(scan, np.random.default_rng(5), together=1.0)
    assert [p.shape.look.rig.body.id for p in a.people] == [
        p.shape.look.rig.body.id for p in b.people
    ]
    assert [p.shape.look.outfit for p in a.people] == [p.shape.look.outfit for p in b.people]
    t = np.linspace(0, 20, 41)
    np.testing.assert_array_equal(a.positions(t), b.positions(t))
    np.testing.assert_array_equal(a.pose(3.3)[1], b.pose(3.3)[1])
    alone = populate(scan, np.random.default_rng(5))
    assert len(a) > len(alone)  # people joined by companions
    # Looks come from their own stream: the same placements and motions as without groups'
    # extra bodies, up to the first group.
    assert a.people[0].anchor.tolist() == alone.people[0].anchor.tolist()
