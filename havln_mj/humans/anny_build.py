"""Maintainer script: builds the shipped catalog of Anny bodies (``humans/anny/``).

Run once, with the build-time extra installed (``pip install -e '.[anny]'``)::

    nice -n 10 python -m havln_mj.humans.anny_build [--out humans/anny]

It loads Anny's default model (``anny`` rig and topology: MakeHuman assets under CC0; never
the ``smpl``/``smplx`` topologies, which download non-commercial files), decimates its mesh
once into a shared topology, and writes every phenotype of :data:`PHENOTYPES` onto it:
rest vertices in our body frame (z up, facing +y, soles on z = 0), the rest positions of
the 24 skeleton joints the motions drive, skinning weights merged onto those joints, UVs,
and a texel → face map the clothes painter uses. The runtime reads only the ``.npz``
(numpy); torch and anny are needed here alone. The first run of Anny parses its assets
(minutes, ~0.8 GB cache in ``$ANNY_CACHE_DIR``); later runs take seconds.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
from pathlib import Path

import numpy as np

from havln_mj.humans.anny_data import (
    ANNY_TO_JOINT,
    JOINT_ANCHOR_BONES,
    POSITION_SCALE,
    TEXTURE_SIZE,
)
from havln_mj.humans.skeleton import NUM_JOINTS

# (id, gender 0 = male … 1 = female, age (0 baby, 1/3 child, 2/3 young adult, 1 old),
#  muscle, weight, standing height in metres (Anny's height parameter is solved for it),
#  proportions); Anny's parameters lie in [0, 1].
PHENOTYPES = (
    ("boy-7", 0.0, 0.24, 0.5, 0.45, 1.22, 0.5),
    ("girl-7", 1.0, 0.24, 0.5, 0.5, 1.20, 0.5),
    ("boy-11", 0.0, 0.34, 0.45, 0.4, 1.45, 0.5),
    ("girl-11", 1.0, 0.34, 0.5, 0.6, 1.44, 0.5),
    ("boy-15", 0.0, 0.46, 0.55, 0.5, 1.70, 0.5),
    ("girl-15", 1.0, 0.46, 0.45, 0.45, 1.60, 0.5),
    ("man-slim-tall", 0.0, 0.62, 0.5, 0.2, 1.88, 0.5),
    ("man-average", 0.0, 0.66, 0.5, 0.5, 1.76, 0.5),
    ("man-muscular", 0.0, 0.64, 0.9, 0.5, 1.80, 0.5),
    ("man-heavy", 0.0, 0.72, 0.45, 0.9, 1.74, 0.5),
    ("man-short", 0.0, 0.7, 0.5, 0.55, 1.64, 0.5),
    ("man-broad", 0.0, 0.78, 0.7, 0.7, 1.83, 0.4),
    ("man-lean", 0.0, 0.82, 0.35, 0.3, 1.78, 0.6),
    ("man-stocky", 0.0, 0.75, 0.6, 0.8, 1.68, 0.6),
    ("man-tall", 0.0, 0.68, 0.55, 0.45, 1.93, 0.5),
    ("woman-slim", 1.0, 0.62, 0.4, 0.2, 1.68, 0.5),
    ("woman-average", 1.0, 0.66, 0.5, 0.5, 1.63, 0.5),
    ("woman-athletic", 1.0, 0.64, 0.8, 0.4, 1.72, 0.5),
    ("woman-heavy", 1.0, 0.72, 0.4, 0.9, 1.62, 0.5),
    ("woman-petite", 1.0, 0.7, 0.45, 0.4, 1.52, 0.5),
    ("woman-tall", 1.0, 0.68, 0.5, 0.5, 1.78, 0.5),
    ("woman-curvy", 1.0, 0.78, 0.45, 0.7, 1.65, 0.4),
    ("woman-lean", 1.0, 0.82, 0.4, 0.3, 1.70, 0.6),
    ("woman-stocky", 1.0, 0.75, 0.55, 0.75, 1.56, 0.6),
    ("man-elder", 0.0, 0.9, 0.4, 0.55, 1.72, 0.5),
    ("man-elder-slim", 0.0, 0.97, 0.3, 0.3, 1.75, 0.5),
    ("man-elder-heavy", 0.0, 0.93, 0.4, 0.8, 1.68, 0.5),
    ("woman-elder", 1.0, 0.9, 0.4, 0.55, 1.60, 0.5),
    ("woman-elder-slim", 1.0, 0.97, 0.3, 0.3, 1.62, 0.5),
    ("woman-elder-heavy", 1.0, 0.93, 0.4, 0.8, 1.55, 0.5),
)
PHENOTYPE_LABELS = ("gender", "age", "muscle", "weight", "height", "proportions")
TARGET_VERTICES = 3200
ANNY_TO_BODY = np.diag([-1.0, -1.0, 1.0])  # Anny faces −y, ours +y: half a turn about z


def _load_anny():
    import anny  # build-time extra
    import torch

    return anny.Anny().to(dtype=torch.float64), torch


def _phenotype_rest(model, torch, values: dict) -> tuple[np.ndarray, np.ndarray]:
    """Rest vertices (V, 3) and bone heads (B, 3) of one phenotype, in Anny's frame."""
    kw = {k: torch.tensor([float(v)], dtype=torch.float64) for k, v in values.items()}
    with torch.no_grad():
        out = model(pose_parameters=None, phenotype_kwargs=kw)
    return out["rest_vertices"][0].numpy(), out["rest_bone_heads"][0].numpy()


