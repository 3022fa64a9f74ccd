"""The annotation session: people as the simulator makes them, views, previews, files."""

from __future__ import annotations

import json
import math

import cv2
import numpy as np
import pytest

from havln_mj.annotator.placements import HA3D_NAME
from havln_mj.annotator.plan import scene_plan
from havln_mj.annotator.session import AnnotationSession
from havln_mj.errors import InvalidArgumentError, UnknownViewpointError
from havln_mj.frames import heading_to
from havln_mj.render.video import probe
from havln_mj.scene.scan import load_scan


@pytest.fixture(scope="module")
def scan():
    return load_scan("proc-0")


@pytest.fixture
def session(scan, tmp_path):
    s = AnnotationSession(scan, tmp_path / "placements.json", size=(96, 72))
    yield s
    s.close()


def _pair(scan):
    """A viewpoint and a neighbour 1.5–5 m from it on the same floor."""
    g = scan.graph
    for a, b, d in g.edges():
        if 1.5 < d < 5.0 and abs(g.floor_z(a) - g.floor_z(b)) < 0.1:
            return a, b
    raise AssertionError("no suitable edge")


def test_plan_lists_the_scan(scan):
    plan = scene_plan(scan)
    assert len(plan["viewpoints"]) == len(scan.graph.ids)
    assert len(plan["edges"]) == scan.graph.num_edges
    assert {r["name"] for r in plan["rooms"]} >= {"kitchen", "hallway"}
    assert len(plan["walls"]) == len(plan["levels"]) and len(plan["walls"][0]) > 20
    vp = plan["viewpoints"][0]
    assert set(vp) >= {"id", "x", "y", "level", "region", "face_deg", "included"}


def test_people_round_trip_and_report_what_plays(session, scan):
    a, _ = _pair(scan)
    session.set_people(
        [{"viewpoint": a, "activity": "kitchen/dishwasher", "model": 2, "heading_deg": 90}]
    )
    (p,) = session.people_json()
    assert p["plays"] == "kitchen/dishwasher" and p["model"] == 2 and p["heading_deg"] == 90.0
    assert p["sentence"] == "kitchen:A person loading the dishwasher."
    path = session.save()
    session.set_people([])
    assert session.people_json() == []
    session.load()
    assert [q["viewpoint"] for q in session.people_json()] == [a]
    assert path.is_file()


def test_bad_people_are_refused_and_nothing_changes(session, scan):
    a, _ = _pair(scan)
    good = [{"viewpoint": a, "activity": "kitchen/dishwasher"}]
    session.set_people(good)
    for bad, error in (
        ({"people": good}, InvalidArgumentError),
        ([{"activity": "kitchen/dishwasher"}], InvalidArgumentError),
        ([{"viewpoint": "x", "activity": "kitchen/dishwasher"}], UnknownViewpointError),
        ([{**good[0], "heading_deg": "north"}], InvalidArgumentError),
        (good + good, InvalidArgumentError),
    ):
        with pytest.raises(error):
            session.set_people(bad)
    assert [p.viewpoint for p in session.people] == [a]


def test_views_show_the_people_placed(session, scan):
    a, b = _pair(scan)
    g = scan.graph
    heading = math.degrees(heading_to(g.position(b), g.position(a)))
    empty = cv2.imdecode(np.frombuffer(session.view_png(b, heading, -10, 0.0), np.uint8), 1)
    assert empty.shape == (72, 96, 3)
    session.set_people([{"viewpoint": a, "activity": "kitchen/dishwasher"}])
    seen = cv2.imdecode(np.frombuffer(session.view_png(b, heading, -10, 0.0), np.uint8), 1)
    # The person stands in front of the camera: many pixels change.
    assert (np.abs(seen.astype(int) - empty).max(axis=2) > 30).mean() > 0.01
    with pytest.raises(InvalidArgumentError, match="heading must be finite"):
        session.view_png(b, math.inf, 0, 0)


def test_preview_is_an_h264_clip_of_the_person(session, scan, tmp_path):
    a, _ = _pair(scan)
    with pytest.raises(InvalidArgumentError, match="no person on viewpoint"):
        session.preview_mp4(a)
    session.set_people([{"viewpoint": a, "activity": "kitchen/dishwasher"}])
    clip = tmp_path / "clip.mp4"
    clip.write_bytes(session.preview_mp4(a))
    info = probe(clip)
    assert info["codec"] == "h264" and info["frames"] == 40 and info["size"] == (96, 72)


def test_a_swapped_activity_is_explained(session, scan):
    """HA3D's file may seat someone; the simulator stands them up, and the page says so."""
    sitting = next(a for a in session.catalog if a.needs_seat)
    a, _ = _pair(scan)
    sentence = f"{HA3D_NAME[sitting.region]}:{sitting.text}"
    session.path.write_text(json.dumps({"proc-0": {a: [sentence, 0, 0]}}))
    session.load()
    (p,) = session.people_json()
    assert p["activity"] == sitting.id and p["sentence"] == sentence
    assert p["plays"] != sitting.id and "sitting needs a seat" in p["note"]
