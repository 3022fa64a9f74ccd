"""Top-down maps."""

from __future__ import annotations

import cv2

from havln_mj.render.topdown import draw_topdown, section_segments
from havln_mj.scene.mesh import parts_to_trimesh
from havln_mj.scene.scan import load_scan


def test_map_has_rooms_walls_and_the_path(tmp_path):
    scan = load_scan("proc-6")
    mesh = parts_to_trimesh(scan.mesh_parts)
    walls = section_segments(mesh, 1.0)
    assert len(walls) > 20 and walls.shape[1:] == (2, 2)
    a, b = scan.graph.components()[0][0], scan.graph.components()[0][-1]
    path = scan.graph.shortest_path(a, b)
    plain, with_path = tmp_path / "plain.png", tmp_path / "path.png"
    draw_topdown(plain, scan.graph, scan.regions, mesh)
    draw_topdown(with_path, scan.graph, scan.regions, mesh, [path], title="t")
    img_plain, img_path = cv2.imread(str(plain)), cv2.imread(str(with_path))
    assert img_plain.shape == img_path.shape and img_plain.shape[2] == 3

    # The highlighted path adds saturated red pixels the plain map lacks.
    def red(img):
        b, g, r = (img[..., k].astype(int) for k in range(3))
        return int(((r > 180) & (g < 80) & (b < 80)).sum())

    assert red(img_path) > red(img_plain) + 100
