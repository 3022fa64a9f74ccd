"""CoACD decomposition of building meshes: hull validity, cache, corruption recovery, MuJoCo."""

from __future__ import annotations

import io
import logging
from pathlib import Path

import coacd
import mujoco
import numpy as np
import pytest
import trimesh
from scipy.spatial import ConvexHull

from havln_mj.errors import CorruptMeshError, InvalidArgumentError
from havln_mj.scene import collision
from havln_mj.scene.collision import (
    CoacdParams,
    Hull,
    decompose,
    hull_cache_key,
    hull_cache_path,
)

# Small search so every decomposition takes well under a second on 2 cores.
FAST = CoacdParams(
    preprocess_resolution=20, resolution=500, mcts_nodes=10, mcts_iterations=20, mcts_max_depth=2
)


def l_prism() -> trimesh.Trimesh:
    """A watertight L-shaped block: [0,2]x[0,1] plus [0,1]x[1,2] in xy, 1 m tall (volume 3)."""
    poly = np.array([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)], dtype=float)
    n = len(poly)
    vertices = np.vstack([np.c_[poly, np.zeros(n)], np.c_[poly, np.ones(n)]])
    faces = []
    for i in range(1, n - 1):  # the L is star-shaped from vertex 0: fan the caps from it
        faces += [(0, i + 1, i), (n, n + i, n + i + 1)]
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, n + j), (i, n + j, n + i)]
    mesh = trimesh.Trimesh(vertices, faces)
    mesh.fix_normals()
    assert mesh.is_watertight and abs(mesh.volume - 3.0) < 1e-9
    return mesh


def inside_l(p: np.ndarray) -> np.ndarray:
    x, y, z = p.T
    in_z = (z > 0) & (z < 1)
    return in_z & (
        ((x > 0) & (x < 2) & (y > 0) & (y < 1)) | ((x > 0) & (x < 1) & (y > 0) & (y < 2))
    )


def inside_any_hull(hulls: list[Hull], points: np.ndarray, tol: float = 1e-6) -> np.ndarray:
    hit = np.zeros(len(points), dtype=bool)
    for h in hulls:
        eq = ConvexHull(h.vertices).equations  # rows (n, d): n.x + d <= 0 inside
        hit |= (points @ eq[:, :3].T + eq[:, 3] <= tol).all(axis=1)
    return hit


