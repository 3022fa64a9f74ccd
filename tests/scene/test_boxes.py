"""Segment / box ray casts and the box file."""

from __future__ import annotations

import numpy as np
import pytest

from havln_mj.errors import MalformedDataError
from havln_mj.scene.boxes import BoxSet, body_sweep_blocked, segments_hit_boxes

UNIT = (np.array([[0.0, 0.0, 0.0]]), np.array([[1.0, 1.0, 1.0]]))


@pytest.mark.parametrize(
    ("p0", "p1", "hit"),
    [
        ([-1, 0.5, 0.5], [2, 0.5, 0.5], True),  # straight through
        ([-1, 0.5, 0.5], [-0.1, 0.5, 0.5], False),  # stops short
        ([-1, 1.5, 0.5], [2, 1.5, 0.5], False),  # parallel, outside the slab
        ([-1, 1.0, 0.5], [2, 1.0, 0.5], True),  # grazes a face
        ([0.5, 0.5, 0.5], [0.6, 0.6, 0.6], True),  # starts inside
        ([-1, -1, 0.5], [2, 2, 0.5], True),  # diagonal through
        ([-1, 0.0, 0.5], [0.0, 1.5, 0.5], False),  # ends beside the box
        ([2, 2, 2], [3, 3, 3], False),
    ],
)
def test_segment_box_cases(p0, p1, hit):
    out = segments_hit_boxes(np.array([p0], float), np.array([p1], float), *UNIT)
    assert bool(out[0]) is hit


def test_many_segments_match_one_by_one():
    rng = np.random.default_rng(0)
    lo = rng.uniform(-5, 5, (30, 3))
    hi = lo + rng.uniform(0.1, 2, (30, 3))
    p0, p1 = rng.uniform(-6, 6, (500, 3)), rng.uniform(-6, 6, (500, 3))
    batched = segments_hit_boxes(p0, p1, lo, hi, chunk=64)
    single = [segments_hit_boxes(p0[i : i + 1], p1[i : i + 1], lo, hi)[0] for i in range(500)]
    np.testing.assert_array_equal(batched, single)
    # Dense sampling along each segment agrees wherever a sample falls inside a box.
    t = np.linspace(0, 1, 400)[None, :, None]
    pts = p0[:, None] + t * (p1 - p0)[:, None]
    inside = ((pts[:, :, None] >= lo) & (pts[:, :, None] <= hi)).all(-1).any((1, 2))
    assert np.all(batched[inside])


def _boxes(lo, hi, kinds):
    n = len(kinds)
    return BoxSet(
        np.array(lo, float), np.array(hi, float), tuple(kinds), ("m",) * n, np.ones((n, 4))
    )


def test_body_sweep_uses_radius_and_height():
    table_top = _boxes([[1.0, -0.5, 0.7]], [[2.0, 0.5, 0.75]], ["furniture"])
    a, b = np.array([[0.0, 0.0, 0.0]]), np.array([[3.0, 0.0, 0.0]])
    assert body_sweep_blocked(a, b, table_top, 0.2, (0.05, 1.8))[0]
    assert not body_sweep_blocked(a, b, table_top, 0.2, (0.05, 0.5))[
        0
    ]  # a short robot passes under
    beside = np.array([[0.0, 0.8, 0.0]]), np.array([[3.0, 0.8, 0.0]])
    assert not body_sweep_blocked(*beside, table_top, 0.2, (0.05, 1.8))[0]
    assert body_sweep_blocked(*beside, table_top, 0.35, (0.05, 1.8))[0]
    floor = _boxes([[-5, -5, -0.1]], [[5, 5, 0.0]], ["floor"])
    assert not body_sweep_blocked(a, b, floor, 0.2, (0.05, 1.8))[0]


def test_box_file_round_trip_and_errors(tmp_path):
    boxes = _boxes([[0, 0, 0], [1, 1, 0]], [[1, 1, 1], [2, 3, 2.5]], ["wall", "furniture"])
    boxes.write(tmp_path / "boxes.json")
    back = BoxSet.read(tmp_path / "boxes.json")
    np.testing.assert_allclose(back.lo, boxes.lo)
    assert back.kind == boxes.kind
    entry = '"material": "m", "rgba": [1, 1, 1, 1]'
    (tmp_path / "bad.json").write_text(
        '{"boxes": [{"lo": [0,0,0], "hi": [1,1,1], "kind": "roof", ' + entry + "}]}"
    )
    with pytest.raises(MalformedDataError, match="'roof'"):
        BoxSet.read(tmp_path / "bad.json")
    (tmp_path / "inv.json").write_text(
        '{"boxes": [{"lo": [0,0,2], "hi": [1,1,1], "kind": "wall", ' + entry + "}]}"
    )
    with pytest.raises(MalformedDataError, match="lo <= hi"):
        BoxSet.read(tmp_path / "inv.json")
