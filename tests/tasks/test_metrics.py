"""Metrics: every measure on hand-made graphs and trajectories, plus one real R2R episode."""

from __future__ import annotations

import json
import math
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from havln_mj.errors import (
    InvalidArgumentError,
    MalformedDataError,
    UnknownScanError,
    UnknownViewpointError,
)
from havln_mj.scene.connectivity import parse_connectivity
from havln_mj.scene.navgraph import NavGraph
from havln_mj.tasks.metrics import (
    EpisodeContext,
    EvalEpisode,
    Evaluator,
    Measure,
    MetricConfig,
    Person,
    Step,
    crux_points,
    dtw,
    episodes_from_submission,
    evaluate,
    ndtw,
    parse_step,
    parse_trajectory,
    unavoidable_people,
)

# The "line" scan, positions in metres (z = 0):
#
#                 q (2,2)
#                 |
#   a(0,0) - b(1,0) - c(2,0) - d(3,0) - e(4,0) ---- f(7,0)        z(10,10) isolated
#
# Geodesics used below: b->e 3, c->e 2, f->e 3, q->c 2, q->b 3, q->d 3, q->e 4.
_LINE = {
    "a": (0.0, 0.0),
    "b": (1.0, 0.0),
    "c": (2.0, 0.0),
    "d": (3.0, 0.0),
    "e": (4.0, 0.0),
    "f": (7.0, 0.0),
    "q": (2.0, 2.0),
    "z": (10.0, 10.0),
}
_LINE_EDGES = [("a", "b"), ("b", "c"), ("c", "d"), ("d", "e"), ("e", "f"), ("c", "q")]
REF = ["a", "b", "c", "d", "e"]  # reference path: start a, goal e, shortest length 4


def _graph(points: dict[str, tuple[float, float]], edges: list[tuple[str, str]]) -> NavGraph:
    """A scan whose undirected edges are ``edges`` and positions ``points`` (z = 0)."""
    ids = list(points)
    pairs = set(edges) | {(b, a) for a, b in edges}
    data: list[dict[str, Any]] = [
        {
            "image_id": vp,
            "pose": [1.0, 0, 0, x, 0, 1.0, 0, y, 0, 0, 1.0, 0.0, 0, 0, 0, 1.0],
            "included": True,
            "visible": [False] * len(ids),
            "unobstructed": [(vp, other) in pairs for other in ids],
            "height": 1.5,
        }
        for vp, (x, y) in points.items()
    ]
    return NavGraph(parse_connectivity(data, "line_connectivity.json"))


@pytest.fixture(scope="module")
def line() -> NavGraph:
    return _graph(_LINE, _LINE_EDGES)


def _episode(traj: list[Any], **kw: Any) -> EvalEpisode:
    return EvalEpisode(kw.pop("episode_id", "ep"), "line", tuple(REF), tuple(traj), **kw)


def _score(graph: NavGraph, traj: list[Any], config: MetricConfig | None = None, **kw: Any):
    return Evaluator(config=config).score(_episode(traj, **kw), graph)


# R2R measures.


def test_exact_path_scores_perfectly(line: NavGraph) -> None:
    s = _score(line, REF)
    assert s["ne"] == 0.0 and s["oracle_ne"] == 0.0
    assert s["sr"] == 1.0 and s["osr"] == 1.0
    assert s["tl"] == pytest.approx(4.0) and s["shortest"] == pytest.approx(4.0)
    assert s["spl"] == pytest.approx(1.0)
    assert s["ndtw"] == pytest.approx(1.0) and s["sdtw"] == pytest.approx(1.0)
    assert s["steps"] == 4.0


@pytest.mark.parametrize(
    ("stop", "ne", "sr"),
    [
        ("c", 2.0, 1.0),  # 2 < 3
        ("b", 3.0, 0.0),  # exactly 3 m: success is strict, NE < 3
        ("d", 1.0, 1.0),
    ],
)
def test_success_threshold_is_strict(line: NavGraph, stop: str, ne: float, sr: float) -> None:
    traj = REF[: REF.index(stop) + 1]
    s = _score(line, traj)
    assert s["ne"] == ne
    assert s["sr"] == sr
    assert s["osr"] == sr  # the walk only approaches the goal: oracle NE = NE


