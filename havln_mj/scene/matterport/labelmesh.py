"""Label meshes: a scan's triangles grouped by object instance, for the segmentation pass.

Two sources:

- A scan folder with ``semantics.json`` (procedural houses): its visual mesh parts, grouped
  by the instance each part belongs to. Blended overlays (alpha below 1) are left out: they
  lie on a surface that is labelled already.
- A Matterport3D scan: the per-face object ids of the house-segmentation mesh
  (:func:`havln_mj.scene.matterport.layout.label_files`: raw ``<scan>.ply`` with
  ``face_segment``, or habitat ``<scan>_semantic.ply`` with ``object_id``), the object's
  class from the ``.house`` file (``O`` object index -> ``C`` category -> mpcat40 index). The
  id is taken to be the ``O`` line's object index. Faces of no known object form one mesh of
  class ``unlabeled`` (41), instance 0, so they still hide what is behind them.

Instances of a Matterport scan are its object indices + 1 (0 stays "none").
"""

from __future__ import annotations

import logging
import re
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from havln_mj.errors import CorruptMeshError
from havln_mj.scene.matterport.categories import LabelMesh, SceneLabels
from havln_mj.scene.matterport.house import read_object_classes
from havln_mj.scene.matterport.layout import label_files
from havln_mj.scene.mesh import MeshPart
from havln_mj.scene.scanfolder import SEMANTICS

if TYPE_CHECKING:
    from havln_mj.scene.scan import Scan

log = logging.getLogger(__name__)

FACE_OBJECT_FIELDS = ("face_segment", "object_id")
"""Face properties read as the face's object id, first found wins."""

UNLABELED = 41

_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
    "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}  # fmt: skip


def parts_label_meshes(parts: list[MeshPart], labels: SceneLabels) -> list[LabelMesh]:
    """Visual mesh parts grouped by instance (overlays and unlabelled parts left out)."""
    by_instance: dict[int, list[MeshPart]] = {}
    for part in parts:
        blended = part.rgba[3] < 1.0 or (part.texture is not None and part.texture.shape[2] == 4)
        inst = labels.instance(part.name)
        if inst is not None and not blended:
            by_instance.setdefault(inst.id, []).append(part)
    out = []
    for iid, group in by_instance.items():
        inst = labels.instance(group[0].name)
        assert inst is not None
        offsets = np.cumsum([0] + [len(p.vertices) for p in group[:-1]])
        verts = np.concatenate([p.vertices for p in group])
        faces = np.concatenate([p.faces + o for p, o in zip(group, offsets, strict=True)])
        out.append(LabelMesh(f"{iid}_{inst.category}", verts, faces, inst.mpcat40, iid))
    return out


