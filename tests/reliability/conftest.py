"""Fixtures of the reliability tests: a private cache, a graph folder to edit, subprocesses."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

# The smallest of the 90 real graphs (8 viewpoints, 14 edges): its proxy builds in a second.
SMALL_SCAN = "gZ6f7yhEvPG"


@pytest.fixture
def fresh_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """``HAVLN_CACHE`` pointed at an empty folder of this test's own."""
    path = tmp_path / "cache"
    monkeypatch.setenv("HAVLN_CACHE", str(path))
    return path


@pytest.fixture
def graph_dir(tmp_path: Path, shared_data: Path) -> Path:
    """A connectivity folder holding a copy of one small real graph (safe to edit)."""
    folder = tmp_path / "graphs"
    folder.mkdir()
    name = f"{SMALL_SCAN}_connectivity.json"
    shutil.copy(shared_data / "mp3d_connectivity" / name, folder / name)
    return folder


@pytest.fixture
def small_scan() -> str:
    """The id of the graph in :func:`graph_dir`."""
    return SMALL_SCAN


@pytest.fixture
def cli(tmp_path: Path):
    """Runs ``python -m <args>`` in a scratch folder; returns the finished process."""

    def run(
        args: list[str], timeout: float = 300, env: dict | None = None
    ) -> subprocess.CompletedProcess:
        return subprocess.run(
            [sys.executable, "-m", *args],
            cwd=tmp_path,
            env={**os.environ, **(env or {})},
            capture_output=True,
            text=True,
            timeout=timeout,
        )

    return run