def test_success_distance_is_configurable(line: NavGraph) -> None:
    s = _score(line, ["a", "b"], MetricConfig(success_distance=3.5))
    assert s["sr"] == 1.0  # 3 < 3.5
    # SPL: l = 4, p = 1 -> 4 / max(1, 4) = 1 (R2R's formula rewards any success this way)
    assert s["spl"] == pytest.approx(1.0)


def test_oracle_success_when_passing_the_goal(line: NavGraph) -> None:
    s = _score(line, [*REF, "d", "c", "b"])  # reaches e, walks back to b
    assert s["ne"] == 3.0 and s["sr"] == 0.0
    assert s["oracle_ne"] == 0.0 and s["osr"] == 1.0
    assert s["tl"] == pytest.approx(7.0)  # 4 out + 3 back
    assert s["spl"] == 0.0 and s["sdtw"] == 0.0


def test_spl_and_ndtw_with_a_detour(line: NavGraph) -> None:
    s = _score(line, ["a", "b", "c", "q", "c", "d", "e"])
    # p = 1 + 1 + 2 + 2 + 1 + 1 = 8, l = 4 -> SPL = 4 / 8
    assert s["tl"] == pytest.approx(8.0)
    assert s["spl"] == pytest.approx(0.5)
    # Best alignment matches q to c (cost 2), everything else to itself (cost 0):
    # DTW = 2, nDTW = exp(-2 / (|R| * d_th)) = exp(-2 / (5 * 3)).
    assert s["ndtw"] == pytest.approx(math.exp(-2 / 15))
    assert s["sdtw"] == pytest.approx(math.exp(-2 / 15))  # SR = 1


def test_ndtw_of_a_short_stop(line: NavGraph) -> None:
    s = _score(line, ["a", "b"])
    # R = a b c d e, Q = a b: a-a 0, b-b 0, then c, d, e all align to b: 1 + 2 + 3 = 6.
    assert s["ndtw"] == pytest.approx(math.exp(-6 / 15))
    assert s["sdtw"] == 0.0  # NE = 3 fails


def test_ndtw_threshold_is_configurable(line: NavGraph) -> None:
    s = _score(line, ["a", "b"], MetricConfig(dtw_threshold=2.0))
    assert s["ndtw"] == pytest.approx(math.exp(-6 / (5 * 2.0)))


def test_turns_and_look_ups_do_not_change_path_measures(line: NavGraph) -> None:
    # Low-level trajectories repeat a viewpoint for every turn; moves are what count.
    traj = [["a", 0, 0], ["a", 0.5, 0], ["a", 1.0, 0], "b", "b", "c", "d", ["e", 0, 0.5]]
    s = _score(line, traj)
    assert s["tl"] == pytest.approx(4.0)
    assert s["ndtw"] == pytest.approx(1.0) and s["spl"] == pytest.approx(1.0)
    assert s["steps"] == 7.0


def test_dtw_by_hand() -> None:
    assert dtw(np.array([[0.0, 1.0], [1.0, 0.0]])) == 0.0  # diagonal match
    assert dtw(np.array([[1.0, 2.0, 3.0]])) == 6.0  # one reference node takes all
    # [[1, 5], [5, 1], [5, 1]]: 1 (0,0) + 1 (1,1) + 1 (2,1) = 3
    assert dtw(np.array([[1.0, 5.0], [5.0, 1.0], [5.0, 1.0]])) == 3.0
    with pytest.raises(InvalidArgumentError, match="non-empty 2-D"):
        dtw(np.zeros((0, 2)))


def test_ndtw_function(line: NavGraph) -> None:
    assert ndtw(line, REF, REF) == pytest.approx(1.0)
    assert ndtw(line, ["a"], ["e"], threshold=4.0) == pytest.approx(math.exp(-4 / 4))
    with pytest.raises(InvalidArgumentError, match="non-empty"):
        ndtw(line, [], ["a"])
    with pytest.raises(UnknownViewpointError):
        ndtw(line, ["a"], ["nope"])


# Collisions and the critical-node adjustment.

