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
    np.testing.assert_array_equal(again.scan("proc-1")[1], feats.astype(np.float16))


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
    with pytest.raises(MissingDataError, match="no feature set"):
        FeatureStore.open(tmp_path / "nothing")
