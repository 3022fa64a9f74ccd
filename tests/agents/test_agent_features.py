"""The per-scan feature cache."""

from __future__ import annotations

import numpy as np
import pytest

from havln_mj.agents.features import FeatureStore
from havln_mj.agents.views import ViewConfig
from havln_mj.errors import MalformedDataError, MissingDataError


def _store(tmp_path, slots=3):
    return FeatureStore(tmp_path / "set", ViewConfig(slots=slots, slot_seconds=2.0), dim=4)


def test_put_then_look_up_by_view_and_time(tmp_path):
    store = _store(tmp_path)
    feats = np.arange(2 * 36 * 3 * 4, dtype=np.float32).reshape(2, 36, 3, 4)
    store.put("proc-1", ["a", "b"], feats)
    assert store.has("proc-1") and not store.has("proc-2")
    assert not list((tmp_path / "set").glob(".*tmp"))  # written atomically
    np.testing.assert_array_equal(store.feature("proc-1", "b", 7, 0.0), feats[1, 7, 0])
    np.testing.assert_array_equal(store.feature("proc-1", "b", 7, 2.2), feats[1, 7, 1])
    np.testing.assert_array_equal(store.feature("proc-1", "a", 35, 6.1), feats[0, 35, 0])  # wraps
    store.write_meta()
    again = FeatureStore.open(tmp_path / "set")
    assert again.config == store.config and again.dim == 4
    np.testing.assert_array_equal(again.scan("proc-1").features, feats.astype(np.float16))


def test_viewpoints_added_one_at_a_time_make_a_partial_scan(tmp_path):
    store = _store(tmp_path)
    feats = np.arange(3 * 36 * 3 * 4, dtype=np.float32).reshape(3, 36, 3, 4)
    store.add("proc-1", ["a"], feats[:1])
    assert store.has_viewpoint("proc-1", "a") and not store.has_viewpoint("proc-1", "b")
    assert not store.has("proc-1")  # a partial scan is not a whole one: builds render it all
    # Another process adds to the same file; what it wrote is kept, and a repeat is ignored.
    other = _store(tmp_path)
    other.add("proc-1", ["b"], feats[1:2])
    store.add("proc-1", ["c", "a"], np.stack([feats[2], feats[2]]))
    again = _store(tmp_path)
    assert list(again.scan("proc-1").rows) == ["a", "b", "c"]
    for row, vp in enumerate("abc"):
        np.testing.assert_array_equal(again.feature("proc-1", vp, 5, 0.0), feats[row, 5, 0])
    assert not again.has("proc-1")
    # A whole scan written over a partial one is complete.
    again.put("proc-1", ["a", "b", "c"], feats)
    assert _store(tmp_path).has("proc-1")


def test_files_without_the_complete_flag_hold_whole_scans(tmp_path):
    store = _store(tmp_path)
    store.folder.mkdir(parents=True)
    feats = np.zeros((1, 36, 3, 4), np.float16)
    np.savez(store.path("proc-1"), viewpoints=np.array(["a"]), features=feats)
    assert store.has("proc-1") and store.has_viewpoint("proc-1", "a")


def test_bad_shapes_missing_and_damaged_files(tmp_path):
    store = _store(tmp_path)
    with pytest.raises(MalformedDataError, match=r"expected \(1, 36, 3, 4\)"):
        store.put("proc-1", ["a"], np.zeros((1, 36, 2, 4)))
    with pytest.raises(MissingDataError, match="featurize --scenes proc-9"):
        store.feature("proc-9", "a", 0, 0.0)
    store.put("proc-1", ["a"], np.zeros((1, 36, 3, 4)))
    with pytest.raises(MissingDataError, match="viewpoint 'z'"):
        store.feature("proc-1", "z", 0, 0.0)
    store.path("proc-2").write_bytes(b"not a zip")
    with pytest.raises(MalformedDataError, match="damaged"):
        store.scan("proc-2")
    with pytest.raises(MalformedDataError, match="damaged"):
        store.has("proc-2")
    with pytest.raises(MissingDataError, match="no feature set"):
        FeatureStore.open(tmp_path / "nothing")