# People: at the start (Beginning), at the middle node c (Obstacle), off the path at q
# (Around) and at the goal (End).
PEOPLE = (
    Person("a", "Beginning"),
    Person("c", "Obstacle"),
    Person("q", "Around"),
    Person("e", "End"),
)
# Hits at the start, at c twice (a move and a turn there) and at the goal: 4 raw collisions.
HIT_TRAJ = [
    ["a", 0, 0, 1],
    ["b", 0, 0, 0],
    ["c", 0, 0, 1],
    ["c", 0.5, 0, True],
    "d",
    ["e", 0, 0, 1],
]


def test_crux_points_of_a_line(line: NavGraph) -> None:
    # Neighbouring nodes of a line share no neighbour: only start and goal are critical.
    assert crux_points(line, REF) == ["a", "e"]
    assert crux_points(line, ["a"]) == ["a"]
    assert crux_points(line, ["a", "b"]) == ["a", "b"]


def test_crux_points_follow_ha3d_rule() -> None:
    # t1 - t2 - t3 with h joined to t1 and t2: t1 and t2 share exactly one neighbour (h),
    # so t2 is a bottleneck. Adding k, joined to t1 and t2 too, gives two shared
    # neighbours and t2 stops being critical.
    pts = {"t1": (0.0, 0.0), "t2": (2.0, 0.0), "t3": (4.0, 0.0), "h": (1.0, 1.0)}
    edges = [("t1", "t2"), ("t2", "t3"), ("h", "t1"), ("h", "t2")]
    assert crux_points(_graph(pts, edges), ["t1", "t2", "t3"]) == ["t1", "t2", "t3"]
    pts2 = {**pts, "k": (1.0, -1.0)}
    edges2 = [*edges, ("k", "t1"), ("k", "t2")]
    assert crux_points(_graph(pts2, edges2), ["t1", "t2", "t3"]) == ["t1", "t3"]


@pytest.mark.parametrize(
    ("config", "crux", "unavoidable", "tcr"),
    [
        # paper, crux computed = [a, e]: people at a and e -> 4 - 2 = 2
        (MetricConfig(), None, [0, 3], 2.0),
        # paper, HA-R2R crux_points = [a, c, e]: people at a, c, e -> 4 - 3 = 1
        (MetricConfig(), ("a", "c", "e"), [0, 1, 3], 1.0),
        # ha3d: labels Beginning and End -> 4 - 2 = 2, whatever the crux points
        (MetricConfig.ha3d(), ("a", "c", "e"), [0, 3], 2.0),
        # no adjustment -> 4
        (MetricConfig(critical="none"), None, [], 4.0),
    ],
)
def test_collision_adjustment_modes(
    line: NavGraph,
    config: MetricConfig,
    crux: tuple[str, ...] | None,
    unavoidable: list[int],
    tcr: float,
) -> None:
    ep = _episode(HIT_TRAJ, people=PEOPLE, crux_points=crux)
    assert unavoidable_people(ep, line, config) == unavoidable
    s = Evaluator(config=config).score(ep, line)
    assert s["collisions"] == 4.0
    assert s["unavoidable"] == float(len(unavoidable))
    assert s["tcr"] == tcr
    assert s["cr"] == 1.0
    assert s["cf_sr"] == 0.0  # successful (NE 0) but hits remain


def test_clipping_and_collision_free_success(line: NavGraph) -> None:
    # No hits at all, two unavoidable people (a, e): 0 - 2.
    ep = _episode(REF, people=PEOPLE)
    paper = Evaluator().score(ep, line)
    assert paper["tcr"] == 0.0  # clipped: max(0, 0 - 2)
    assert paper["cr"] == 0.0 and paper["cf_sr"] == 1.0
    ha3d = Evaluator(config=MetricConfig.ha3d()).score(ep, line)
    assert ha3d["tcr"] == -2.0  # HA3D lets the count go negative
    assert ha3d["cr"] == 0.0
    assert ha3d["cf_sr"] == 0.0  # HA3D requires adjusted hits == 0 exactly


