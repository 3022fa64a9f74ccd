"""Read, validate and write Matterport3DSimulator connectivity files.

A connectivity file (``<scan>_connectivity.json``) is a JSON array with one object per
viewpoint, in the order that MatterSim's ``ViewPoint.ix`` indexes::

    {"image_id": str, "pose": [16 floats], "included": bool,
     "visible": [bool x N], "unobstructed": [bool x N], "height": float}

``pose`` is a row-major 4x4 camera-to-world matrix (z up, metres); the viewpoint position is
``pose[3], pose[7], pose[11]`` and the floor lies ``height`` below it. ``visible`` and
``unobstructed`` are indexed by position in the file. Reading is strict: any deviation from
this schema raises ``MalformedDataError`` naming the file, the entry, the field and what was
expected. Writing is deterministic: the same data always gives the same bytes.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from havln_mj.cache import atomic_write_bytes
from havln_mj.errors import InvalidArgumentError, MalformedDataError, MissingDataError

# Field names in the order MatterSim writes them; ``dumps_connectivity`` keeps this order.
FIELDS = ("image_id", "pose", "included", "visible", "unobstructed", "height")
# Decimals kept for poses and heights when writing (the MatterSim files hold 6 significant
# digits, so this loses nothing they carry while hiding float noise below 1e-6).
DEFAULT_DECIMALS = 6
_SUFFIX = "_connectivity.json"
# Geometry a file must have: metres in a building's frame (the 90 MatterSim graphs lie within
# ±75 m, camera heights 0.04–8.1 m), rigid poses (their rotations are orthonormal to 6e-6).
MAX_COORDINATE_M = 10_000.0
MAX_HEIGHT_M = 100.0
_ROTATION_TOL = 1e-3
# What a scene can be built from: the 90 graphs span at most 81 m across and 14 m up.
MAX_EXTENT_M = 300.0
MAX_RISE_M = 100.0
MIN_EXTENT_M = 0.01


@dataclass(frozen=True, eq=False)
class Connectivity:
    """One scan's viewpoints and their pairwise flags, as read from a connectivity file.

    Arrays are copied on construction and made read-only. Index ``i`` of every array is the
    ``i``-th entry of the file (MatterSim's ``ViewPoint.ix``).

    Attributes:
        ids: Viewpoint ids (``image_id``) in file order, N of them.
        poses: (N, 4, 4) float64 camera-to-world matrices.
        included: (N,) bool; False for the overlapping duplicates the simulator skips.
        visible: (N, N) bool; ``visible[i, j]``: j can be seen from i (MatterSim ignores it).
        unobstructed: (N, N) bool; ``unobstructed[i, j]``: the agent may move from i to j.
        heights: (N,) float64 camera height above the floor, metres.
        source: Where the data came from (a file path or ``"<memory>"``), used in messages.
    """

    ids: tuple[str, ...]
    poses: np.ndarray
    included: np.ndarray
    visible: np.ndarray
    unobstructed: np.ndarray
    heights: np.ndarray
    source: str = "<memory>"

    def __post_init__(self) -> None:
        ids = tuple(self.ids)
        n = len(ids)
        if not all(isinstance(i, str) and i for i in ids):
            raise InvalidArgumentError(f"{self.source}: ids must be non-empty strings")
        if len(set(ids)) != n:
            raise InvalidArgumentError(f"{self.source}: ids must be unique")
        expected = {
            "poses": ((n, 4, 4), np.float64),
            "included": ((n,), np.bool_),
            "visible": ((n, n), np.bool_),
            "unobstructed": ((n, n), np.bool_),
            "heights": ((n,), np.float64),
        }
        object.__setattr__(self, "ids", ids)
        for name, (shape, dtype) in expected.items():
            arr = np.array(getattr(self, name), dtype=dtype, copy=True)
            if arr.shape != shape:
                raise InvalidArgumentError(
                    f"{self.source}: {name} has shape {arr.shape}, expected {shape} "
                    f"for {n} viewpoints"
                )
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)

    def __len__(self) -> int:
        return len(self.ids)

    @property
    def scan(self) -> str:
        """The scan id when ``source`` is a ``<scan>_connectivity.json`` path, else ``source``."""
        name = Path(self.source).name
        return name[: -len(_SUFFIX)] if name.endswith(_SUFFIX) else self.source

    @property
    def positions(self) -> np.ndarray:
        """Viewpoint positions ``pose[3], pose[7], pose[11]``, shape ``(N, 3)``."""
        return self.poses[:, :3, 3].copy()

    @property
    def floor_z(self) -> np.ndarray:
        """Floor height under each viewpoint (position z minus ``height``), shape ``(N,)``."""
        return self.poses[:, 2, 3] - self.heights


def read_connectivity(path: str | Path) -> Connectivity:
    """Reads and validates a MatterSim connectivity file.

    Args:
        path: A ``<scan>_connectivity.json`` file.

    Returns:
        The validated ``Connectivity``, with ``source`` set to ``path``.

    Raises:
        MissingDataError: The file does not exist or is not a regular file.
        MalformedDataError: The file is not valid UTF-8 JSON or does not follow the schema.
    """
    path = Path(path)
    if not path.is_file():
        what = "is a folder, not a file" if path.is_dir() else "not found"
        raise MissingDataError(f"connectivity file {what}: {path}")
    try:
        data = json.loads(path.read_bytes().decode("utf-8"))
    except UnicodeDecodeError as e:
        raise MalformedDataError(f"{path}: not UTF-8 text (byte {e.start})") from e
    except json.JSONDecodeError as e:
        raise MalformedDataError(
            f"{path}: invalid JSON at line {e.lineno} column {e.colno} (char {e.pos}): {e.msg}"
        ) from e
    return parse_connectivity(data, str(path))


def parse_connectivity(data: Any, source: str = "<memory>") -> Connectivity:
    """Validates decoded connectivity JSON and converts it to arrays.

    Args:
        data: The decoded JSON (a list of viewpoint objects).
        source: Name of the data's origin (usually the file path), used in error messages.

    Returns:
        The validated ``Connectivity``.

    Raises:
        MalformedDataError: ``data`` does not follow the schema; the message names the source,
            the entry index, the field and what was expected.
    """
    if not isinstance(data, list):
        raise MalformedDataError(
            f"{source}: expected a JSON array of viewpoint objects, got {_json_type(data)}"
        )
    n = len(data)
    ids: list[str] = []
    seen: dict[str, int] = {}
    poses, included, visible, unobstructed, heights = [], [], [], [], []
    for i, entry in enumerate(data):
        vp = _check_entry(entry, f"{source}: entry {i}")
        where = f"{source}: entry {i} (image_id {vp!r})"
        if vp in seen:
            raise MalformedDataError(
                f"{where}: duplicate image_id, already used by entry {seen[vp]}"
            )
        seen[vp] = i
        ids.append(vp)
        _check_values(entry, where, n)
        poses.append(entry["pose"])
        included.append(entry["included"])
        visible.append(entry["visible"])
        unobstructed.append(entry["unobstructed"])
        heights.append(entry["height"])

    pose_array = np.array(poses, dtype=np.float64).reshape(n, 4, 4)
    height_array = np.array(heights, dtype=np.float64)
    _check_geometry(pose_array, height_array, ids, source)
    return Connectivity(
        ids=tuple(ids),
        poses=pose_array,
        included=np.array(included, dtype=bool),
        visible=_bool_matrix(visible, "visible", ids, source),
        unobstructed=_bool_matrix(unobstructed, "unobstructed", ids, source),
        heights=height_array,
        source=source,
    )


def _check_entry(entry: Any, where: str) -> str:
    """The entry's image_id, once it is an object with exactly the schema's fields."""
    if not isinstance(entry, dict):
        raise MalformedDataError(f"{where}: expected an object, got {_json_type(entry)}")
    missing = [f for f in FIELDS if f not in entry]
    if missing:
        raise MalformedDataError(
            f"{where}: missing field(s) {', '.join(missing)}; expected {', '.join(FIELDS)}"
        )
    extra = [k for k in entry if k not in FIELDS]
    if extra:
        raise MalformedDataError(
            f"{where}: unexpected field(s) {', '.join(map(repr, extra))}; "
            f"expected exactly {', '.join(FIELDS)}"
        )
    vp = entry["image_id"]
    if not isinstance(vp, str) or not vp:
        raise MalformedDataError(f"{where}: image_id must be a non-empty string, got {vp!r}")
    return vp


def _check_values(entry: dict, where: str, n: int) -> None:
    """Raises for the entry's first pose, flag, row or height of the wrong type or size."""
    pose = entry["pose"]
    if not isinstance(pose, list) or len(pose) != 16:
        got = f"{len(pose)}" if isinstance(pose, list) else _json_type(pose)
        raise MalformedDataError(f"{where}: pose must be 16 numbers, got {got}")
    for k, v in enumerate(pose):
        if not _is_finite_number(v):
            raise MalformedDataError(f"{where}: pose[{k}] must be a finite number, got {v!r}")
    flag = entry["included"]
    if not isinstance(flag, bool):
        raise MalformedDataError(f"{where}: included must be true or false, got {flag!r}")
    for name in ("visible", "unobstructed"):
        row = entry[name]
        if not isinstance(row, list):
            raise MalformedDataError(
                f"{where}: {name} must be an array of {n} booleans, got {_json_type(row)}"
            )
        if len(row) != n:
            raise MalformedDataError(
                f"{where}: {name} has {len(row)} entries, expected {n} (one per viewpoint)"
            )
    height = entry["height"]
    if not _is_finite_number(height):
        raise MalformedDataError(f"{where}: height must be a finite number, got {height!r}")


def _check_geometry(poses: np.ndarray, heights: np.ndarray, ids: list[str], source: str) -> None:
    """Raises for the first viewpoint whose pose is not rigid, lies too far, or has no height."""
    if not len(ids):
        return
    rot = poses[:, :3, :3]
    rigid = (
        np.all(np.abs(rot @ rot.transpose(0, 2, 1) - np.eye(3)) <= _ROTATION_TOL, axis=(1, 2))
        & (np.abs(np.linalg.det(rot) - 1.0) <= _ROTATION_TOL)
        & np.all(poses[:, 3] == (0.0, 0.0, 0.0, 1.0), axis=1)
    )
    near = np.all(np.abs(poses[:, :3, 3]) <= MAX_COORDINATE_M, axis=1)
    tall = (heights > 0.0) & (heights <= MAX_HEIGHT_M)
    bad = np.flatnonzero(~(rigid & near & tall))
    if not len(bad):
        return
    i = int(bad[0])
    where = f"{source}: entry {i} (image_id {ids[i]!r})"
    if not rigid[i]:
        raise MalformedDataError(
            f"{where}: pose must be a rigid camera-to-world transform (an orthonormal "
            f"rotation with determinant 1 and a last row 0 0 0 1), got "
            f"{poses[i].ravel().tolist()}"
        )
    if not near[i]:
        raise MalformedDataError(
            f"{where}: position {poses[i, :3, 3].tolist()} m lies outside "
            f"±{MAX_COORDINATE_M:g} m; positions are metres in the building's frame"
        )
    raise MalformedDataError(
        f"{where}: height must be a camera height above the floor in (0, {MAX_HEIGHT_M:g}] "
        f"m, got {float(heights[i])!r}"
    )


def check_buildable(c: Connectivity) -> None:
    """Checks that a scene can be built around a graph: a building's worth of viewpoints.

    Raises:
        MalformedDataError: Fewer than two included viewpoints, no edge between them, all of
            them at one point, or spread wider or higher than a building (the message gives
            the numbers and the limits).
    """
    inc = np.flatnonzero(c.included)
    where = f"{c.source}: cannot build a scene from this graph"
    if len(inc) < 2:
        raise MalformedDataError(
            f"{where}: it has {len(inc)} included viewpoint(s) of {len(c)}; at least 2 are needed"
        )
    flags = c.unobstructed[np.ix_(inc, inc)].copy()
    np.fill_diagonal(flags, False)
    if not flags.any():
        raise MalformedDataError(
            f"{where}: no edge joins its {len(inc)} included viewpoints (every 'unobstructed' "
            "flag between them is false)"
        )
    pos = c.positions[inc]
    span = np.ptp(pos, axis=0)
    if float(np.max(span)) < MIN_EXTENT_M:
        raise MalformedDataError(
            f"{where}: all {len(inc)} included viewpoints stand at one point {pos[0].tolist()}"
        )
    if float(np.max(span[:2])) > MAX_EXTENT_M or float(span[2]) > MAX_RISE_M:
        raise MalformedDataError(
            f"{where}: its viewpoints span {span[0]:.1f} × {span[1]:.1f} m and {span[2]:.1f} m "
            f"up; a building spans at most {MAX_EXTENT_M:g} m across and {MAX_RISE_M:g} m up"
        )


def dumps_connectivity(c: Connectivity, decimals: int = DEFAULT_DECIMALS) -> str:
    """Serialises a ``Connectivity`` in the exact MatterSim schema, on a single line.

    The output is deterministic: keys in MatterSim's order (``image_id, pose, included,
    visible, unobstructed, height``), no spaces, poses and heights rounded to ``decimals``
    places (and ``-0.0`` written as ``0.0``), so float noise smaller than the rounding step
    does not change the bytes.

    Args:
        c: The connectivity to write.
        decimals: Decimal places kept for ``pose`` and ``height`` values.

    Returns:
        The JSON text (no trailing newline, like the MatterSim files).
    """
    poses = c.poses.reshape(len(c), 16)
    entries = [
        {
            "image_id": vp,
            "pose": [_round(v, decimals) for v in poses[i].tolist()],
            "included": bool(c.included[i]),
            "visible": c.visible[i].tolist(),
            "unobstructed": c.unobstructed[i].tolist(),
            "height": _round(float(c.heights[i]), decimals),
        }
        for i, vp in enumerate(c.ids)
    ]
    return json.dumps(entries, separators=(",", ":"), allow_nan=False)


def write_connectivity(path: str | Path, c: Connectivity, decimals: int = DEFAULT_DECIMALS) -> None:
    """Writes ``c`` to ``path`` atomically, in the format of ``dumps_connectivity``.

    Args:
        path: Destination file; its folder is created if needed.
        c: The connectivity to write.
        decimals: Decimal places kept for ``pose`` and ``height`` values.
    """
    atomic_write_bytes(Path(path), dumps_connectivity(c, decimals).encode("utf-8"))


def _round(value: float, decimals: int) -> float:
    # Adding 0.0 turns -0.0 into 0.0, so noise around zero cannot flip the sign in the text.
    return round(value, decimals) + 0.0


def _is_finite_number(value: Any) -> bool:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:  # an integer too large for a float
        return False


def _bool_matrix(rows: list[list[Any]], name: str, ids: list[str], source: str) -> np.ndarray:
    """Stacks rows already checked to be N long into an (N, N) bool array, or raises."""
    n = len(rows)
    # Converting the whole matrix at once is much faster than checking each element: only
    # rows holding nothing but JSON booleans become a 2-D bool array.
    try:
        matrix = np.array(rows) if n else np.zeros((0, 0), dtype=bool)
    except ValueError:  # ragged nesting, e.g. an array inside a row
        matrix = None
    if matrix is not None and matrix.dtype == np.bool_ and matrix.shape == (n, n):
        return matrix
    for i, row in enumerate(rows):
        for j, v in enumerate(row):
            if not isinstance(v, bool):
                raise MalformedDataError(
                    f"{source}: entry {i} (image_id {ids[i]!r}): {name}[{j}] must be true or "
                    f"false, got {v!r}"
                )
    raise AssertionError(f"{name} rows hold only booleans but did not stack")  # unreachable


def _json_type(value: Any) -> str:
    names = {dict: "an object", list: "an array", str: "a string", bool: "a boolean"}
    if value is None:
        return "null"
    for cls, name in names.items():
        if isinstance(value, cls):
            return name
    return "a number" if isinstance(value, int | float) else type(value).__name__