def _solve_height(model, torch, values: dict) -> dict:
    """``values`` with Anny's height parameter set so the body stands ``values["height"]`` m.

    Standing height is linear in that parameter (other parameters fixed), so two
    evaluations find it.
    """
    target = values["height"]
    tall = []
    for h in (0.0, 1.0):
        verts, _ = _phenotype_rest(model, torch, values | {"height": h})
        tall.append(float(np.ptp(verts[:, 2])))
    h = (target - tall[0]) / (tall[1] - tall[0])
    if not 0.0 <= h <= 1.0:
        raise ValueError(f"height {target} m needs Anny height {h:.2f}, outside [0, 1]")
    return values | {"height": h}


def _joint_weights(model) -> np.ndarray:
    """Anny's skinning weights summed onto our 24 joints, ``(V, 24)``."""
    idx = model.vertex_bone_indices.numpy()
    w = model.vertex_bone_weights.numpy()
    labels, parents = list(model.bone_labels), list(model.bone_parents)
    to_joint = np.array([_joint_of(labels, parents, b) for b in range(len(labels))])
    out = np.zeros((len(idx), NUM_JOINTS))
    np.add.at(out, (np.repeat(np.arange(len(idx)), idx.shape[1]), to_joint[idx].ravel()), w.ravel())
    return out / out.sum(axis=1, keepdims=True)


def _joint_of(labels: list[str], parents: list[int], bone: int) -> int:
    """Our joint driving Anny bone ``bone``: its own mapping, else its nearest mapped parent."""
    while labels[bone] not in ANNY_TO_JOINT:
        bone = parents[bone]
    return ANNY_TO_JOINT[labels[bone]]


def _decimate(vertices: np.ndarray, faces: np.ndarray, target: int):
    import fast_simplification  # build-time extra

    reduction = 1.0 - target / len(vertices)
    return fast_simplification.simplify(vertices, faces, target_reduction=reduction, agg=5)