@pytest.fixture(autouse=True)
def _own_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A fresh cache folder per test so every test starts cold."""
    monkeypatch.setenv("HAVLN_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


@pytest.fixture
def coacd_calls(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """Counts calls to coacd.run_coacd (the collision module imports coacd when it runs)."""
    calls: list[int] = []
    real = coacd.run_coacd

    def counting(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(coacd, "run_coacd", counting)
    return calls


def assert_same(a: list[Hull], b: list[Hull]) -> None:
    assert len(a) == len(b)
    for ha, hb in zip(a, b, strict=True):
        np.testing.assert_array_equal(ha.vertices, hb.vertices)
        np.testing.assert_array_equal(ha.faces, hb.faces)


# --- decomposition quality -------------------------------------------------------------------


def test_l_shape_needs_several_convex_hulls_that_cover_it() -> None:
    hulls = decompose(l_prism(), FAST)
    assert len(hulls) >= 2
    for h in hulls:
        assert h.vertices.dtype == np.float64 and h.vertices.shape[1] == 3
        assert h.faces.dtype == np.int32 and h.faces.shape[1] == 3
        assert len(h.vertices) >= 4
        # Convex: the closed surface CoACD returns encloses as much as its convex hull.
        own = trimesh.Trimesh(h.vertices, h.faces, process=True)
        hull_vol = ConvexHull(h.vertices).volume
        assert hull_vol > 0
        assert abs(abs(own.volume) - hull_vol) <= 1e-3 * hull_vol

    rng = np.random.default_rng(0)
    pts = rng.uniform((0, 0, 0), (2, 2, 1), size=(4000, 3))
    in_l = inside_l(pts)
    covered = inside_any_hull(hulls, pts)
    assert covered[in_l].mean() > 0.97  # the union covers the L ...
    assert covered[~in_l].mean() < 0.05  # ... and leaves its notch [1,2]x[1,2] open


def test_remeshed_soup_input_still_gives_valid_hulls() -> None:
    # Two overlapping boxes, not unioned: a non-manifold soup that CoACD has to remesh.
    a = trimesh.creation.box(extents=(2, 1, 1))
    a.apply_translation((1, 0.5, 0.5))
    b = trimesh.creation.box(extents=(1, 2, 1))
    b.apply_translation((0.5, 1, 0.5))
    soup = trimesh.util.concatenate([a, b])
    hulls = decompose(soup, FAST)
    assert len(hulls) >= 2
    rng = np.random.default_rng(1)
    pts = rng.uniform((0, 0, 0), (2, 2, 1), size=(4000, 3))
    in_l = inside_l(pts)
    covered = inside_any_hull(hulls, pts)
    assert covered[in_l].mean() > 0.97
    assert covered[~in_l].mean() < 0.1


def test_hull_arrays_are_read_only() -> None:
    h = Hull(np.eye(4, 3), [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]])
    assert h.vertices.dtype == np.float64 and h.faces.dtype == np.int32
    with pytest.raises(ValueError):
        h.vertices[0, 0] = 1.0


def test_degenerate_pieces_are_dropped() -> None:
    flat = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype=float)
    tet_faces = np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]])
    assert collision._clean_hull(flat, tet_faces) is None
    assert collision._clean_hull(flat[:3], tet_faces[:1]) is None
    tet = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    assert collision._clean_hull(tet, tet_faces) is not None
    nan = tet.copy()
    nan[0, 0] = np.nan
    assert collision._clean_hull(nan, tet_faces) is None


# --- cache -----------------------------------------------------------------------------------


def test_cache_miss_then_hit(coacd_calls: list[int], _own_cache: Path) -> None:
    mesh = l_prism()
    path = hull_cache_path(mesh, FAST)
    assert path.parent == _own_cache / "hulls" and not path.exists()

    first = decompose(mesh, FAST)
    assert len(coacd_calls) == 1 and path.is_file()
    second = decompose(mesh.copy(), FAST)
    assert len(coacd_calls) == 1  # served from the cache
    assert_same(first, second)


def test_cache_false_neither_reads_nor_writes(coacd_calls: list[int]) -> None:
    mesh = l_prism()
    path = hull_cache_path(mesh, FAST)
    hulls = decompose(mesh, FAST, cache=False)
    assert len(coacd_calls) == 1 and not path.exists()
    assert_same(hulls, decompose(mesh, FAST))  # seeded: the cached run matches
    assert len(coacd_calls) == 2
    decompose(mesh, FAST, cache=False)
    assert len(coacd_calls) == 3


def test_key_depends_on_mesh_and_params() -> None:
    mesh = l_prism()
    key = hull_cache_key(mesh, FAST)
    assert len(key) == 64 and hull_cache_path(mesh, FAST).name == f"{key}.npz"
    assert hull_cache_key(mesh.copy(), FAST) == key
    assert hull_cache_key(mesh, CoacdParams(**{**FAST.__dict__})) == key

    for changed in (
        CoacdParams(**{**FAST.__dict__, "threshold": 0.2}),
        CoacdParams(**{**FAST.__dict__, "real_metric": False}),
        CoacdParams(**{**FAST.__dict__, "seed": 1}),
        CoacdParams(**{**FAST.__dict__, "preprocess_resolution": 21}),
        CoacdParams(),
    ):
        assert hull_cache_key(mesh, changed) != key

    moved = mesh.copy()
    moved.apply_translation((0.001, 0, 0))
    assert hull_cache_key(moved, FAST) != key
    flipped = trimesh.Trimesh(mesh.vertices, mesh.faces[:, ::-1], process=False)
    assert hull_cache_key(flipped, FAST) != key
    assert hull_cache_key(mesh) == hull_cache_key(mesh, CoacdParams())


def _valid_npz(**arrays: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


def _corrupt(path: Path, kind: str) -> None:
    good = path.read_bytes()
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    if kind == "truncated":
        path.write_bytes(good[: len(good) // 2])
    elif kind == "empty":
        path.write_bytes(b"")
    elif kind == "garbage":
        path.write_bytes(np.random.default_rng(0).bytes(len(good)))
    elif kind == "wrong_arrays":
        path.write_bytes(_valid_npz(foo=np.arange(3), bar=np.zeros((2, 2))))
    elif kind == "bad_offsets":
        arrays["vertex_offsets"] = arrays["vertex_offsets"][::-1].copy()
        path.write_bytes(_valid_npz(**arrays))
    elif kind == "nan_vertices":
        arrays["vertices"][0, 0] = np.nan
        path.write_bytes(_valid_npz(**arrays))
    elif kind == "bad_face_index":
        arrays["faces"][0, 0] = 10_000
        path.write_bytes(_valid_npz(**arrays))
    elif kind == "old_schema":
        arrays["schema"] = np.int64(collision.SCHEMA_VERSION - 1)
        path.write_bytes(_valid_npz(**arrays))
    else:
        raise AssertionError(kind)


@pytest.mark.parametrize(
    "kind",
    [
        "truncated",
        "empty",
        "garbage",
        "wrong_arrays",
        "bad_offsets",
        "nan_vertices",
        "bad_face_index",
        "old_schema",
    ],
)
def test_corrupt_entry_is_logged_and_recomputed(
    kind: str, coacd_calls: list[int], caplog: pytest.LogCaptureFixture
) -> None:
    mesh = l_prism()
    path = hull_cache_path(mesh, FAST)
    first = decompose(mesh, FAST)
    _corrupt(path, kind)

    with caplog.at_level(logging.WARNING, logger=collision.__name__):
        again = decompose(mesh, FAST)
    assert len(coacd_calls) == 2
    assert_same(first, again)
    warnings = [r for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 1 and str(path) in warnings[0].getMessage()

    # The entry was rewritten and is valid again: the next call is a hit, without warnings.
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger=collision.__name__):
        assert_same(first, decompose(mesh, FAST))
    assert len(coacd_calls) == 2 and not caplog.records


# --- atomic writes ---------------------------------------------------------------------------


def test_no_temporary_files_after_success(_own_cache: Path) -> None:
    mesh = l_prism()
    decompose(mesh, FAST)
    assert sorted(p.name for p in (_own_cache / "hulls").iterdir()) == [
        hull_cache_path(mesh, FAST).name
    ]


def test_failed_write_leaves_nothing(
    monkeypatch: pytest.MonkeyPatch, _own_cache: Path, caplog: pytest.LogCaptureFixture
) -> None:
    mesh = l_prism()
    path = hull_cache_path(mesh, FAST)
    written: list[int] = []

    def failing_fsync(fd: int) -> None:  # the bytes are in the temp file; then the disk fails
        written.append(fd)
        raise OSError(28, "No space left on device")

    # An I/O error while writing the cache only costs the cache: the hulls still come back.
    with monkeypatch.context() as m, caplog.at_level(logging.WARNING, logger=collision.__name__):
        m.setattr("havln_mj.cache.os.fsync", failing_fsync)
        hulls = decompose(mesh, FAST)
    assert written and len(hulls) >= 2
    assert "No space left" in caplog.text
    assert not path.exists() and list((_own_cache / "hulls").iterdir()) == []

    # Any other failure during the write propagates, and still leaves nothing behind.
    def crashing_fsync(fd: int) -> None:
        raise RuntimeError("interrupted")

    with monkeypatch.context() as m:
        m.setattr("havln_mj.cache.os.fsync", crashing_fsync)
        with pytest.raises(RuntimeError, match="interrupted"):
            decompose(mesh, FAST)
    assert not path.exists() and list((_own_cache / "hulls").iterdir()) == []


# --- bad input -------------------------------------------------------------------------------


def test_bad_meshes_raise_corrupt_mesh_error() -> None:
    with pytest.raises(CorruptMeshError, match="no vertices"):
        decompose(trimesh.Trimesh())
    with pytest.raises(CorruptMeshError, match="no triangle faces"):
        decompose(trimesh.Trimesh(vertices=np.eye(3), faces=np.zeros((0, 3), int)))
    good = l_prism()
    nan = good.vertices.copy()
    nan[3] = (np.nan, 0.0, np.inf)
    with pytest.raises(CorruptMeshError, match=r"non-finite.*index 3.*nan"):
        decompose(trimesh.Trimesh(nan, good.faces, process=False))
    faces = good.faces.copy()
    faces[0, 0] = 99
    with pytest.raises(CorruptMeshError, match="99"):
        decompose(trimesh.Trimesh(good.vertices, faces, process=False, validate=False))
    with pytest.raises(InvalidArgumentError, match="ndarray"):
        decompose(np.zeros((4, 3)))  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match="str"):
        decompose(good, "fast")  # type: ignore[arg-type]


def test_flat_mesh_raises_corrupt_mesh_error() -> None:
    plane = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 1, 2], [1, 3, 2]])
    with pytest.raises(CorruptMeshError, match="no solid piece"):
        decompose(plane, CoacdParams(preprocess_mode="off", mcts_iterations=5), cache=False)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("threshold", -0.1),
        ("threshold", 0.0),
        ("threshold", float("inf")),
        ("threshold", float("nan")),
        ("max_convex_hull", 0),
        ("max_convex_hull", -2),
        ("preprocess_mode", "sometimes"),
        ("preprocess_resolution", 3),
        ("resolution", 10),
        ("mcts_nodes", 0),
        ("mcts_iterations", 1.5),
        ("mcts_max_depth", 0),
        ("max_ch_vertex", 3),
        ("extrude_margin", -1.0),
        ("apx_mode", "sphere"),
        ("seed", -1),
        ("pca", "yes"),
        ("merge", 1),
    ],
)
def test_bad_params_name_field_and_value(field: str, value: object) -> None:
    with pytest.raises(InvalidArgumentError) as info:
        CoacdParams(**{field: value})
    message = str(info.value)
    assert field in message and repr(value) in message and "valid" in message


def test_threshold_range_depends_on_units() -> None:
    assert CoacdParams(threshold=2.0, real_metric=True).threshold == 2.0  # metres
    with pytest.raises(InvalidArgumentError, match=r"threshold=2\.0.*\(0, 1\]"):
        CoacdParams(threshold=2.0, real_metric=False)  # normalised units


def test_parameters_the_installed_coacd_lacks_are_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    def old_run_coacd(mesh, threshold=0.05, preprocess_resolution=50, seed=0):  # no real_metric
        raise AssertionError("not called")

    monkeypatch.setattr(coacd, "run_coacd", old_run_coacd)
    with pytest.raises(InvalidArgumentError, match=r"real_metric=True.*upgrade coacd"):
        CoacdParams().coacd_kwargs()
    kwargs = CoacdParams(real_metric=False, threshold=0.05).coacd_kwargs()
    assert kwargs == {"threshold": 0.05, "preprocess_resolution": 50, "seed": 0}


# --- MuJoCo ----------------------------------------------------------------------------------


def compile_hulls(hulls: list[Hull]) -> tuple[mujoco.MjModel, mujoco.MjData]:
    spec = mujoco.MjSpec()
    for i, h in enumerate(hulls):
        spec.add_mesh(
            name=f"hull{i}",
            uservert=h.vertices.ravel().tolist(),
            userface=h.faces.ravel().tolist(),
        )
        spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"hull{i}")
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


def ray(model: mujoco.MjModel, data: mujoco.MjData, start, direction) -> float:
    geomid = np.array([-1], dtype=np.int32)
    vec = np.asarray(direction, dtype=float)
    return mujoco.mj_ray(model, data, np.asarray(start, float), vec, None, True, -1, geomid)


@pytest.mark.parametrize(("preprocess_mode", "tol"), [("auto", 0.01), ("on", 0.05)])
def test_hulls_load_into_mujoco_and_rays_hit_the_walls(preprocess_mode: str, tol: float) -> None:
    params = CoacdParams(**{**FAST.__dict__, "preprocess_mode": preprocess_mode})
    hulls = decompose(l_prism(), params)
    model, data = compile_hulls(hulls)
    assert model.ngeom == len(hulls)
    # From inside the notch: the inner walls x=1 and y=1 are 0.5 m away (a single convex hull
    # would fill the notch and the rays would start inside it). "on" remeshes: ~cm inflation.
    assert ray(model, data, (1.5, 1.5, 0.5), (-1, 0, 0)) == pytest.approx(0.5, abs=tol)
    assert ray(model, data, (1.5, 1.5, 0.5), (0, -1, 0)) == pytest.approx(0.5, abs=tol)
    # From outside: the outer walls.
    assert ray(model, data, (3.0, 0.5, 0.5), (-1, 0, 0)) == pytest.approx(1.0, abs=tol)
    assert ray(model, data, (0.5, 0.5, 3.0), (0, 0, -1)) == pytest.approx(2.0, abs=tol)
    # Up out of the notch there is nothing.
    assert ray(model, data, (1.5, 1.5, 0.5), (0, 0, 1)) == -1
