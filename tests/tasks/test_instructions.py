"""The instruction generator: route facts (turns, rooms, stairs, landmarks, people) and wording."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from havln_mj.errors import InvalidArgumentError
from havln_mj.frames import heading_to
from havln_mj.humans.crowd import Crowd
from havln_mj.scene.connectivity import Connectivity
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.scan import Scan, load_scan
from havln_mj.tasks.instructions import (
    TURNS,
    describe_route,
    generate_instructions,
    room_name,
    tokenize,
    word_count,
)
from havln_mj.tasks.procedural import sample_paths, scene_crowd

SCAN = "proc-0"


@pytest.fixture(scope="module")
def scan() -> Scan:
    return load_scan(SCAN)


@pytest.fixture(scope="module")
def crowd(scan) -> Crowd:
    return scene_crowd(scan, 0)


@pytest.fixture(scope="module")
def paths(scan) -> list[tuple[str, ...]]:
    return sample_paths(scan.graph, 40, np.random.default_rng(0))


def _stair_scan() -> Scan:
    """A made-up line a-b-c-d, 2 m apart; c and d are a storey (3 m) up: b→c is stairs."""
    ids = ["a", "b", "c", "d"]
    poses = np.tile(np.eye(4), (4, 1, 1))
    for i, z in enumerate([0.0, 0.0, 3.0, 3.0]):
        poses[i, 1, 3] = 2.0 * i  # along +y: heading 0
        poses[i, 2, 3] = z + 1.5
    unob = np.zeros((4, 4), bool)
    for i in range(3):
        unob[i, i + 1] = unob[i + 1, i] = True
    conn = Connectivity(ids, poses, [True] * 4, ~np.eye(4, dtype=bool), unob, [1.5] * 4)
    graph = NavGraph(conn)
    return Scan("toy", "folder", Path("."), Path("mesh.glb"), graph, None, None)


def test_route_facts_follow_the_geometry(scan, crowd, paths):
    graph = scan.graph
    for path in paths:
        start = heading_to(graph.position(path[0]), graph.position(path[1]))
        route = describe_route(scan, path, start, crowd)
        assert route.steps[0].turn == "straight"  # facing the first edge already
        assert len(route.steps) == len(path) - 1
        assert math.isclose(route.distance, graph.path_length(path))
        facing = start
        for step, a, b in zip(route.steps, path, path[1:], strict=False):
            h = heading_to(graph.position(a), graph.position(b))
            delta = math.degrees(abs((h - facing + math.pi) % (2 * math.pi) - math.pi))
            assert step.turn in TURNS
            assert (step.turn == "straight") == (delta < 25.0)
            assert (step.turn == "around") == (delta >= 145.0)
            assert step.room_to == room_name(scan.regions.region_of(b).label)
            assert step.climb == 0  # procedural houses have one storey
            facing = h
        assert route.goal_room == room_name(scan.regions.region_of(path[-1]).label)
        turned = describe_route(scan, path, start + math.pi, crowd)
        assert turned.steps[0].turn == "around"


def test_stairs_are_described():
    toy = _stair_scan()
    route = describe_route(toy, ["a", "b", "c", "d"], 0.0, Crowd([]))
    assert [s.climb for s in route.steps] == [0, 1, 0]
    assert route.goal_room is None and route.people == ()
    texts, about = generate_instructions(route, np.random.default_rng(0))
    assert about == ("", "", "")
    for text in texts:
        assert "stairs" in text or "steps" in text or "staircase" in text
    down = describe_route(toy, ["d", "c", "b", "a"], math.pi, Crowd([]))
    assert [s.climb for s in down.steps] == [0, -1, 0]


def test_three_varied_instructions_mention_the_route_and_people(scan, crowd, paths):
    rng = np.random.default_rng(3)
    seen_people = 0
    for path in paths:
        route = describe_route(scan, path, float(rng.uniform(0, 2 * math.pi)), crowd)
        texts, about = generate_instructions(route, rng)
        assert len(texts) == 3 and len(set(texts)) == 3 and len(about) == 3
        rooms = {s.room_to.lower() for s in route.steps} | {route.start_room.lower()}
        for text, people in zip(texts, about, strict=True):
            low = text.lower()
            assert route.goal_room.lower() in low
            assert any(r in low for r in rooms) or any(
                w in low for w in ("left", "right", "around", "straight")
            )
            assert text.endswith(".") and text[0].isupper()
            for p in route.people:  # each person, doing what, in the instruction and its summary
                assert p.verb in text and p.verb in people
            assert (
                people == "" or people in text or all(s.strip() in text for s in people.split(". "))
            )
        seen_people += len(route.people)
    assert seen_people > 0  # proc-0 with seed 0 has people near some paths


def test_people_keep_the_rel_pos_rule(scan, crowd, paths):
    from havln_mj.tasks.annotate import rel_pos

    for path in paths:
        route = describe_route(scan, path, 0.0, crowd)
        on_crowd = {p.viewpoint for p in crowd.people}
        for p in route.people:
            assert p.human.viewpoint in on_crowd
            assert p.human.rel_pos == rel_pos(p.human.viewpoint, path, scan.graph)
            assert ":" in p.human.description


def test_generation_is_deterministic(scan, crowd, paths):
    route = describe_route(scan, paths[0], 1.0, crowd)
    a = generate_instructions(route, np.random.default_rng(5))
    b = generate_instructions(route, np.random.default_rng(5))
    assert a == b
    assert generate_instructions(route, np.random.default_rng(6)) != a


def test_lengths_near_ha_r2r(scan, crowd, paths):
    rng = np.random.default_rng(0)
    words = []
    for path in paths:
        route = describe_route(scan, path, float(rng.uniform(0, 2 * math.pi)), crowd)
        words += [word_count(t) for t in generate_instructions(route, rng)[0]]
    assert 50 <= np.mean(words) <= 72
    assert min(words) >= 25 and max(words) <= 140


def test_bad_input():
    toy = _stair_scan()
    with pytest.raises(InvalidArgumentError, match="at least 2 viewpoints"):
        describe_route(toy, ["a"], 0.0, Crowd([]))
    with pytest.raises(InvalidArgumentError):
        describe_route(toy, ["a", "c"], 0.0, Crowd([]))  # not an edge
    route = describe_route(toy, ["a", "b"], 0.0, Crowd([]))
    with pytest.raises(InvalidArgumentError, match="at least 1"):
        generate_instructions(route, np.random.default_rng(0), n=0)


def test_tokenize():
    assert tokenize("Turn left, then you'll see the TV stand.") == [
        "turn",
        "left",
        ",",
        "then",
        "you'll",
        "see",
        "the",
        "tv",
        "stand",
        ".",
    ]
    assert tokenize("about 12 metres") == ["about", "12", "metres"]
