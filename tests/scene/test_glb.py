"""The trimesh-free reader of our own .glb files gives exactly what the trimesh path gives."""

from __future__ import annotations

import json
import struct
import subprocess
import sys

import numpy as np
import pytest

import havln_mj.scene.mesh as mesh_module
from havln_mj.errors import CorruptMeshError
from havln_mj.scene.glb import read_own_glb
from havln_mj.scene.mesh import MeshPart, load_mesh_parts, write_glb
from havln_mj.scene.scan import load_scan


def _by_trimesh(monkeypatch, path, **kwargs) -> list[MeshPart]:
    with monkeypatch.context() as m:
        m.setattr(mesh_module, "read_own_glb", lambda *args: None)
        return load_mesh_parts(path, **kwargs)


def _assert_same(fast: list[MeshPart], slow: list[MeshPart]) -> None:
    assert [p.name for p in fast] == [p.name for p in slow]
    for a, b in zip(fast, slow, strict=True):
        assert (a.rgba, a.shine, a.emission) == (b.rgba, b.shine, b.emission), a.name
        for field in ("vertices", "faces", "uv", "texture"):
            x, y = getattr(a, field), getattr(b, field)
            assert (x is None) == (y is None), (a.name, field)
            if x is not None:
                assert x.dtype == y.dtype and x.shape == y.shape, (a.name, field)
                assert np.array_equal(x, y), (a.name, field)

    # Parts share texture arrays the same way (the world builder merges by identity).
    def sharing(parts):
        ids = [id(p.texture) for p in parts if p.texture is not None]
        return [ids.index(i) for i in ids]

    assert sharing(fast) == sharing(slow)


def test_a_procedural_house_reads_the_same_without_trimesh(monkeypatch):
    path = load_scan("proc-0").mesh_path
    assert read_own_glb(path, None) is not None
    fast = load_mesh_parts(path)
    assert sum(p.textured for p in fast) > 10 and any(p.emission > 0 for p in fast)
    _assert_same(fast, _by_trimesh(monkeypatch, path))
    options = {"up": "y", "max_texture_size": 16}
    _assert_same(load_mesh_parts(path, **options), _by_trimesh(monkeypatch, path, **options))


def test_a_real_scan_proxy_reads_the_same_without_trimesh(monkeypatch, shared_data):
    path = load_scan("17DRP5sb8fy", connectivity_dir=shared_data / "mp3d_connectivity").mesh_path
    assert read_own_glb(path, None) is not None
    _assert_same(load_mesh_parts(path), _by_trimesh(monkeypatch, path))


def _parts() -> list[MeshPart]:
    verts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 1]], dtype=float)
    faces = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32)
    texture = np.arange(4 * 6 * 3, dtype=np.uint8).reshape(4, 6, 3)
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float32)
    return [
        MeshPart("a", verts, faces, (0.2, 0.4, 0.6, 1.0), shine=0.3),
        MeshPart("b", verts + 2, faces, (1.0, 1.0, 1.0, 1.0), uv, texture, emission=0.5),
    ]


def _edit_json(path, edit) -> None:
    """Rewrites a GLB file's JSON chunk with ``edit(header)`` applied."""
    data = path.read_bytes()
    size = struct.unpack_from("<I", data, 12)[0]
    header = json.loads(data[20 : 20 + size])
    edit(header)
    text = json.dumps(header).encode()
    text += b" " * (-len(text) % 4)
    rest = data[20 + size :]
    out = struct.pack("<4sII", b"glTF", 2, 20 + len(text) + len(rest))
    path.write_bytes(out + struct.pack("<II", len(text), 0x4E4F534A) + text + rest)


def test_a_file_beyond_what_we_write_is_read_by_trimesh(tmp_path, monkeypatch):
    path = tmp_path / "moved.glb"
    write_glb(_parts(), path)
    _edit_json(path, lambda h: h["nodes"][0].update(translation=[0.0, 0.0, 5.0]))
    assert read_own_glb(path, None) is None
    parts = {p.name: p for p in load_mesh_parts(path)}
    assert parts["a"].vertices[:, 2].min() == 5.0 and parts["b"].vertices[:, 2].min() == 2.0
    unmarked = tmp_path / "unmarked.glb"
    write_glb(_parts(), unmarked)
    _edit_json(unmarked, lambda h: h["scenes"][0].pop("extras"))
    assert read_own_glb(unmarked, None) is None


def test_a_broken_file_of_ours_is_reported(tmp_path):
    path = tmp_path / "short.glb"
    write_glb(_parts(), path)

    def accessor(header, attribute):
        prim = header["meshes"][0]["primitives"][0]
        index = prim["indices"] if attribute == "indices" else prim["attributes"][attribute]
        return header["accessors"][index]

    _edit_json(path, lambda h: accessor(h, "indices").update(count=9))
    with pytest.raises(CorruptMeshError, match=r"accessor .* runs past its buffer view"):
        load_mesh_parts(path)
    write_glb(_parts(), path)
    _edit_json(path, lambda h: accessor(h, "POSITION").update(count=2))
    with pytest.raises(CorruptMeshError, match="indexes vertex 3 of 2"):
        load_mesh_parts(path)
    path.write_bytes(path.read_bytes()[:-100])
    with pytest.raises(
        CorruptMeshError, match=r"the GLB header says \d+ bytes, the file is shorter"
    ):
        load_mesh_parts(path)


def test_reading_our_file_imports_no_trimesh(tmp_path):
    path = tmp_path / "ours.glb"
    write_glb(_parts(), path)
    code = (
        "import sys; from pathlib import Path; from havln_mj.scene.mesh import load_mesh_parts;"
        f"parts = load_mesh_parts(Path({str(path)!r}));"
        "assert [p.name for p in parts] == ['b', 'a'] and parts[0].textured;"
        "print(sorted(m for m in ('trimesh', 'scipy', 'networkx') if m in sys.modules))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"
