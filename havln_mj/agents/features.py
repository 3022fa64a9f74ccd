"""The per-scan cache of view features that agents observe.

A feature set is named by the vision encoder (a digest of its weights), the view configuration
and the people seed; it lives in ``$HAVLN_CACHE/agents/features/<name>/`` with one
``<scan>.npz`` per scan: ``viewpoints`` (V,), ``features`` (V, 36, S, D) float16 and
``complete``, whether V covers every viewpoint of the scan. A feature build writes whole scans;
an evaluation adds the viewpoints its agent reaches, one at a time
(:meth:`FeatureStore.add`), so a trained agent is scored without rendering the viewpoints it
never visits. Files are written atomically, so an interrupted build leaves whole files, and a
re-run only renders what is missing.
"""

from __future__ import annotations

import io
import json
import zipfile
from dataclasses import dataclass
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


@dataclass(frozen=True)
class _Scan:
    """One scan's cached features.

    Attributes:
        rows: Viewpoint id → row.
        features: ``(V, 36, S, D)`` float16.
        complete: Whether the rows cover every viewpoint of the scan.
    """

    rows: dict[str, int]
    features: np.ndarray
    complete: bool

    @classmethod
    def of(cls, viewpoints: list[str], features: np.ndarray, complete: bool) -> _Scan:
        rows = {vp: i for i, vp in enumerate(viewpoints)}
        return cls(rows, features.astype(np.float16, copy=False), bool(complete))


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
        self._scans: dict[str, _Scan] = {}

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
        """Whether every viewpoint of the scan is cached."""
        return self.path(scan_id).is_file() and self.scan(scan_id).complete

    def has_viewpoint(self, scan_id: str, viewpoint: str) -> bool:
        """Whether one viewpoint's features are cached."""
        entry = self._scans.get(scan_id)  # asked at every step: no file system call if loaded
        if entry is None:
            if not self.path(scan_id).is_file():
                return False
            entry = self.scan(scan_id)
        return viewpoint in entry.rows

    def put(self, scan_id: str, viewpoints: list[str], features: np.ndarray) -> None:
        """Stores the features ``(V, 36, S, D)`` of every viewpoint of a scan, atomically.

        Raises:
            MalformedDataError: The array does not have the set's shape.
        """
        self._check(scan_id, viewpoints, features)
        self._write(scan_id, _Scan.of(viewpoints, features, complete=True))

    def add(self, scan_id: str, viewpoints: list[str], features: np.ndarray) -> None:
        """Adds some viewpoints' features ``(V, 36, S, D)`` to a scan's file, atomically.

        What the file holds when this is called (another process may have added to it) is
        kept; a viewpoint already there keeps its features.

        Raises:
            MalformedDataError: The array does not have the set's shape.
        """
        self._check(scan_id, viewpoints, features)
        self._scans.pop(scan_id, None)
        old = self.scan(scan_id) if self.path(scan_id).is_file() else None
        if old is None:
            merged = _Scan.of(viewpoints, features, complete=False)
        else:
            new = [i for i, vp in enumerate(viewpoints) if vp not in old.rows]
            merged = _Scan.of(
                list(old.rows) + [viewpoints[i] for i in new],
                np.concatenate([old.features, features[new].astype(np.float16)]),
                complete=old.complete,
            )
        self._write(scan_id, merged)

    def _check(self, scan_id: str, viewpoints: list[str], features: np.ndarray) -> None:
        want = (len(viewpoints), NUM_VIEWS, self.config.slots, self.dim)
        if features.shape != want:
            raise MalformedDataError(
                f"features of {scan_id} have shape {features.shape}, expected {want}"
            )

    def _write(self, scan_id: str, entry: _Scan) -> None:
        buf = io.BytesIO()
        np.savez(
            buf,
            viewpoints=np.array(list(entry.rows)),
            features=entry.features,
            complete=np.array(entry.complete),
        )
        atomic_write_bytes(self.path(scan_id), buf.getvalue())
        self._scans[scan_id] = entry

    def scan(self, scan_id: str) -> _Scan:
        """A scan's cached features (loaded once).

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
                complete = bool(z["complete"]) if "complete" in z.files else True
        except (OSError, ValueError, KeyError, zipfile.BadZipFile) as exc:
            raise MalformedDataError(f"feature file {path} is damaged: {exc}") from None
        if feats.shape != (len(vps), NUM_VIEWS, self.config.slots, self.dim):
            raise MalformedDataError(f"feature file {path} has shape {feats.shape}")
        entry = _Scan.of(vps, feats, complete)
        self._scans[scan_id] = entry
        return entry

    def feature(self, scan_id: str, viewpoint: str, view_index: int, time: float) -> np.ndarray:
        """The ``(D,)`` feature an agent sees at ``viewpoint`` looking at ``view_index``.

        Raises:
            MissingDataError: The viewpoint is not in the scan's features.
        """
        entry = self.scan(scan_id)
        row = entry.rows.get(viewpoint)
        if row is None:
            raise MissingDataError(
                f"viewpoint {viewpoint!r} of {scan_id} has no features in {self.folder}"
            )
        return entry.features[row, view_index, self.config.slot(time)]
