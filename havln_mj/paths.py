"""The one place that resolves where assets and caches live.

Assets (materials, scene recipes, activity catalogs, robot models) are found under the
project home: ``$HAVLN_HOME`` if set, else the repository root that holds this package.
Caches (built scans, collision hulls, features) go to ``$HAVLN_CACHE``, default
``~/.cache/havln_mj``. Nothing here depends on the working directory.
"""

from __future__ import annotations

import os
from pathlib import Path

from havln_mj.errors import MissingDataError

_ASSET_DIRS = ("assets", "scenes", "humans", "robots", "agents", "eval")


def project_home() -> Path:
    """Returns the folder holding the asset directories (``assets/``, ``scenes/``, ...).

    Raises:
        MissingDataError: ``$HAVLN_HOME`` points at a folder without asset directories, or the
            package was installed without its repository and ``$HAVLN_HOME`` is unset.
    """
    env = os.environ.get("HAVLN_HOME")
    home = Path(env).expanduser().resolve() if env else Path(__file__).resolve().parents[1]
    if not (home / "scenes").is_dir():
        source = "$HAVLN_HOME" if env else "the repository root"
        raise MissingDataError(
            f"asset folder not found: {home / 'scenes'} ({source}). Install havln_mj from its "
            "repository with 'pip install -e .', or set HAVLN_HOME to a checkout."
        )
    return home


def asset_path(kind: str, *parts: str) -> Path:
    """Returns the path of an asset file, e.g. ``asset_path("scenes", "procedural.json")``.

    Args:
        kind: One of the asset directories: assets, scenes, humans, robots, agents, eval.
        *parts: Path components inside that directory.

    Raises:
        MissingDataError: The file does not exist.
    """
    if kind not in _ASSET_DIRS:
        raise ValueError(f"unknown asset kind {kind!r}; valid: {', '.join(_ASSET_DIRS)}")
    path = project_home().joinpath(kind, *parts)
    if not path.exists():
        raise MissingDataError(f"asset not found: {path}")
    return path


def cache_dir(*parts: str) -> Path:
    """Returns (and creates) a folder under ``$HAVLN_CACHE`` (default ``~/.cache/havln_mj``)."""
    root = Path(os.environ.get("HAVLN_CACHE", "~/.cache/havln_mj")).expanduser()
    path = root.joinpath(*parts)
    path.mkdir(parents=True, exist_ok=True)
    return path
