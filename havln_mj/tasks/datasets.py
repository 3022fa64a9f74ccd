"""R2R and HA-R2R files: finding, reading, validating and writing them.

Both files are a JSON array with one object per path::

    {"distance": float (absent in R2R test), "scan": str, "path_id": int,
     "path": [viewpoint ids, start first, goal last], "heading": radians,
     "instructions": [str, ...]}

HA-R2R adds ``"human": [{"human_viewpoint", "human_rel_pos", "human_description"}, ...]``,
``"crux_points": [viewpoint ids]`` and, on paths with people, ``"Relative Position
Description": [str, ...]``. Each object becomes an :class:`~havln_mj.tasks.episodes.Episode`.
Reading is strict about the schema; keys the schema does not name are kept in
``Episode.extra`` and written back, so ``write_dataset`` after ``load_dataset`` gives the same
JSON. Given a connectivity folder, every scan and viewpoint is checked against its graph.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from havln_mj.cache import atomic_write_json
from havln_mj.errors import (
    InvalidArgumentError,
    MalformedDataError,
    MissingDataError,
    UnknownScanError,
    UnknownViewpointError,
    did_you_mean,
)
from havln_mj.scene.navgraph import NavGraph
from havln_mj.tasks.episodes import REL_POSITIONS, Dataset, Episode, HumanOnPath

SPLITS = ("train", "val_seen", "val_unseen", "test")
PREFIXES = ("R2R", "HA")  # file stems as distributed: R2R_<split>.json, HA_<split>.json
DATA_ENV = "HAVLN_VLN_DATA"
# HA-R2R key names; the order is the files' own and the one ``write_dataset`` uses.
_HUMAN, _REL_DESC, _CRUX = "human", "Relative Position Description", "crux_points"
_KEYS = ("distance", "scan", "path_id", "path", "heading", "instructions", _HUMAN, _REL_DESC, _CRUX)
_HUMAN_KEYS = ("human_viewpoint", "human_rel_pos", "human_description")


# ---------------------------------------------------------------------- file names


def resolve_dataset_path(name: str | Path, data_dir: str | Path | None = None) -> Path:
    """The file of a dataset given as a path or a split name.

    Split names are ``<split>`` (R2R), ``R2R_<split>`` or ``HA_<split>`` with ``<split>`` one of
    :data:`SPLITS`; the file ``<name>.json`` is looked for in ``data_dir`` (default
    ``$HAVLN_VLN_DATA``) and its ``r2r/`` and ``ha_r2r/`` subfolders.

    Raises:
        MissingDataError: The file does not exist; the message lists where it looked.
        InvalidArgumentError: ``name`` is neither an existing file nor a split name.
    """
    path = Path(name).expanduser()
    if path.is_file():
        return path
    text = str(name)
    if os.sep in text or text.endswith(".json"):
        raise MissingDataError(f"dataset file not found: {path}")
    stem = text if text.split("_", 1)[0] in PREFIXES else f"R2R_{text}"
    prefix, _, split = stem.partition("_")
    if split not in SPLITS:
        names = [f"{p}_{s}" for p in PREFIXES for s in SPLITS] + list(SPLITS)
        raise InvalidArgumentError(
            f"{text!r} is neither a file nor a split name; valid names: {', '.join(names)}."
            f"{did_you_mean(text, names)}"
        )
    root = data_dir if data_dir is not None else os.environ.get(DATA_ENV)
    if root is None:
        raise MissingDataError(
            f"split {text!r} needs a data folder: pass data_dir or set ${DATA_ENV} to the folder "
            f"holding {stem}.json (or its r2r/ and ha_r2r/ subfolders)"
        )
    root = Path(root).expanduser()
    sub = "ha_r2r" if prefix == "HA" else "r2r"
    tried = [root / f"{stem}.json", root / sub / f"{stem}.json"]
    for candidate in tried:
        if candidate.is_file():
            return candidate
    raise MissingDataError(
        f"split {text!r} not found; looked for {', '.join(str(p) for p in tried)}"
    )


# ---------------------------------------------------------------------- parsing


def _fail(where: str, msg: str) -> MalformedDataError:
    return MalformedDataError(f"{where}: {msg}")


def _str(obj: Any, key: str, where: str) -> str:
    value = obj.get(key)
    if not isinstance(value, str) or not value:
        raise _fail(where, f"{key!r} must be a non-empty string, got {value!r}")
    return value


def _str_list(obj: Any, key: str, where: str, *, allow_empty: bool = False) -> tuple[str, ...]:
    value = obj.get(key)
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise _fail(where, f"{key!r} must be a list of strings, got {value!r}")
    if not value and not allow_empty:
        raise _fail(where, f"{key!r} must not be empty")
    return tuple(value)


def _number(obj: Any, key: str, where: str) -> float:
    value = obj.get(key)
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise _fail(where, f"{key!r} must be a finite number, got {value!r}")
    return float(value)


def _human(entry: Any, where: str) -> HumanOnPath:
    if not isinstance(entry, dict) or set(entry) != set(_HUMAN_KEYS):
        raise _fail(
            where, f"each 'human' entry needs exactly the keys {_HUMAN_KEYS}, got {entry!r}"
        )
    vp = _str(entry, "human_viewpoint", where)
    rel = entry["human_rel_pos"]
    if rel not in REL_POSITIONS:
        raise _fail(where, f"human_rel_pos {rel!r} is not one of {', '.join(REL_POSITIONS)}")
    desc = entry["human_description"]
    if not isinstance(desc, str):
        raise _fail(where, f"human_description must be a string, got {desc!r}")
    return HumanOnPath(vp, rel, desc)


def episode_from_json(obj: Any, where: str = "<memory>") -> Episode:
    """Parses one JSON object of an R2R or HA-R2R file.

    Args:
        obj: The decoded object.
        where: The file and entry, for messages.

    Raises:
        MalformedDataError: The object does not follow the schema.
    """
    if not isinstance(obj, dict):
        raise _fail(where, f"expected a JSON object, got {type(obj).__name__}")
    path_id = obj.get("path_id")
    if isinstance(path_id, bool) or not isinstance(path_id, int):
        raise _fail(where, f"'path_id' must be an integer, got {path_id!r}")
    where = f"{where} (path_id {path_id})"
    humans = obj.get(_HUMAN)
    if humans is not None:
        if not isinstance(humans, list):
            raise _fail(where, f"'human' must be a list, got {humans!r}")
        humans = tuple(_human(h, where) for h in humans)
    return Episode(
        path_id=path_id,
        scan=_str(obj, "scan", where),
        path=_str_list(obj, "path", where),
        heading=_number(obj, "heading", where),
        instructions=_str_list(obj, "instructions", where, allow_empty=True),
        distance=_number(obj, "distance", where) if "distance" in obj else None,
        humans=humans,
        crux_points=_str_list(obj, _CRUX, where, allow_empty=True) if _CRUX in obj else None,
        rel_pos_descriptions=(
            _str_list(obj, _REL_DESC, where, allow_empty=True) if _REL_DESC in obj else None
        ),
        extra={k: v for k, v in obj.items() if k not in _KEYS},
    )


def episode_to_json(episode: Episode) -> dict[str, Any]:
    """The episode as a JSON object of its file's schema (keys in the files' order)."""
    e = episode
    out: dict[str, Any] = {}
    if e.distance is not None:
        out["distance"] = e.distance
    out |= {
        "scan": e.scan,
        "path_id": e.path_id,
        "path": list(e.path),
        "heading": e.heading,
        "instructions": list(e.instructions),
    }
    if e.humans is not None:
        out[_HUMAN] = [
            dict(zip(_HUMAN_KEYS, (h.viewpoint, h.rel_pos, h.description), strict=True))
            for h in e.humans
        ]
    if e.rel_pos_descriptions is not None:
        out[_REL_DESC] = list(e.rel_pos_descriptions)
    if e.crux_points is not None:
        out[_CRUX] = list(e.crux_points)
    out.update(e.extra)
    return out


# ---------------------------------------------------------------------- validation


class _Graphs:
    """Connectivity graphs of one folder, loaded on first use."""

    def __init__(self, folder: Path) -> None:
        if not folder.is_dir():
            raise MissingDataError(f"connectivity folder not found: {folder}")
        self.folder = folder
        self._graphs: dict[str, NavGraph] = {}

    def get(self, scan: str, where: str) -> NavGraph:
        graph = self._graphs.get(scan)
        if graph is None:
            path = self.folder / f"{scan}_connectivity.json"
            if not path.is_file():
                known = sorted(
                    p.name.removesuffix("_connectivity.json")
                    for p in self.folder.glob("*_connectivity.json")
                )
                raise UnknownScanError(
                    f"{where}: unknown scan {scan!r}, no {path.name} in {self.folder}."
                    f"{did_you_mean(scan, known)}"
                )
            graph = self._graphs[scan] = NavGraph.from_file(path)
        return graph


def _check_viewpoint(
    graph: NavGraph, vp: str, what: str, where: str, *, included: bool = True
) -> None:
    if vp in graph or (not included and vp in graph.ids):
        return
    if vp in graph.ids:
        raise UnknownViewpointError(
            f"{where}: {what} {vp!r} is an excluded viewpoint of scan {graph.name} "
            "(an overlapping duplicate the simulator never uses)"
        )
    raise UnknownViewpointError(
        f"{where}: {what} {vp!r} is not a viewpoint of scan {graph.name}."
        f"{did_you_mean(vp, graph.ids if not included else graph.nodes)}"
    )


def validate_episode(episode: Episode, graph: NavGraph, where: str = "<memory>") -> None:
    """Checks an episode against its scan's graph.

    Every path viewpoint and crux point must be an included viewpoint, every person's
    viewpoint a viewpoint of the scan, and consecutive path viewpoints must be joined by an
    edge.

    Raises:
        UnknownViewpointError: A viewpoint is unknown or excluded (with the nearest id).
        MalformedDataError: Two consecutive path viewpoints are not neighbours.
    """
    where = f"{where} (path_id {episode.path_id})"
    for i, vp in enumerate(episode.path):
        _check_viewpoint(graph, vp, f"path[{i}]", where)
    for i, vp in enumerate(episode.crux_points or ()):
        _check_viewpoint(graph, vp, f"crux_points[{i}]", where)
    for i, h in enumerate(episode.humans or ()):
        # HA3D placed some people on excluded viewpoints: they need only exist.
        _check_viewpoint(graph, h.viewpoint, f"human[{i}].human_viewpoint", where, included=False)
    try:
        graph.path_length(episode.path)
    except InvalidArgumentError as exc:
        raise MalformedDataError(f"{where}: {exc}") from None


# ---------------------------------------------------------------------- files


def read_episodes(path: str | Path) -> list[Episode]:
    """Reads and parses an R2R or HA-R2R file (schema checks only).

    Raises:
        MissingDataError: The file does not exist.
        MalformedDataError: It is not JSON or does not follow the schema.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise MissingDataError(f"dataset file not found: {path}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise MalformedDataError(f"{path}: not valid JSON ({exc})") from None
    if not isinstance(data, list):
        raise MalformedDataError(f"{path}: expected a JSON array of paths")
    return [episode_from_json(obj, f"{path}[{i}]") for i, obj in enumerate(data)]


def load_dataset(
    path_or_split: str | Path,
    *,
    connectivity_dir: str | Path | None = None,
    data_dir: str | Path | None = None,
    validate: bool = True,
) -> Dataset:
    """Loads an R2R or HA-R2R file, by path or split name.

    Args:
        path_or_split: A file, or a split name (see :func:`resolve_dataset_path`).
        connectivity_dir: Folder of ``<scan>_connectivity.json``; when given (and ``validate``)
            every episode is checked against its scan's graph.
        data_dir: Where split names are looked up (default ``$HAVLN_VLN_DATA``).
        validate: Whether to check episodes against the graphs.

    Raises:
        MissingDataError: The file (or the connectivity folder) does not exist.
        MalformedDataError: The file breaks the schema, or a path step is not an edge.
        UnknownScanError: An episode's scan has no graph in ``connectivity_dir``.
        UnknownViewpointError: A viewpoint is not in its scan's graph.
    """
    path = resolve_dataset_path(path_or_split, data_dir)
    episodes = read_episodes(path)
    if validate and connectivity_dir is not None:
        graphs = _Graphs(Path(connectivity_dir).expanduser())
        for i, e in enumerate(episodes):
            where = f"{path}[{i}]"
            validate_episode(e, graphs.get(e.scan, f"{where} (path_id {e.path_id})"), where)
    return Dataset(episodes, str(path))


def write_dataset(
    episodes: Iterable[Episode], path: str | Path, *, indent: int | None = None
) -> None:
    """Writes episodes in the R2R / HA-R2R schema, atomically.

    Args:
        episodes: The episodes (a ``Dataset`` or any iterable).
        path: The output file.
        indent: JSON indentation (None: one line, as HA-R2R; R2R files use 2).
    """
    atomic_write_json(Path(path), [episode_to_json(e) for e in episodes], indent=indent)