def test_cr_adjusted_or_raw(line: NavGraph) -> None:
    # One hit, at the start, next to the Beginning person: adjusted 1 - 1 = 0, raw 1.
    ep = _episode([["a", 0, 0, 1], "b", "c", "d", "e"], people=(Person("a", "Beginning"),))
    assert Evaluator().score(ep, line)["cr"] == 0.0  # HA-VLN 2.0: CR_ep = min(TCR_ep, 1)
    assert Evaluator(config=MetricConfig.ha3d()).score(ep, line)["cr"] == 1.0  # HA3D: raw


def test_collided_people_count_once_per_step(line: NavGraph) -> None:
    ep = _episode([["a", 0, 0, [0, 1]], {"viewpoint": "b", "collided_people": [2]}, *REF[2:]])
    s = Evaluator(config=MetricConfig(critical="none")).score(ep, line)
    assert s["collisions"] == 2.0  # two steps with hits, not three people


def test_paper_mode_uses_collision_radius(line: NavGraph) -> None:
    crux = ("a", "c", "e")
    people = (
        Person(position=(2.0, 1.0, 0.0)),  # exactly 1 m from c: unavoidable (<= 1 m)
        Person(position=(2.0, 1.01, 0.0)),  # 1.01 m from c, > 1.4 m from b and d: avoidable
        Person("q"),  # 2 m from c
    )
    ep = _episode(REF, people=people, crux_points=crux)
    assert unavoidable_people(ep, line, MetricConfig()) == [0]
    assert unavoidable_people(ep, line, MetricConfig(collision_radius=2.0)) == [0, 1, 2]
    # HA3D mode only reads labels, and these people have none.
    assert unavoidable_people(ep, line, MetricConfig.ha3d()) == []


# Evaluator, summary and dependencies.


def test_evaluate_summarises_episodes(line: NavGraph) -> None:
    eps = [
        _episode(HIT_TRAJ, episode_id="hit", people=PEOPLE),  # success, tcr 2
        _episode(["a", "b"], episode_id="short"),  # NE 3: failure, no hits
        _episode(["a", "b", "c", "q", "c", "d", "e"], episode_id="detour"),  # success
    ]
    result = evaluate(eps, {"line": line})
    assert [row["episode_id"] for row in result.per_episode] == ["hit", "short", "detour"]
    summ = result.summary
    assert summ["episodes"] == 3.0
    assert summ["sr"] == pytest.approx(2 / 3)
    assert summ["ne"] == pytest.approx((0 + 3 + 0) / 3)
    assert summ["spl"] == pytest.approx((1 + 0 + 0.5) / 3)
    assert summ["tcr"] == pytest.approx((2 + 0 + 0) / 3)
    assert summ["cr"] == pytest.approx(1 / 3)
    assert summ["cf_sr"] == pytest.approx(1 / 3)  # only "detour" succeeds without hits
    # Same result through a loader function.
    assert evaluate(eps, lambda scan: line).summary == summ


def test_requested_measures_pull_in_dependencies() -> None:
    assert Evaluator(["spl"]).names == ["ne", "sr", "tl", "shortest", "spl"]
    assert Evaluator(["cf_sr"]).names == ["ne", "sr", "collisions", "unavoidable", "tcr", "cf_sr"]


class _HalfSR(Measure):
    name = "half_sr"
    requires = ("sr",)

    def compute(self, ctx: EpisodeContext) -> float:
        return ctx["sr"] / 2


class _Sneaky(Measure):
    name = "sneaky"

    def compute(self, ctx: EpisodeContext) -> float:
        return ctx["ne"]  # not declared


def _cyclic(name: str, dep: str) -> Measure:
    cls = type(name, (Measure,), {"name": name, "requires": (dep,), "compute": lambda s, c: 0.0})
    return cls()


def test_custom_measure(line: NavGraph) -> None:
    ev = Evaluator([_HalfSR()])
    assert ev.names == ["ne", "sr", "half_sr"]
    assert ev.score(_episode(REF), line)["half_sr"] == 0.5


def test_undeclared_read_is_an_error(line: NavGraph) -> None:
    with pytest.raises(InvalidArgumentError, match="'sneaky' read 'ne' without declaring"):
        Evaluator(["ne", _Sneaky()]).score(_episode(REF), line)