def _barycentric(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Barycentric coordinates ``(N, 3)`` of points in triangles ``(N, 3, 3)`` (their plane)."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    v0, v1, v2 = b - a, c - a, points - a
    d00 = np.einsum("ij,ij->i", v0, v0)
    d01 = np.einsum("ij,ij->i", v0, v1)
    d11 = np.einsum("ij,ij->i", v1, v1)
    d20 = np.einsum("ij,ij->i", v2, v0)
    d21 = np.einsum("ij,ij->i", v2, v1)
    den = np.maximum(d00 * d11 - d01 * d01, 1e-18)
    v = (d11 * d20 - d01 * d21) / den
    w = (d00 * d21 - d01 * d20) / den
    return np.stack([1.0 - v - w, v, w], axis=1)


def _surface_map(template: np.ndarray, faces: np.ndarray, points: np.ndarray):
    """Each point as the closest point of the template surface: (face, barycentric)."""
    import trimesh

    mesh = trimesh.Trimesh(template, faces, process=False)
    closest, _, tri = trimesh.proximity.closest_point(mesh, points)
    return tri, _barycentric(closest, template[faces[tri]])


def _corner_uvs(model, template, faces, dec_v, dec_f) -> np.ndarray:
    """UV ``(F', 3, 2)`` of each decimated face corner, from the template face under it.

    All three corners take the UV chart of the template face under the face's centroid
    (extrapolated affinely past that face), so no face straddles two charts.
    """
    uv = model.texture_coordinates.numpy()
    fuv = model.face_texture_coordinate_indices.numpy()
    tri_v = dec_v[dec_f]  # (F', 3, 3)
    tri, _ = _surface_map(template, faces, tri_v.mean(axis=1))
    src = np.repeat(tri, 3)
    bary = _barycentric(tri_v.reshape(-1, 3), template[faces[src]])
    return np.einsum("nk,nkc->nc", bary, uv[fuv[src]]).reshape(-1, 3, 2)


def _render_vertices(dec_f: np.ndarray, corner_uv: np.ndarray):
    """Vertices split where the UV is discontinuous: (render → geometric index, uv, faces)."""
    key = np.concatenate(
        [dec_f.reshape(-1, 1), np.round(corner_uv.reshape(-1, 2) * 4096).astype(np.int64)], axis=1
    )
    unique, inverse = np.unique(key, axis=0, return_inverse=True)
    uv = np.zeros((len(unique), 2))
    np.add.at(uv, inverse.ravel(), corner_uv.reshape(-1, 2))
    uv /= np.bincount(inverse.ravel())[:, None]
    return unique[:, 0].astype(np.int32), uv, inverse.reshape(-1, 3).astype(np.int32)


def _texel_map(uv: np.ndarray, faces: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """Which face each texel shows and where in it: ``(S, S)`` face (−1 none), ``(S, S, 2)``.

    Rows run top-down with ``v = 1 − (row + 0.5) / S`` (image order, OBJ-convention UVs);
    empty texels take their nearest painted neighbour's face, so mipmaps do not bleed.
    """
    face_of = np.full((size, size), -1, np.int32)
    bary = np.zeros((size, size, 2), np.float32)
    px = np.stack([uv[:, 0] * size - 0.5, (1.0 - uv[:, 1]) * size - 0.5], axis=1)
    for f, (a, b, c) in enumerate(faces):
        tri = px[[a, b, c]]
        lo = np.maximum(np.floor(tri.min(axis=0)).astype(int), 0)
        hi = np.minimum(np.ceil(tri.max(axis=0)).astype(int), size - 1)
        if np.any(hi < lo):
            continue
        xs, ys = np.meshgrid(np.arange(lo[0], hi[0] + 1), np.arange(lo[1], hi[1] + 1))
        pts = np.stack([xs.ravel(), ys.ravel()], axis=1).astype(float)
        t = tri[1:] - tri[0]
        det = t[0, 0] * t[1, 1] - t[0, 1] * t[1, 0]
        if abs(det) < 1e-12:
            continue
        d = pts - tri[0]
        u = (d[:, 0] * t[1, 1] - d[:, 1] * t[1, 0]) / det
        v = (t[0, 0] * d[:, 1] - t[0, 1] * d[:, 0]) / det
        inside = (u >= -1e-3) & (v >= -1e-3) & (u + v <= 1 + 1e-3)
        face_of[ys.ravel()[inside], xs.ravel()[inside]] = f
        bary[ys.ravel()[inside], xs.ravel()[inside]] = np.stack([u[inside], v[inside]], axis=1)
    return _dilate(face_of, bary)


def _dilate(face_of: np.ndarray, bary: np.ndarray, steps: int = 6):
    """Grows painted texels into empty ones (nearest of the 4 neighbours), ``steps`` times."""
    for _ in range(steps):
        empty = face_of < 0
        if not empty.any():
            break
        for dy, dx in ((0, 1), (0, -1), (1, 0), (-1, 0)):
            src_f = np.roll(face_of, (dy, dx), axis=(0, 1))
            src_b = np.roll(bary, (dy, dx), axis=(0, 1))
            take = empty & (src_f >= 0) & (face_of < 0)
            face_of[take], bary[take] = src_f[take], src_b[take]
    return face_of, bary


def _top4(weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The 4 largest joint weights per vertex, renormalised: (indices uint8, weights)."""
    idx = np.argsort(-weights, axis=1)[:, :4]
    w = np.take_along_axis(weights, idx, axis=1)
    w /= w.sum(axis=1, keepdims=True)
    return idx.astype(np.uint8), w.astype(np.float32)


def build(out_dir: Path, target: int = TARGET_VERTICES) -> Path:
    """Builds ``bodies.npz`` and ``bodies.json`` in ``out_dir``; returns the npz path."""
    model, torch = _load_anny()
    labels = list(model.bone_labels)
    faces = model.faces.numpy().astype(np.int64)
    neutral = {k: 0.5 for k in PHENOTYPE_LABELS}
    template, _ = _phenotype_rest(model, torch, neutral)
    dec_v, dec_f = _decimate(template, faces, target)
    tri, bary = _surface_map(template, faces, dec_v)
    dense_w = _joint_weights(model)
    w_dec = np.einsum("nk,nkj->nj", bary, dense_w[faces[tri]])
    joint_idx, joint_w = _top4(w_dec)
    corner_uv = _corner_uvs(model, template, faces, dec_v, dec_f)
    render_to_geom, uv, render_faces = _render_vertices(dec_f, corner_uv)
    texel_face, texel_bary = _texel_map(uv, render_faces, TEXTURE_SIZE)
    anchor_bones = [labels.index(name) for name in JOINT_ANCHOR_BONES]
    eyes = [labels.index("eye.L"), labels.index("eye.R")]
    rest, joints, eye_pos, heights = [], [], [], []
    params = []
    for _, *values in PHENOTYPES:
        values = _solve_height(model, torch, dict(zip(PHENOTYPE_LABELS, values, strict=False)))
        params.append([values[k] for k in PHENOTYPE_LABELS])
        verts, heads = _phenotype_rest(model, torch, values)
        v = np.einsum("nk,nkc->nc", bary, verts[faces[tri]]) @ ANNY_TO_BODY.T
        shift = np.array([0.0, 0.0, -v[:, 2].min()])
        heads = heads @ ANNY_TO_BODY.T + shift
        rest.append(v + shift)
        joints.append(heads[anchor_bones])
        eye_pos.append(heads[eyes])
        heights.append(float(np.ptp(v[:, 2])))
    rest = np.array(rest)
    out_dir.mkdir(parents=True, exist_ok=True)
    arrays = {
        "rest": np.round(rest / POSITION_SCALE).astype(np.int16),
        "joints": np.array(joints, np.float32),
        "eyes": np.array(eye_pos, np.float32),
        "faces": dec_f.astype(np.int16),
        "joint_index": joint_idx,
        "joint_weight": joint_w,
        "uv": uv.astype(np.float32),
        "uv_vertex": render_to_geom.astype(np.int16),
        "uv_faces": render_faces.astype(np.int16),
        "texel_face": texel_face.astype(np.int16),
        "texel_bary": texel_bary.astype(np.float16),
        "phenotypes": np.array(params, np.float32),
    }
    path = out_dir / "bodies.npz"
    _write_atomic(path, arrays)
    meta = {
        "source": f"anny {_anny_version()} (rig 'anny', topology 'anny'), decimated",
        "phenotype_labels": list(PHENOTYPE_LABELS),
        "bodies": [
            {"id": p[0], "height_m": round(h, 3)}
            | {k: round(float(v), 4) for k, v in zip(PHENOTYPE_LABELS, q, strict=True)}
            for p, q, h in zip(PHENOTYPES, params, heights, strict=True)
        ],
        "vertices": len(dec_v),
        "faces": len(dec_f),
    }
    (out_dir / "bodies.json").write_text(json.dumps(meta, indent=1) + "\n")
    return path


def _anny_version() -> str:
    from importlib.metadata import version

    return version("anny")


def _write_atomic(path: Path, arrays: dict) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".npz")
    os.close(fd)
    np.savez_compressed(tmp, **arrays)
    os.chmod(tmp, 0o644)
    os.replace(tmp, path)


def main(argv: list[str] | None = None) -> int:
    """Command line: builds the catalog into ``--out``."""
    from havln_mj.paths import project_home

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=project_home() / "humans" / "anny")
    ap.add_argument("--vertices", type=int, default=TARGET_VERTICES)
    args = ap.parse_args(argv)
    path = build(args.out, args.vertices)
    print(f"wrote {path} ({path.stat().st_size / 1e6:.2f} MB)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
