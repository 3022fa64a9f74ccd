"""The per-scan cache of view features that agents observe.

A feature set is named by the vision encoder (a digest of its weights), the view configuration
and the people seed; it lives in ``$HAVLN_CACHE/agents/features/<name>/`` with one
``<scan>.npz`` per scan: ``viewpoints`` (V,) and ``features`` (V, 36, S, D) float16. Files are
written atomically, so an interrupted build leaves whole scans or nothing, and a re-run only
renders what is missing.
"""

from __future__ import annotations

import io
import json
import zipfile
from pathlib import Path

import numpy as np

from havln_mj.agents.views import ViewConfig
from havln_mj.cache import atomic_write_bytes, atomic_write_json
from havln_mj.errors import MalformedDataError, MissingDataError
from havln_mj.paths import cache_dir
from havln_mj.sim.viewing import NUM_VIEWS

META = "features.json"


def features_root() -> Path:
    """Where feature sets are cached."""
    return cache_dir("agents", "features")


class FeatureStore:
    """One feature set: view features of many scans, looked up per agent state.

    Args:
        folder: The set's folder (created on the first write).
        config: How the views were rendered.
        dim: Feature size.
    """

    def __init__(self, folder: str | Path, config: ViewConfig, dim: int) -> None:
        self.folder = Path(folder)
        self.config = config
        self.dim = int(dim)
        self._scans: dict[str, tuple[dict[str, int], np.ndarray]] = {}

    @classmethod
    def named(cls, name: str, config: ViewConfig, dim: int) -> FeatureStore:
        """The set ``name`` under :func:`features_root`."""
        return cls(features_root() / name, config, dim)

    @classmethod
    def open(cls, folder: str | Path) -> FeatureStore:
        """An existing set, its configuration read from its ``features.json``.

        Raises:
            MissingDataError: The folder holds no feature set.
        """
        folder = Path(folder)
        meta = folder / META
        if not meta.is_file():
            raise MissingDataError(
                f"no feature set at {folder} (missing {META}); build one with "
                "`python -m havln_mj.agents.featurize --scenes ...`"
            )
        data = json.loads(meta.read_text())
        return cls(folder, ViewConfig(**data["view"]), data["dim"])

    def write_meta(self, extra: dict | None = None) -> None:
        """Records the configuration beside the features."""
        meta = {"view": self.config.__dict__, "dim": self.dim, **(extra or {})}
        atomic_write_json(self.folder / META, meta, indent=1)

    def path(self, scan_id: str) -> Path:
        """The file of one scan."""
        return self.folder / f"{scan_id}.npz"

    def has(self, scan_id: str) -> bool:
        """Whether the scan's features are cached."""
        return self.path(scan_id).is_file()

    def put(self, scan_id: str, viewpoints: list[str], features: np.ndarray) -> None:
        """Stores a scan's features ``(V, 36, S, D)`` atomically.

        Raises:
            MalformedDataError: The array does not have the set's shape.
        """
        want = (len(viewpoints), NUM_VIEWS, self.config.slots, self.dim)
        if features.shape != want:
            raise MalformedDataError(
                f"features of {scan_id} have shape {features.shape}, expected {want}"
            )
        buf = io.BytesIO()
        np.savez(buf, viewpoints=np.array(viewpoints), features=features.astype(np.float16))
        atomic_write_bytes(self.path(scan_id), buf.getvalue())
        self._scans.pop(scan_id, None)

    def scan(self, scan_id: str) -> tuple[dict[str, int], np.ndarray]:
        """A scan's viewpoint → row map and its ``(V, 36, S, D)`` features (loaded once).

        Raises:
            MissingDataError: The scan has no features in this set.
            MalformedDataError: The file is damaged or has the wrong shape.
        """
        entry = self._scans.get(scan_id)
        if entry is not None:
            return entry
        path = self.path(scan_id)
        if not path.is_file():
            raise MissingDataError(
                f"no features for scan {scan_id!r} in {self.folder}; build them with "
                f"`python -m havln_mj.agents.featurize --scenes {scan_id} ...`"
            )
        try:
            with np.load(path) as z:
                vps, feats = [str(v) for v in z["viewpoints"]], z["features"]
        except (OSError, ValueError, KeyError, zipfile.BadZipFile) as exc:
            raise MalformedDataError(f"feature file {path} is damaged: {exc}") from None
        if feats.shape != (len(vps), NUM_VIEWS, self.config.slots, self.dim):
            raise MalformedDataError(f"feature file {path} has shape {feats.shape}")
        entry = ({vp: i for i, vp in enumerate(vps)}, feats)
        self._scans[scan_id] = entry
        return entry

    def feature(self, scan_id: str, viewpoint: str, view_index: int, time: float) -> np.ndarray:
        """The ``(D,)`` feature an agent sees at ``viewpoint`` looking at ``view_index``.

        Raises:
            MissingDataError: The viewpoint is not in the scan's features.
        """
        rows, feats = self.scan(scan_id)
        row = rows.get(viewpoint)
        if row is None:
            raise MissingDataError(
                f"viewpoint {viewpoint!r} of {scan_id} has no features in {self.folder}"
            )
        return feats[row, view_index, self.config.slot(time)]
