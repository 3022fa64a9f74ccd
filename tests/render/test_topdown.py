"""Top-down maps."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from havln_mj.errors import InvalidArgumentError
from havln_mj.render.topdown import draw_topdown, section_segments
from havln_mj.scene.scan import load_scan


@pytest.fixture(scope="module")
def scan():
    return load_scan("proc-6")


@pytest.fixture(scope="module")
def route(scan):
    nodes = scan.graph.components()[0]
    return scan.graph.shortest_path(nodes[0], nodes[-1])


def _count(img, bgr, tol=40):
    diff = np.abs(img.astype(int) - np.array(bgr)[None, None, :]).max(axis=2)
    return int((diff < tol).sum())


def _red(img):
    b, g, r = (img[..., k].astype(int) for k in range(3))
    return int(((r > 180) & (g < 80) & (b < 80)).sum())


def test_map_has_rooms_walls_and_the_path(tmp_path, scan, route):
    walls = section_segments(scan.mesh, 1.0)
    assert len(walls) > 20 and walls.shape[1:] == (2, 2)
    plain, with_path = tmp_path / "plain.png", tmp_path / "path.png"
    draw_topdown(plain, scan.graph, scan.regions, scan.mesh)
    draw_topdown(with_path, scan.graph, scan.regions, scan.mesh, [route], title="t")
    img_plain, img_path = cv2.imread(str(plain)), cv2.imread(str(with_path))
    assert img_plain.shape[2] == 3
    # The highlighted path adds saturated red pixels the plain map lacks.
    assert _red(img_path) > _red(img_plain) + 100


def test_legend_names_every_mark_drawn(tmp_path, scan, route):
    g = scan.graph
    plain = draw_topdown(tmp_path / "plain.png", g, scan.regions, scan.mesh)
    assert plain == [
        "room (region), coloured by kind",
        "furniture",
        "walls (mesh cut 1 m above the floor)",
        "viewpoint",
        "navigable edge",
    ]
    track = np.array([g.position(v) for v in route])
    people = track[[1]] - np.array([0.0, 0.0, 0.6])  # a pelvis beside the path
    labels = draw_topdown(
        tmp_path / "full.png",
        g,
        scan.regions,
        scan.mesh,
        [route],
        title="t",
        people=people,
        walked=[track],
        collisions=track[[1]],
    )
    for label in (
        "planned path (graph)",
        "start",
        "goal",
        "walked track (true position)",
        "where the walk ended",
        "person",
        "1 m collision radius",
        "collision (agent within 1 m of a person)",
    ):
        assert label in labels
    # One episode needs no colour key; two do.
    assert not any(lb.startswith("episode") for lb in labels)
    two = draw_topdown(tmp_path / "two.png", g, None, None, [route, route[::-1]])
    assert [lb for lb in two if lb.startswith("episode")] == ["episode 1", "episode 2"]


def test_walked_track_people_tracks_and_collisions_are_drawn(tmp_path, scan, route):
    g = scan.graph
    base = tmp_path / "base.png"
    draw_topdown(base, g, None, None, [route])
    pts = np.array([g.position(v) for v in route])
    # A walked track off to one side of the planned path, in its colour.
    walked = pts + np.array([0.4, 0.4, -1.0])
    draw_topdown(tmp_path / "walked.png", g, None, None, [route], walked=[walked])
    # A person pacing across the map over the episode.
    lo, hi = pts[:, :2].min(axis=0), pts[:, :2].max(axis=0)
    t = np.linspace(0.0, 1.0, 50)[:, None]
    pelvis = np.column_stack([lo + t * (hi - lo), np.full(50, g.floor_z(route[0]) + 0.9)])
    draw_topdown(tmp_path / "people.png", g, None, None, [route], people_tracks=pelvis[:, None])
    draw_topdown(tmp_path / "hits.png", g, None, None, [route], collisions=pts[1:-1, :2])
    base_img = cv2.imread(str(base))
    walked_img = cv2.imread(str(tmp_path / "walked.png"))
    assert _red(walked_img) > _red(base_img) + 100
    orange = (14, 127, 255)  # BGR of the people's colour
    people_img = cv2.imread(str(tmp_path / "people.png"))
    assert _count(people_img, orange) > _count(base_img, orange) + 200
    hit_red = (11, 0, 232)
    hits_img = cv2.imread(str(tmp_path / "hits.png"))
    assert _count(hits_img, hit_red, 30) > _count(base_img, hit_red, 30) + 50


def test_other_levels_are_left_out(tmp_path, scan, route):
    g = scan.graph
    pts = np.array([g.position(v) for v in route])
    base = tmp_path / "base.png"
    draw_topdown(base, g, None, None)
    upstairs = pts + np.array([0.0, 0.0, 5.0])  # a walk and a person one floor up
    draw_topdown(
        tmp_path / "up.png",
        g,
        None,
        None,
        walked=[upstairs],
        people=upstairs[:1],
        collisions=upstairs,
    )
    base_img, up_img = cv2.imread(str(base)), cv2.imread(str(tmp_path / "up.png"))
    assert _red(up_img) == _red(base_img)
    assert _count(up_img, (14, 127, 255)) == _count(base_img, (14, 127, 255))


def test_long_titles_wrap_and_margins_are_tight(tmp_path, scan):
    g = scan.graph
    short, long = tmp_path / "short.png", tmp_path / "long.png"
    draw_topdown(short, g, scan.regions, None, title="proc-6")
    words = "a graph proxy synthesised from the navigation graph, NOT the real mesh; " * 4
    draw_topdown(long, g, scan.regions, None, title=f"17DRP5sb8fy ({words})")
    a, b = cv2.imread(str(short)), cv2.imread(str(long))
    # Wrapped, the long title takes more lines, never more width.
    assert b.shape[1] == a.shape[1] and b.shape[0] > a.shape[0] + 30
    # No wide white border: every side has ink within a few pixels of the edge.
    ink = (a < 200).any(axis=2)
    rows, cols = np.flatnonzero(ink.any(axis=1)), np.flatnonzero(ink.any(axis=0))
    assert rows[0] <= 15 and rows[-1] >= a.shape[0] - 16
    assert cols[0] <= 15 and cols[-1] >= a.shape[1] - 16


def test_bad_arrays_name_what_is_valid(tmp_path, scan):
    g = scan.graph
    with pytest.raises(InvalidArgumentError, match=r"walked tracks must be \(n, 2\) or \(n, 3\)"):
        draw_topdown(tmp_path / "x.png", g, None, None, walked=[np.zeros((4, 5))])
    with pytest.raises(InvalidArgumentError, match=r"people_tracks must be \(T, P, 3\)"):
        draw_topdown(tmp_path / "x.png", g, None, None, people_tracks=np.zeros((4, 3)))
    with pytest.raises(InvalidArgumentError, match="collisions"):
        draw_topdown(tmp_path / "x.png", g, None, None, collisions=np.zeros(3))
