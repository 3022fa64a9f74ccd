"""Shared fixtures: an isolated cache per test session and the shared real-data folder."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("MUJOCO_GL", "egl")

_REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session", autouse=True)
def _isolated_cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Points HAVLN_CACHE at a per-session temp folder so tests never touch the user's cache."""
    path = tmp_path_factory.mktemp("havln_cache")
    old = os.environ.get("HAVLN_CACHE")
    os.environ["HAVLN_CACHE"] = str(path)
    yield path
    if old is None:
        os.environ.pop("HAVLN_CACHE", None)
    else:
        os.environ["HAVLN_CACHE"] = old


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The real public test data (``$HAVLN_SHARED_DATA`` or ``../shared/data``); skips if absent."""
    path = Path(os.environ.get("HAVLN_SHARED_DATA", _REPO.parent / "shared" / "data"))
    if not (path / "mp3d_connectivity").is_dir():
        pytest.skip(f"shared real data not found at {path} (set HAVLN_SHARED_DATA)")
    return path
