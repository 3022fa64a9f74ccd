"""Static collision for buildings: CoACD convex decomposition with an on-disk cache.

MuJoCo collides a mesh geom through its convex hull, so a non-convex building mesh (a
procedural house, a Matterport scan) is split into convex pieces with CoACD first. CoACD takes
tens of seconds per house, so :func:`decompose` caches its result under
``cache_dir("hulls")``, keyed by the mesh content, the parameters, the CoACD version and
:data:`SCHEMA_VERSION`. The CoACD settings are :class:`~havln_mj.scene.coacd_params.CoacdParams`
(importable from here too).

Cache file format (``<key>.npz``, written with ``np.savez``, read with ``allow_pickle=False``):

* ``schema``: int64 scalar, :data:`SCHEMA_VERSION`.
* ``key``: unicode scalar, the 64-hex-digit key (must match the file name).
* ``vertices``: float64 ``(sum V_i, 3)``, every hull's vertices, hull after hull.
* ``faces``: int32 ``(sum F_i, 3)``, every hull's triangles, indices local to their hull.
* ``vertex_offsets``, ``face_offsets``: int64 ``(H + 1,)``, hull ``i`` owns rows
  ``offsets[i]:offsets[i + 1]``; both start at 0 and end at the row count.

Entries are written atomically (temporary file and rename). An entry that cannot be read or
fails these checks is logged, deleted and recomputed.
"""

from __future__ import annotations

import hashlib
import io
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from havln_mj.cache import atomic_write_bytes
from havln_mj.errors import CorruptMeshError, InvalidArgumentError, MalformedDataError
from havln_mj.paths import cache_dir
from havln_mj.scene.coacd_params import CoacdParams, coacd_version

if TYPE_CHECKING:
    import trimesh

logger = logging.getLogger(__name__)

#: Bumped whenever the cache file layout or the hull post-processing changes.
SCHEMA_VERSION = 1

_ARRAYS = ("schema", "key", "vertices", "faces", "vertex_offsets", "face_offsets")
# A hull whose vertices span less than this fraction of its extent in some direction is flat.
_FLAT_TOL = 1e-9


@dataclass(frozen=True, eq=False)
class Hull:
    """One convex piece, ready for a MuJoCo mesh asset (``uservert`` / ``userface``).

    Attributes:
        vertices: float64 ``(V, 3)``, V >= 4 and not all coplanar; read-only.
        faces: int32 ``(F, 3)`` triangles indexing ``vertices``; read-only.
    """

    vertices: np.ndarray
    faces: np.ndarray

    def __post_init__(self) -> None:
        """Stores read-only contiguous copies with the documented dtypes."""
        v = np.array(self.vertices, dtype=np.float64, order="C").reshape(-1, 3)
        f = np.array(self.faces, dtype=np.int32, order="C").reshape(-1, 3)
        v.setflags(write=False)
        f.setflags(write=False)
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "faces", f)


def hull_cache_key(mesh: trimesh.Trimesh, params: CoacdParams | None = None) -> str:
    """Returns the cache key (sha256 hex) of ``mesh`` decomposed with ``params``.

    Raises:
        CorruptMeshError: The mesh is empty, has no faces, or has non-finite vertices.
        InvalidArgumentError: ``mesh`` or ``params`` has the wrong type.
    """
    vertices, faces = _checked_arrays(mesh)
    return _key(vertices, faces, _checked_params(params))


def hull_cache_path(mesh: trimesh.Trimesh, params: CoacdParams | None = None) -> Path:
    """Returns where :func:`decompose` caches ``mesh`` decomposed with ``params``.

    Raises:
        CorruptMeshError: The mesh is empty, has no faces, or has non-finite vertices.
        InvalidArgumentError: ``mesh`` or ``params`` has the wrong type.
    """
    return cache_dir("hulls") / f"{hull_cache_key(mesh, params)}.npz"


