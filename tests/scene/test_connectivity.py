"""Reading, validating and writing MatterSim connectivity files."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from havln_mj.errors import InvalidArgumentError, MalformedDataError, MissingDataError
from havln_mj.scene.connectivity import (
    FIELDS,
    Connectivity,
    dumps_connectivity,
    parse_connectivity,
    read_connectivity,
    write_connectivity,
)

# Half the 1e-6 rounding step, plus float error at exact halves.
_HALF_STEP = 5e-7 + 1e-12


def _pose(x: float, y: float, z: float) -> list[float]:
    return [1.0, 0.0, 0.0, x, 0.0, 1.0, 0.0, y, 0.0, 0.0, 1.0, z, 0.0, 0.0, 0.0, 1.0]


def _tiny() -> list[dict[str, Any]]:
    """Three viewpoints: a <-> b unobstructed, c excluded; visible deliberately asymmetric."""
    return [
        {
            "image_id": "vp_a",
            "pose": _pose(0.0, 0.0, 1.5),
            "included": True,
            "visible": [False, True, True],
            "unobstructed": [False, True, False],
            "height": 1.5,
        },
        {
            "image_id": "vp_b",
            "pose": _pose(3.0, 0.0, 1.25),
            "included": True,
            "visible": [True, False, False],
            "unobstructed": [True, False, False],
            "height": 1.25,
        },
        {
            "image_id": "vp_c",
            "pose": _pose(1.0, 2.0, 4.5),
            "included": False,
            "visible": [False, False, False],
            "unobstructed": [False, False, False],
            "height": 1,  # JSON integers are valid numbers
        },
    ]


def test_parse_gives_arrays_in_file_order() -> None:
    c = parse_connectivity(_tiny(), "tiny.json")
    assert c.ids == ("vp_a", "vp_b", "vp_c")
    assert len(c) == 3
    assert c.poses.shape == (3, 4, 4) and c.poses.dtype == np.float64
    np.testing.assert_array_equal(c.positions, [[0, 0, 1.5], [3, 0, 1.25], [1, 2, 4.5]])
    np.testing.assert_array_equal(c.floor_z, [0.0, 0.0, 3.5])
    np.testing.assert_array_equal(c.included, [True, True, False])
    np.testing.assert_array_equal(c.visible[0], [False, True, True])
    assert c.unobstructed[0, 1] and c.unobstructed[1, 0] and not c.unobstructed[0, 2]
    assert c.heights.dtype == np.float64 and c.heights[2] == 1.0
    assert c.source == "tiny.json"


def test_arrays_are_read_only_copies() -> None:
    poses = np.tile(np.eye(4), (2, 1, 1))
    c = Connectivity(
        ids=("a", "b"),
        poses=poses,
        included=np.ones(2, bool),
        visible=np.zeros((2, 2), bool),
        unobstructed=np.zeros((2, 2), bool),
        heights=np.ones(2),
    )
    poses[0, 0, 3] = 99.0
    assert c.poses[0, 0, 3] == 0.0
    with pytest.raises(ValueError, match="read-only"):
        c.included[0] = False


def test_constructor_rejects_inconsistent_shapes() -> None:
    with pytest.raises(InvalidArgumentError, match=r"unobstructed has shape \(2, 3\)"):
        Connectivity(
            ids=("a", "b"),
            poses=np.zeros((2, 4, 4)),
            included=np.ones(2, bool),
            visible=np.zeros((2, 2), bool),
            unobstructed=np.zeros((2, 3), bool),
            heights=np.ones(2),
        )


def _set(i: int, field: str, value: Any):
    def mutate(data: list[dict[str, Any]]) -> None:
        data[i][field] = value

    return mutate


def _delete(i: int, field: str):
    def mutate(data: list[dict[str, Any]]) -> None:
        del data[i][field]

    return mutate


def _set_item(i: int, field: str, k: int, value: Any):
    def mutate(data: list[dict[str, Any]]) -> None:
        data[i][field][k] = value

    return mutate


def _replace_entry(i: int, value: Any):
    def mutate(data: list[dict[str, Any]]) -> None:
        data[i] = value

    return mutate


@pytest.mark.parametrize(
    ("mutate", "expected"),
    [
        (_replace_entry(1, ["vp_b"]), "entry 1: expected an object, got an array"),
        (_delete(0, "height"), "entry 0: missing field(s) height"),
        (_set(2, "extra", 1), "entry 2: unexpected field(s) 'extra'"),
        (_set(1, "image_id", 7), "entry 1: image_id must be a non-empty string, got 7"),
        (_set(1, "image_id", ""), "entry 1: image_id must be a non-empty string"),
        (_set(2, "image_id", "vp_a"), "entry 2 (image_id 'vp_a'): duplicate image_id"),
        (_set(0, "pose", [0.0] * 12), "entry 0 (image_id 'vp_a'): pose must be 16 numbers, got 12"),
        (_set(0, "pose", "eye"), "pose must be 16 numbers, got a string"),
        (_set_item(1, "pose", 5, "1.0"), "entry 1 (image_id 'vp_b'): pose[5] must be a finite"),
        (_set_item(1, "pose", 5, True), "pose[5] must be a finite number, got True"),
        (_set_item(1, "pose", 3, float("nan")), "pose[3] must be a finite number, got nan"),
        (_set(0, "included", 1), "entry 0 (image_id 'vp_a'): included must be true or false"),
        (
            _set(1, "visible", [True, False]),
            "entry 1 (image_id 'vp_b'): visible has 2 entries, expected 3 (one per viewpoint)",
        ),
        (_set(1, "visible", None), "visible must be an array of 3 booleans, got null"),
        (_set_item(2, "unobstructed", 1, 0), "entry 2 (image_id 'vp_c'): unobstructed[1] must be"),
        (_set_item(0, "unobstructed", 2, [True]), "entry 0 (image_id 'vp_a'): unobstructed[2]"),
        (_set_item(1, "visible", 0, "true"), "entry 1 (image_id 'vp_b'): visible[0] must be"),
        (_set(2, "height", "1.5"), "entry 2 (image_id 'vp_c'): height must be a finite number"),
        (_set(2, "height", 10**400), "height must be a finite number"),
    ],
)
def test_schema_errors_name_file_entry_and_field(mutate, expected: str) -> None:
    data = _tiny()
    mutate(data)
    with pytest.raises(MalformedDataError) as info:
        parse_connectivity(data, "scan_connectivity.json")
    assert str(info.value).startswith("scan_connectivity.json: ")
    assert expected in str(info.value)


def test_top_level_must_be_an_array() -> None:
    with pytest.raises(MalformedDataError, match=r"x\.json: expected a JSON array .*got an object"):
        parse_connectivity({"image_id": "vp_a"}, "x.json")


def test_empty_array_is_an_empty_scan() -> None:
    c = parse_connectivity([], "empty.json")
    assert len(c) == 0 and c.unobstructed.shape == (0, 0) and c.poses.shape == (0, 4, 4)


def test_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "nope_connectivity.json"
    with pytest.raises(MissingDataError, match=r"nope_connectivity\.json") as info:
        read_connectivity(path)
    assert isinstance(info.value, FileNotFoundError)
    with pytest.raises(MissingDataError, match="is a folder"):
        read_connectivity(tmp_path)


def test_invalid_json_names_file_and_position(tmp_path: Path) -> None:
    path = tmp_path / "bad_connectivity.json"
    path.write_text('[{"image_id": "vp_a",\n "pose": [1, 2,]}]')
    with pytest.raises(MalformedDataError) as info:
        read_connectivity(path)
    message = str(info.value)
    assert str(path) in message and "invalid JSON at line 2 column" in message
    assert isinstance(info.value, ValueError)


def test_invalid_utf8(tmp_path: Path) -> None:
    path = tmp_path / "bin_connectivity.json"
    path.write_bytes(b"[\xff\xfe]")
    with pytest.raises(MalformedDataError, match="not UTF-8"):
        read_connectivity(path)


def test_round_trip(tmp_path: Path) -> None:
    data = _tiny()
    data[0]["pose"][3] = 0.1234567891  # beyond the 6 written decimals
    original = parse_connectivity(data)
    path = tmp_path / "sub" / "tiny_connectivity.json"
    write_connectivity(path, original)
    back = read_connectivity(path)
    assert back.ids == original.ids
    np.testing.assert_allclose(back.poses, original.poses, rtol=0, atol=_HALF_STEP)
    np.testing.assert_allclose(back.heights, original.heights, rtol=0, atol=_HALF_STEP)
    for name in ("included", "visible", "unobstructed"):
        np.testing.assert_array_equal(getattr(back, name), getattr(original, name))
    assert back.poses[0, 0, 3] == 0.123457
    assert back.scan == "tiny"
    # Writing what was read gives the same bytes again.
    assert dumps_connectivity(back) == path.read_text()
    assert not list(path.parent.glob("*.tmp"))  # the atomic write left no temporary file


def test_bytes_are_deterministic_and_ignore_noise() -> None:
    text = dumps_connectivity(parse_connectivity(_tiny()))
    assert text == dumps_connectivity(parse_connectivity(_tiny()))
    noisy = _tiny()
    noisy[0]["pose"][3] = -1e-9  # would print as "-0.0" without normalisation
    noisy[1]["pose"][3] = 3.0 + 1e-9
    noisy[1]["height"] = 1.25 - 1e-10
    assert dumps_connectivity(parse_connectivity(noisy)) == text
    assert "-0.0" not in text


def test_exact_schema_and_key_order() -> None:
    text = dumps_connectivity(parse_connectivity(_tiny()))
    assert text.startswith('[{"image_id":"vp_a","pose":[1.0,0.0,0.0,0.0,')
    assert "\n" not in text and " " not in text
    entries = json.loads(text, object_pairs_hook=lambda pairs: pairs)
    assert len(entries) == 3
    for pairs in entries:
        assert tuple(k for k, _ in pairs) == FIELDS
    loaded = json.loads(text)
    assert loaded[2]["included"] is False
    assert loaded[0]["visible"] == [False, True, True]
    assert loaded[2]["height"] == 1.0 and isinstance(loaded[2]["height"], float)


def test_decimals_argument() -> None:
    data = _tiny()
    data[1]["pose"][3] = 3.14159
    text = dumps_connectivity(parse_connectivity(data), decimals=2)
    assert json.loads(text)[1]["pose"][3] == 3.14


def test_parse_does_not_modify_input() -> None:
    data = _tiny()
    before = copy.deepcopy(data)
    parse_connectivity(data)
    assert data == before


@pytest.mark.parametrize("scan", ["gZ6f7yhEvPG", "B6ByNegPMKs"])  # smallest and largest file
def test_real_file_round_trip(shared_data: Path, scan: str, tmp_path: Path) -> None:
    original = read_connectivity(shared_data / "mp3d_connectivity" / f"{scan}_connectivity.json")
    assert original.scan == scan
    raw = json.loads(Path(original.source).read_text())
    assert [e["image_id"] for e in raw] == list(original.ids)
    assert list(raw[0]) == list(FIELDS)  # the MatterSim files use the same key order
    path = tmp_path / f"{scan}_connectivity.json"
    write_connectivity(path, original)
    back = read_connectivity(path)
    np.testing.assert_allclose(back.poses, original.poses, rtol=0, atol=_HALF_STEP)
    np.testing.assert_allclose(back.heights, original.heights, rtol=0, atol=_HALF_STEP)
    np.testing.assert_array_equal(back.unobstructed, original.unobstructed)
    np.testing.assert_array_equal(back.visible, original.visible)
    np.testing.assert_array_equal(back.included, original.included)
    assert dumps_connectivity(back).encode() == path.read_bytes()