def test_unknown_and_cyclic_dependencies() -> None:
    with pytest.raises(InvalidArgumentError, match=r"unknown measure 'spll'.*Did you mean 'spl'"):
        Evaluator(["spll"])
    with pytest.raises(InvalidArgumentError, match=r"'nothing' \(required by 'x'\)"):
        Evaluator([_cyclic("x", "nothing")])
    with pytest.raises(InvalidArgumentError, match="x -> y -> x"):
        Evaluator([_cyclic("x", "y"), _cyclic("y", "x")])
    with pytest.raises(InvalidArgumentError, match="names or Measure objects"):
        Evaluator([3])  # type: ignore[list-item]


# Input formats and bad input.


def test_step_formats() -> None:
    assert parse_step("a") == Step("a")
    assert parse_step(["a", 0.5, -0.5]) == Step("a", 0.5, -0.5)
    assert parse_step(["a", 0, 0, 1]).collided
    assert not parse_step(["a", 0, 0, 0]).collided
    hit = parse_step(["a", 0, 0, [3, 1]])
    assert hit.collided and hit.collided_people == (3, 1)
    assert parse_step({"viewpoint": "a", "heading": 1, "isCrushed": 1}) == Step("a", 1.0, 0, True)
    assert parse_step({"viewpoint": "a", "isCrashed": 0}).collided is False


@pytest.mark.parametrize(
    ("raw", "match"),
    [
        (["a", "x", 0], "heading must be a number"),
        (["a", math.nan, 0], "heading must be finite"),
        (["a", 0, 0, 2], "collision flag must be a bool or 0/1"),
        (["a", 0, 0, [-1]], "collided_people must hold ints"),
        ({"heading": 0}, "needs a 'viewpoint' key"),
        (["a", 0], "cannot read step"),
        (["", 0, 0], "non-empty string"),
    ],
)
def test_bad_steps(raw: Any, match: str) -> None:
    with pytest.raises(InvalidArgumentError, match=match):
        parse_step(raw)


def test_bad_trajectories_and_episodes(line: NavGraph) -> None:
    with pytest.raises(InvalidArgumentError, match="trajectory is empty"):
        parse_trajectory([])
    with pytest.raises(InvalidArgumentError, match="trajectory step 1: step heading"):
        parse_trajectory(["a", ["b", "x", 0]])
    with pytest.raises(InvalidArgumentError, match="starts at 'b', but the reference"):
        _episode(["b", "c"])
    with pytest.raises(InvalidArgumentError, match="reference_path is empty"):
        EvalEpisode("ep", "line", (), ("a",))
    with pytest.raises(InvalidArgumentError, match=r"human_rel_pos must be one of.*'Middle'"):
        Person("a", "Middle")
    with pytest.raises(InvalidArgumentError, match="needs a viewpoint or a position"):
        Person()
    with pytest.raises(UnknownViewpointError, match="'nope'"):
        Evaluator().score(_episode(["a", "nope"]), line)


def test_bad_config_and_graphs(line: NavGraph) -> None:
    with pytest.raises(InvalidArgumentError, match="critical must be one of"):
        MetricConfig(critical="paperr")  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match="success_distance must be finite and > 0"):
        MetricConfig(success_distance=-1.0)
    with pytest.raises(InvalidArgumentError, match="no episodes"):
        evaluate([], line)
    with pytest.raises(UnknownScanError, match="no navigation graph for scan 'line'"):
        evaluate([_episode(REF)], {"other": line})
    unreachable = EvalEpisode("iso", "line", ("a", "z"), ("a",))
    with pytest.raises(InvalidArgumentError, match="goal 'z' cannot be reached"):
        evaluate([unreachable], line)


# Dataset entries and R2R submissions.

_ITEM = {
    "scan": "line",
    "path_id": 7,
    "path": REF,
    "instructions": ["go", "walk"],
    "human": [
        {"human_viewpoint": "a", "human_rel_pos": "Beginning", "human_description": "x"},
        {"human_viewpoint": "c", "human_rel_pos": "Obstacle", "human_description": "y"},
    ],
    "crux_points": ["a", "c", "e"],
}