def read_ply(path: Path) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Reads a triangle PLY (ascii or binary): vertices, faces and the faces' other properties.

    Raises:
        CorruptMeshError: The file is not a PLY this reader handles (elements other than
            ``vertex`` and ``face``, faces that are not triangles, a truncated body).
    """
    data = path.read_bytes()
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise CorruptMeshError(f"{path}: not a PLY file (no 'ply' ... 'end_header' header)")
    body_at = data.index(b"\n", end) + 1
    header = data[:end].decode("ascii", "replace").splitlines()
    fmt, elements = "", []
    for line in header:
        words = line.split()
        if words[:1] == ["format"]:
            fmt = words[1]
        elif words[:1] == ["element"]:
            elements.append((words[1], int(words[2]), []))
        elif words[:1] == ["property"] and elements:
            elements[-1][2].append(words[1:])
    if [e[0] for e in elements] != ["vertex", "face"]:
        raise CorruptMeshError(
            f"{path}: expected elements vertex, face; got {[e[0] for e in elements]}"
        )
    try:
        if fmt == "ascii":
            return _ply_ascii(data[body_at:], elements)
        order = {"binary_little_endian": "<", "binary_big_endian": ">"}[fmt]
        return _ply_binary(data[body_at:], elements, order)
    except (KeyError, ValueError, IndexError) as exc:
        raise CorruptMeshError(
            f"{path}: cannot read PLY body ({type(exc).__name__}: {exc})"
        ) from exc


def _ply_binary(body: bytes, elements: list, order: str) -> tuple:
    (_, nv, vprops), (_, nf, fprops) = elements
    vdtype = np.dtype([(p[-1], order + _PLY_TYPES[p[0]]) for p in vprops])
    verts = np.frombuffer(body, vdtype, nv)
    fields = []
    for p in fprops:
        if p[0] == "list":
            fields += [("n", order + _PLY_TYPES[p[1]]), ("v", order + _PLY_TYPES[p[2]], 3)]
        else:
            fields.append((p[-1], order + _PLY_TYPES[p[0]]))
    faces = np.frombuffer(body, np.dtype(fields), nf, offset=vdtype.itemsize * nv)
    if nf and not np.all(faces["n"] == 3):
        raise ValueError("faces must all be triangles")
    xyz = np.column_stack([verts[c].astype(float) for c in ("x", "y", "z")])
    extra = {name: faces[name].astype(np.int64) for name, *_ in fields if name not in ("n", "v")}
    return xyz, faces["v"].astype(np.int64), extra


def _ply_ascii(body: bytes, elements: list) -> tuple:
    (_, nv, vprops), (_, nf, fprops) = elements
    rows = body.decode("ascii").split("\n")
    verts = np.array([r.split() for r in rows[:nv]], float).reshape(nv, -1)
    names = [p[-1] for p in vprops]
    xyz = verts[:, [names.index(c) for c in ("x", "y", "z")]]
    face_rows = [r.split() for r in rows[nv : nv + nf]]
    if any(int(r[0]) != 3 for r in face_rows):
        raise ValueError("faces must all be triangles")
    table = np.array(face_rows, np.int64).reshape(nf, -1)
    others = [p[-1] for p in fprops if p[0] != "list"]
    extra = {name: table[:, 4 + k] for k, name in enumerate(others)}
    return xyz, table[:, 1:4], extra


def ply_label_meshes(ply: Path, house: Path | None) -> list[LabelMesh]:
    """One label mesh per object of a Matterport house-segmentation PLY (see the module doc)."""
    verts, faces, extra = read_ply(ply)
    field = next((f for f in FACE_OBJECT_FIELDS if f in extra), None)
    if field is None:
        raise CorruptMeshError(
            f"{ply}: faces carry no object id (looked for {', '.join(FACE_OBJECT_FIELDS)}; "
            f"found {', '.join(extra) or 'none'})"
        )
    classes = read_object_classes(house) if house is not None else {}
    ids = extra[field]
    out = []
    for obj in np.unique(ids):
        sel = faces[ids == obj]
        used, local = np.unique(sel, return_inverse=True)
        known = int(obj) in classes
        name, mpcat40 = classes.get(int(obj), ("unlabeled", UNLABELED))
        out.append(
            LabelMesh(
                re.sub(r"[^A-Za-z0-9_.-]", "_", f"{obj}_{name}"),
                verts[used],
                local.reshape(-1, 3),
                mpcat40 if known else UNLABELED,
                int(obj) + 1 if known else 0,
            )
        )
    return out


def scan_label_meshes(scan: Scan) -> list[LabelMesh]:
    """The label meshes of a scan: from ``semantics.json``, a Matterport PLY, or none.

    A Matterport scan whose PLY is missing logs where it looked and gets no label meshes
    (its segmentation then reads class 0 everywhere but on people).
    """
    if (scan.folder / SEMANTICS).is_file():
        return parts_label_meshes(scan.mesh_parts, SceneLabels.read(scan.folder / SEMANTICS))
    if scan.kind != "matterport" or "mesh" not in scan.meta:
        return []
    ply, house = label_files(Path(scan.meta["mesh"]), scan.scene_id, scan.meta.get("layout", "raw"))
    if not ply.is_file():
        log.warning(
            "%s: no per-face object labels at %s; semantic labels are void", scan.scene_id, ply
        )
        return []
    return ply_label_meshes(ply, house if house.is_file() else None)
