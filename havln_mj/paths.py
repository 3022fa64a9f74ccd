"""The one place that resolves where assets and caches live.

Assets (materials, scene recipes, activity catalogs, robot models, agent configs) are found
under the project home: ``$HAVLN_HOME`` if set; else the package's own copy
(``havln_mj/_data``, which a built wheel carries, found through ``importlib.resources``);
else the source checkout that holds this package (an editable install). Caches (built scans,
collision hulls, features) go to ``$HAVLN_CACHE``, default ``~/.cache/havln_mj``. Nothing
here depends on the working directory.
"""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path

from havln_mj.errors import InvalidArgumentError, MissingDataError

_ASSET_DIRS = ("assets", "scenes", "humans", "robots", "agents", "eval")


def project_home() -> Path:
    """Returns the folder holding the asset directories (``assets/``, ``scenes/``, ...).

    Raises:
        MissingDataError: ``$HAVLN_HOME`` points at a folder without asset directories, or the
            package was installed without its repository and ``$HAVLN_HOME`` is unset.
    """
    env = os.environ.get("HAVLN_HOME")
    if env:
        home, source = Path(env).expanduser().resolve(), "$HAVLN_HOME"
    else:
        packaged = Path(str(resources.files("havln_mj") / "_data"))
        checkout = Path(__file__).resolve().parents[1]
        home = packaged if packaged.is_dir() else checkout
        source = "the installed package" if packaged.is_dir() else "the source checkout"
    if not (home / "scenes").is_dir():
        raise MissingDataError(
            f"asset folder not found: {home / 'scenes'} ({source}). Reinstall havln_mj "
            "('pip install havln_mj' or 'pip install -e .' in a checkout), or set HAVLN_HOME "
            "to a checkout."
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
        raise InvalidArgumentError(f"unknown asset kind {kind!r}; valid: {', '.join(_ASSET_DIRS)}")
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
