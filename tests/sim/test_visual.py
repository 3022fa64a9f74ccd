"""Visual mesh parts in MuJoCo: textures land the right way round, plain parts keep rgba."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh
from PIL import Image

from havln_mj import groups
from havln_mj.render.camera import Camera
from havln_mj.scene.mesh import MeshPart, load_mesh_parts
from havln_mj.sim.visual import add_visual_parts

RED, BLUE, GREEN, YELLOW = (255, 0, 0), (0, 0, 255), (0, 255, 0), (255, 255, 0)
W, H = 64, 48

# A 2 m square in the z = 0 plane; OBJ texture coordinates put the image's bottom-left corner
# at (-1, -1) and its top-right corner at (1, 1).
QUAD_OBJ = """mtllib quad.mtl
v -1 -1 0
v 1 -1 0
v 1 1 0
v -1 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 1
usemtl painted
f 1/1/1 2/2/1 3/3/1
f 1/1/1 3/3/1 4/4/1
"""
QUAD_MTL = """newmtl painted
Ka 1 1 1
Kd 1 1 1
map_Kd paint.png
"""


def _write_quad(folder: Path, image: np.ndarray) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    Image.fromarray(image).save(folder / "paint.png")
    (folder / "quad.mtl").write_text(QUAD_MTL)
    (folder / "quad.obj").write_text(QUAD_OBJ)
    return folder / "quad.obj"


def _halves(first: tuple, second: tuple, axis: int) -> np.ndarray:
    """A 16×32 image: left/right halves (axis 1) or top/bottom halves (axis 0)."""
    image = np.zeros((16, 32, 3), dtype=np.uint8)
    if axis == 1:
        image[:, :16], image[:, 16:] = first, second
    else:
        image[:8], image[8:] = first, second
    return image


def _render(parts: list[MeshPart]) -> np.ndarray:
    """Renders the parts from 2 m above the origin, image up = +y, flat white light."""
    spec = mujoco.MjSpec()
    spec.visual.headlight.ambient = (1.0, 1.0, 1.0)
    spec.visual.headlight.diffuse = (0.0, 0.0, 0.0)
    spec.visual.headlight.specular = (0.0, 0.0, 0.0)
    assert add_visual_parts(spec, parts) == len(parts)
    spec.worldbody.add_camera(name="top", pos=(0.0, 0.0, 2.0))  # looks along -z, +y up
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    with Camera(model, "top", W, H, vfov_deg=45.0) as cam:
        return cam.render(data, depth=False).rgb


def _close(pixel: np.ndarray, colour: tuple) -> bool:
    return bool(np.all(np.abs(pixel.astype(int) - np.array(colour)) <= 8))


def test_obj_texture_renders_left_red_right_blue(tmp_path):
    parts = load_mesh_parts(_write_quad(tmp_path, _halves(RED, BLUE, axis=1)))
    (part,) = parts
    assert part.textured and part.texture.shape == (16, 32, 3) and part.uv.shape == (4, 2)
    rgb = _render(parts)
    assert _close(rgb[H // 2, W // 2 - 8], RED), rgb[H // 2, W // 2 - 8]
    assert _close(rgb[H // 2, W // 2 + 8], BLUE), rgb[H // 2, W // 2 + 8]


def test_obj_texture_renders_the_right_way_up(tmp_path):
    rgb = _render(load_mesh_parts(_write_quad(tmp_path, _halves(GREEN, YELLOW, axis=0))))
    assert _close(rgb[H // 2 - 8, W // 2], GREEN), rgb[H // 2 - 8, W // 2]
    assert _close(rgb[H // 2 + 8, W // 2], YELLOW), rgb[H // 2 + 8, W // 2]


def test_glb_texture_renders_like_the_obj(tmp_path):
    obj = _write_quad(tmp_path / "obj", _halves(RED, BLUE, axis=1))
    glb = tmp_path / "quad.glb"
    glb.write_bytes(trimesh.load(obj, force="scene", process=False).export(file_type="glb"))
    (from_obj,), (from_glb,) = load_mesh_parts(obj), load_mesh_parts(glb)
    np.testing.assert_allclose(from_glb.uv, from_obj.uv, atol=1e-6)
    np.testing.assert_array_equal(from_glb.texture, from_obj.texture)
    rgb = _render([from_glb])
    assert _close(rgb[H // 2, W // 2 - 8], RED) and _close(rgb[H // 2, W // 2 + 8], BLUE)


def test_untextured_part_renders_its_rgba_and_geoms_are_visual_only(tmp_path):
    textured = load_mesh_parts(_write_quad(tmp_path, _halves(RED, BLUE, axis=1)))[0]
    shifted = textured.vertices + np.array([0.0, 0.0, 0.5])  # same quad, 0.5 m nearer the camera
    plain = MeshPart("plain wall/1", shifted[[0, 1, 2]], np.array([[0, 1, 2]]), (0, 1, 0, 1))
    rgb = _render([textured, plain])
    # The triangle covers the image's lower right half; the textured quad shows elsewhere.
    assert _close(rgb[H // 2 + 8, W // 2 + 8], GREEN)
    assert _close(rgb[H // 2 - 8, W // 2 - 8], RED)

    spec = mujoco.MjSpec()
    add_visual_parts(spec, [textured, plain, textured], group=groups.VISUAL)
    model = spec.compile()
    names = [model.geom(i).name for i in range(model.ngeom)]
    assert names == ["visual/0_painted", "visual/1_plain_wall_1", "visual/2_painted"]
    assert np.all(model.geom_contype == 0) and np.all(model.geom_conaffinity == 0)
    assert np.all(model.geom_group == groups.VISUAL)
    assert model.ntex == 1 and model.nmat == 1  # one image, uploaded once; one shared material
    assert model.geom_matid[1] == -1
    np.testing.assert_allclose(model.geom_rgba[1], (0, 1, 0, 1))


def test_bad_uv_shape_is_rejected():
    image = _halves(RED, BLUE, axis=1)
    verts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float)
    part = MeshPart("p", verts, np.array([[0, 1, 2]]), (1, 1, 1, 1), np.zeros((2, 2)), image)
    with pytest.raises(ValueError, match=r"uv has shape \(2, 2\), expected \(3, 2\)"):
        add_visual_parts(mujoco.MjSpec(), [part])


def test_part_without_surface_is_skipped_but_names_keep_their_index(caplog):
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    flat = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], dtype=float)  # collinear: no area
    parts = [
        MeshPart("line", flat, np.array([[0, 1, 2]]), (1, 0, 0, 1)),
        MeshPart("square", square, np.array([[0, 1, 2], [0, 2, 3]]), (0, 0, 1, 1)),
    ]
    spec = mujoco.MjSpec()
    assert add_visual_parts(spec, parts) == 1
    assert "('line') has no surface" in caplog.text
    model = spec.compile()
    assert [model.geom(i).name for i in range(model.ngeom)] == ["visual/1_square"]


def test_out_of_range_faces_are_rejected():
    verts = np.zeros((4, 3))
    part = MeshPart("p", verts, np.array([[0, 1, 4]]), (1, 1, 1, 1))
    with pytest.raises(ValueError, match=r"face indices span \[0, 4\], valid \[0, 3\]"):
        add_visual_parts(mujoco.MjSpec(), [part])


def test_large_textures_can_be_shrunk_on_load(tmp_path):
    obj = _write_quad(tmp_path, np.repeat(np.repeat(_halves(RED, BLUE, axis=1), 4, 0), 4, 1))
    assert load_mesh_parts(obj)[0].texture.shape == (64, 128, 3)
    (part,) = load_mesh_parts(obj, max_texture_size=50)
    assert part.texture.shape == (22, 43, 3)  # reduced by 3: neither side above 50
    rgb = _render([part])
    assert _close(rgb[H // 2, W // 2 - 8], RED) and _close(rgb[H // 2, W // 2 + 8], BLUE)
    with pytest.raises(ValueError, match="max_texture_size"):
        load_mesh_parts(obj, max_texture_size=0)


def _quad_part(name, texture, z=0.0, rgba=(1.0, 1.0, 1.0, 1.0), shine=0.0, emission=0.0):
    verts = np.array([[-1, -1, z], [1, -1, z], [1, 1, z], [-1, 1, z]], float)
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32)
    faces = np.array([[0, 1, 2], [0, 2, 3]], np.int32)
    return MeshPart(name, verts, faces, rgba, uv, texture, shine, emission)


def test_written_glb_reads_back_part_by_part_with_its_finish(tmp_path):
    from havln_mj.scene.mesh import write_glb

    paint = _halves(RED, BLUE, axis=1)
    overlay = np.zeros((8, 8, 4), np.uint8)
    overlay[..., 3] = 128
    parts = [
        _quad_part("1:wood", paint, rgba=(0.8, 0.6, 0.4, 1.0), shine=0.3),
        _quad_part("2:wood", paint, z=0.1, rgba=(0.8, 0.6, 0.4, 1.0), shine=0.3),
        _quad_part("2:lamp", None, z=0.2, rgba=(1.0, 0.9, 0.8, 1.0), emission=1.0),
        _quad_part("3:shade", overlay, z=0.3, rgba=(1.0, 1.0, 1.0, 0.99)),
    ]
    write_glb(parts, tmp_path / "m.glb")
    back = {p.name: p for p in load_mesh_parts(tmp_path / "m.glb")}
    assert set(back) == {"1:wood", "2:wood", "2:lamp", "3:shade"}  # one part per node
    assert back["1:wood"].texture is back["2:wood"].texture  # one image, shared
    assert abs(back["1:wood"].shine - 0.3) < 1e-6 and back["1:wood"].rgba[0] == pytest.approx(
        0.8, abs=0.003
    )
    assert back["2:lamp"].emission == 1.0 and back["2:lamp"].texture is None
    assert back["3:shade"].texture.shape == (8, 8, 4) and back["3:shade"].rgba[3] < 1.0
    np.testing.assert_allclose(back["2:wood"].vertices, parts[1].vertices)


def test_parts_that_look_alike_merge_and_share_one_material():
    from havln_mj.scene.mesh import merge_by_look

    paint = _halves(RED, BLUE, axis=1)
    parts = [
        _quad_part("1:wood", paint, shine=0.3),
        _quad_part("2:wood", paint, z=0.1, shine=0.3),
        _quad_part("3:oak", paint, z=0.2, rgba=(0.5, 0.5, 0.5, 1.0), shine=0.3),
    ]
    merged = merge_by_look(parts)
    assert [p.name for p in merged] == ["wood", "oak"]
    assert len(merged[0].faces) == 4 and merged[0].faces.max() == 7
    spec = mujoco.MjSpec()
    shade = _quad_part("4:shade", np.zeros((4, 4, 4), np.uint8), 0.3, (1, 1, 1, 0.99))
    add_visual_parts(spec, [*merged, shade])
    model = spec.compile()
    assert model.ntex == 2 and model.nmat == 3
    assert model.tex_nchannel[1] == 4  # the overlay keeps its alpha
    np.testing.assert_allclose(model.mat_rgba[1], (0.5, 0.5, 0.5, 1.0))  # tint of the texture
    assert model.mat_specular[0] == pytest.approx(0.15)