def test_episode_from_ha_r2r(line: NavGraph) -> None:
    ep = EvalEpisode.from_ha_r2r(_ITEM, HIT_TRAJ)
    assert ep.episode_id == "7" and ep.scan == "line" and ep.goal == "e"
    assert ep.people == (Person("a", "Beginning"), Person("c", "Obstacle"))
    assert ep.crux_points == ("a", "c", "e")
    # 4 hits - 2 people at crux points a and c
    assert Evaluator(["tcr"]).score(ep, line)["tcr"] == 2.0
    with pytest.raises(MalformedDataError, match="lacks a field"):
        EvalEpisode.from_ha_r2r({"scan": "line", "path_id": 1}, REF)


def test_episode_from_dataset_record(line: NavGraph) -> None:
    # Records with attributes (like havln_mj.tasks.episodes.Episode) work as well as JSON.
    human = SimpleNamespace(viewpoint="e", rel_pos="End")
    rec = SimpleNamespace(scan="line", path=tuple(REF), path_id=9, humans=(human,))
    ep = EvalEpisode.from_ha_r2r(rec, REF, "9_0")
    assert ep.episode_id == "9_0" and ep.people == (Person("e", "End"),)
    assert ep.crux_points is None  # computed from the graph when scored
    assert Evaluator(["unavoidable"]).score(ep, line)["unavoidable"] == 1.0


def test_episodes_from_submission(line: NavGraph) -> None:
    sub = [
        {"instr_id": "7_1", "trajectory": [[vp, 0.0, 0.0] for vp in REF]},
        {"instr_id": "7_0", "trajectory": [["a", 0.0, 0.0], ["b", 0.0, 0.0]]},
    ]
    eps = episodes_from_submission(sub, [_ITEM])
    assert [e.episode_id for e in eps] == ["7_1", "7_0"]
    assert evaluate(eps, line).summary["sr"] == 0.5
    with pytest.raises(InvalidArgumentError, match="lacks 1 of 2 instructions"):
        episodes_from_submission(sub[:1], [_ITEM])
    assert len(episodes_from_submission(sub[:1], [_ITEM], require_all=False)) == 1
    with pytest.raises(InvalidArgumentError, match="unknown instr_id '7_2'"):
        episodes_from_submission([{"instr_id": "7_2", "trajectory": ["a"]}], [_ITEM])
    with pytest.raises(InvalidArgumentError, match="appears twice"):
        episodes_from_submission([sub[0], sub[0]], [_ITEM], require_all=False)
    with pytest.raises(MalformedDataError, match="needs 'instr_id' and 'trajectory'"):
        episodes_from_submission([{"instr_id": "7_0"}], [_ITEM])


# Real data.


def test_real_r2r_episode_scores_perfectly(shared_data) -> None:
    scan = "17DRP5sb8fy"
    graph = NavGraph.from_file(shared_data / "mp3d_connectivity" / f"{scan}_connectivity.json")
    r2r = shared_data / "r2r" / "R2R_val_seen.json"
    if not r2r.is_file():
        pytest.skip(f"{r2r} not found")
    items = [x for x in json.loads(r2r.read_text()) if x["scan"] == scan]
    assert items, f"no val_seen episode in {scan}"
    item = items[0]
    # The R2R path is a graph shortest path; replay it in submission format.
    path = graph.shortest_path(item["path"][0], item["path"][-1])
    assert path == item["path"]
    traj = [[vp, item["heading"], 0.0] for vp in path]
    s = Evaluator().score(EvalEpisode.from_ha_r2r(item, traj), graph)
    assert s["ne"] == 0.0 and s["sr"] == 1.0
    assert s["spl"] == pytest.approx(1.0) and s["ndtw"] == pytest.approx(1.0)
    assert s["tl"] == pytest.approx(s["shortest"])
    assert s["collisions"] == 0.0 and s["tcr"] == 0.0


def test_real_ha_r2r_crux_points_match_graph_rule(shared_data) -> None:
    scan = "17DRP5sb8fy"
    ha = shared_data / "ha_r2r" / "HA_val_seen.json"
    if not ha.is_file():
        pytest.skip(f"{ha} not found")
    graph = NavGraph.from_file(shared_data / "mp3d_connectivity" / f"{scan}_connectivity.json")
    items = [x for x in json.loads(ha.read_text()) if x["scan"] == scan]
    assert items
    for item in items:
        assert crux_points(graph, item["path"]) == item["crux_points"]