def decompose(
    mesh: trimesh.Trimesh, params: CoacdParams | None = None, *, cache: bool = True
) -> list[Hull]:
    """Splits a (non-convex) mesh into convex hulls with CoACD, cached on disk.

    Args:
        mesh: The triangle mesh, in metres. Need not be watertight (CoACD remeshes it).
        params: CoACD settings; ``CoacdParams()`` when omitted.
        cache: Read and write the on-disk cache. With False, CoACD always runs and nothing is
            read or written.

    Returns:
        The hulls, each with at least 4 non-coplanar vertices. Identical for identical input.

    Raises:
        CorruptMeshError: The mesh is empty, has no faces, has non-finite vertices or face
            indices out of range, or CoACD finds no solid piece in it.
        InvalidArgumentError: ``mesh`` or ``params`` has the wrong type.
    """
    params = _checked_params(params)
    vertices, faces = _checked_arrays(mesh)
    if not cache:
        return _run_coacd(vertices, faces, params)

    key = _key(vertices, faces, params)
    path = cache_dir("hulls") / f"{key}.npz"
    if path.exists():
        try:
            return _load(path, key)
        except Exception as exc:  # any unreadable entry is recomputed, never raised
            logger.warning("corrupt hull cache entry %s (%s); recomputing", path, exc)
            try:
                path.unlink(missing_ok=True)
            except OSError as unlink_exc:  # e.g. a folder in its place; the write will say more
                logger.warning("could not delete %s: %s", path, unlink_exc)

    hulls = _run_coacd(vertices, faces, params)
    try:
        atomic_write_bytes(path, _dump(hulls, key))
    except OSError as exc:  # an unwritable cache costs time, not correctness
        logger.warning("could not write hull cache entry %s: %s", path, exc)
    return hulls


def _checked_params(params: CoacdParams | None) -> CoacdParams:
    if params is None:
        return CoacdParams()
    if not isinstance(params, CoacdParams):
        raise InvalidArgumentError(f"params must be a CoacdParams, got {type(params).__name__}")
    return params


def _checked_arrays(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    """Returns (float64 vertices, int64 faces) of a usable mesh, or raises CorruptMeshError."""
    import trimesh  # a large import: only when meshes are decomposed

    if not isinstance(mesh, trimesh.Trimesh):
        raise InvalidArgumentError(f"mesh must be a trimesh.Trimesh, got {type(mesh).__name__}")
    vertices = np.ascontiguousarray(mesh.vertices, dtype=np.float64)
    faces = np.ascontiguousarray(mesh.faces, dtype=np.int64)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or len(vertices) == 0:
        raise CorruptMeshError(f"mesh has no vertices (vertices shape {vertices.shape})")
    if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0:
        raise CorruptMeshError(f"mesh has no triangle faces (faces shape {faces.shape})")
    bad = ~np.isfinite(vertices).all(axis=1)
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        raise CorruptMeshError(
            f"mesh has {int(bad.sum())} non-finite vertices (first: index {first}, "
            f"{vertices[first].tolist()}); all coordinates must be finite"
        )
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise CorruptMeshError(
            f"mesh face indices span {int(faces.min())}..{int(faces.max())}; valid: "
            f"0..{len(vertices) - 1}"
        )
    return vertices, faces


def _key(vertices: np.ndarray, faces: np.ndarray, params: CoacdParams) -> str:
    h = hashlib.sha256()
    for part in (
        f"havln_mj.hulls/{SCHEMA_VERSION}".encode(),
        f"coacd/{coacd_version()}".encode(),
        params.to_json().encode(),
        np.asarray(vertices.shape, dtype="<i8").tobytes(),
        vertices.astype("<f8", order="C", copy=False).tobytes(),
        np.asarray(faces.shape, dtype="<i8").tobytes(),
        faces.astype("<i8", order="C", copy=False).tobytes(),
    ):
        h.update(len(part).to_bytes(8, "little"))  # length prefix: no ambiguous concatenation
        h.update(part)
    return h.hexdigest()


def _run_coacd(vertices: np.ndarray, faces: np.ndarray, params: CoacdParams) -> list[Hull]:
    import coacd

    kwargs = params.coacd_kwargs()
    if len(vertices) >= 2**31:
        raise CorruptMeshError(f"mesh has {len(vertices)} vertices; CoACD takes at most 2**31 - 1")
    if hasattr(coacd, "set_log_level"):
        coacd.set_log_level("info" if logger.isEnabledFor(logging.DEBUG) else "error")
    logger.debug("running CoACD on %d vertices / %d faces: %s", len(vertices), len(faces), kwargs)
    parts = coacd.run_coacd(coacd.Mesh(vertices, faces.astype(np.int32)), **kwargs)
    hulls = []
    for i, (v, f) in enumerate(parts):
        hull = _clean_hull(np.asarray(v, dtype=np.float64), np.asarray(f, dtype=np.int64))
        if hull is None:
            logger.debug("dropping degenerate CoACD piece %d (%d vertices)", i, len(v))
        else:
            hulls.append(hull)
    if not hulls:
        raise CorruptMeshError(
            f"CoACD found no solid piece in the mesh ({len(vertices)} vertices, {len(faces)} "
            f"faces, {len(parts)} raw pieces); is it flat or degenerate?"
        )
    return hulls


def _clean_hull(vertices: np.ndarray, faces: np.ndarray) -> Hull | None:
    """Returns the piece as a Hull, or None if MuJoCo could not build a hull from it."""
    if vertices.ndim != 2 or vertices.shape[1] != 3 or len(vertices) < 4:
        return None
    if not np.isfinite(vertices).all():
        return None
    if faces.ndim != 2 or faces.shape[1] != 3 or faces.min(initial=0) < 0:
        return None
    if faces.max(initial=-1) >= len(vertices):
        return None
    # Flat pieces (all vertices on one plane or line) have no volume: the smallest singular
    # value of the centred vertex cloud must be a non-negligible fraction of the largest.
    s = np.linalg.svd(vertices - vertices.mean(axis=0), compute_uv=False)
    if s[0] <= 0 or s[2] <= _FLAT_TOL * s[0]:
        return None
    return Hull(vertices, faces)


def _dump(hulls: list[Hull], key: str) -> bytes:
    """Serialises hulls in the documented npz layout."""
    v_off = np.cumsum([0] + [len(h.vertices) for h in hulls], dtype=np.int64)
    f_off = np.cumsum([0] + [len(h.faces) for h in hulls], dtype=np.int64)
    buf = io.BytesIO()
    np.savez(
        buf,
        schema=np.int64(SCHEMA_VERSION),
        key=np.str_(key),
        vertices=np.concatenate([h.vertices for h in hulls]).astype(np.float64),
        faces=np.concatenate([h.faces for h in hulls]).astype(np.int32),
        vertex_offsets=v_off,
        face_offsets=f_off,
    )
    return buf.getvalue()


def _load(path: Path, key: str) -> list[Hull]:
    """Reads and checks a cache entry.

    Raises:
        MalformedDataError: (or any I/O or zip error) the entry is unusable.
    """
    with np.load(path, allow_pickle=False) as data:
        missing = [name for name in _ARRAYS if name not in data.files]
        if missing:
            raise MalformedDataError(f"missing arrays {missing}")
        arrays = {name: data[name] for name in _ARRAYS}
    if arrays["schema"].shape != () or int(arrays["schema"]) != SCHEMA_VERSION:
        raise MalformedDataError(f"schema {arrays['schema']!r}, expected {SCHEMA_VERSION}")
    if arrays["key"].shape != () or str(arrays["key"]) != key:
        raise MalformedDataError("stored key does not match the file name")
    vertices, faces = arrays["vertices"], arrays["faces"]
    v_off, f_off = arrays["vertex_offsets"], arrays["face_offsets"]
    if vertices.dtype != np.float64 or vertices.ndim != 2 or vertices.shape[1] != 3:
        raise MalformedDataError(f"vertices {vertices.dtype} {vertices.shape}, want float64 (N, 3)")
    if faces.dtype != np.int32 or faces.ndim != 2 or faces.shape[1] != 3:
        raise MalformedDataError(f"faces {faces.dtype} {faces.shape}, want int32 (M, 3)")
    if not np.isfinite(vertices).all():
        raise MalformedDataError("non-finite vertices")
    for name, off, total in (("vertex", v_off, len(vertices)), ("face", f_off, len(faces))):
        if (
            off.dtype != np.int64
            or off.ndim != 1
            or len(off) != len(v_off)
            or len(off) < 2
            or off[0] != 0
            or off[-1] != total
            or (np.diff(off) < 0).any()
        ):
            raise MalformedDataError(f"inconsistent {name}_offsets {off!r} for {total} rows")
    hulls = []
    for i in range(len(v_off) - 1):
        v = vertices[v_off[i] : v_off[i + 1]]
        f = faces[f_off[i] : f_off[i + 1]]
        if len(v) < 4 or len(f) == 0 or f.min() < 0 or f.max() >= len(v):
            raise MalformedDataError(f"hull {i} has {len(v)} vertices / bad face indices")
        hulls.append(Hull(v, f))
    return hulls
