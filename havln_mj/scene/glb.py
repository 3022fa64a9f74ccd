"""Reading back the binary glTF files this package writes, with numpy (and Pillow for images).

:func:`havln_mj.scene.mesh.write_glb` writes a plain subset of glTF 2.0: one buffer in the
file's BIN chunk, root nodes each naming one mesh of one indexed triangle primitive with
``POSITION`` and, when textured, ``TEXCOORD_0``, PBR materials with a base colour factor and
optionally a base colour texture stored in the buffer (JPEG or PNG). :func:`read_own_glb`
reads that subset into :class:`Piece` objects without trimesh (which would bring scipy and
networkx into every process that renders a scan). It gives exactly the arrays the trimesh
path of :func:`~havln_mj.scene.mesh.load_mesh_parts` gives, in the same order, and returns
None for any file outside the subset (not marked as ours, node transforms or children,
several primitives, sparse or strided accessors, extensions...): the caller then reads the
file with trimesh.
"""

from __future__ import annotations

import hashlib
import io
import json
import struct
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from havln_mj.errors import CorruptMeshError
from havln_mj.scene.materials import image_array

MARKER = {"havln_mj": {"parts": "node"}}
"""glTF scene ``extras`` of a file written one part per node."""

_MAGIC = b"glTF"
_JSON_CHUNK = 0x4E4F534A
_BIN_CHUNK = 0x004E4942
_TRIANGLES = 4
_COMPONENTS = {5121: "u1", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
_WIDTHS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3}
_ATTRIBUTES = {"POSITION", "NORMAL", "TEXCOORD_0"}
_PLAIN_NODE = {"name", "mesh"}
_MATERIAL_KEYS = {"name", "pbrMetallicRoughness", "doubleSided", "alphaMode", "emissiveFactor"}
_IMAGE_TYPES = ("image/jpeg", "image/png")


class Piece(NamedTuple):
    """One node's triangles and look, before pieces of one part are merged."""

    name: str
    vertices: np.ndarray  # (V, 3) float64
    faces: np.ndarray  # (F, 3) integer
    uv: np.ndarray | None  # (V, 2) float32, origin at the image's bottom left
    texture: np.ndarray | None  # H×W×3|4 uint8, top row first
    rgba: tuple[float, float, float, float]
    shine: float
    emission: float


class _OutsideError(Exception):
    """The file uses glTF beyond what the package writes."""


def read_own_glb(path: Path, max_texture_size: int | None) -> list[Piece] | None:
    """The pieces of a ``.glb`` written by ``write_glb``, or None for any other file.

    Pieces come in the order trimesh walks the nodes (last root first), each named after
    its mesh; pieces whose images decode to the same pixels share one texture array. Only
    the JSON chunk of a file that is not ours is read.

    Raises:
        CorruptMeshError: The file is marked as ours but its buffer, buffer ranges, indices
            or images are broken.
    """
    with path.open("rb") as file:
        start = file.read(20)
        if len(start) < 20 or start[:4] != _MAGIC:
            return None
        version, length, size, kind = struct.unpack_from("<IIII", start, 4)
        if version != 2 or kind != _JSON_CHUNK:
            return None
        try:
            header = json.loads(file.read(size))
            scene = header["scenes"][header.get("scene", 0)]
            if scene.get("extras") != MARKER:
                return None
        except (ValueError, KeyError, IndexError, TypeError, AttributeError):
            return None
        rest = file.read()
    if 20 + size + len(rest) < length:
        raise CorruptMeshError(f"{path}: the GLB header says {length} bytes, the file is shorter")
    try:
        return _Reader(header, _bin_chunk(rest, path), path, max_texture_size).pieces()
    except _OutsideError:
        return None
    except (KeyError, IndexError, TypeError, ValueError) as exc:
        raise CorruptMeshError(f"{path}: malformed glTF ({type(exc).__name__}: {exc})") from exc


def _bin_chunk(rest: bytes, path: Path) -> bytes:
    """The BIN chunk's bytes from what follows the JSON chunk (empty when there is none)."""
    if len(rest) < 8:
        return b""
    size, kind = struct.unpack_from("<II", rest)
    if kind != _BIN_CHUNK:
        raise _OutsideError
    if 8 + size > len(rest):
        raise CorruptMeshError(f"{path}: the GLB BIN chunk runs past the end of the file")
    return rest[8 : 8 + size]


def first_alike(texture: np.ndarray, seen: dict[tuple, np.ndarray]) -> np.ndarray:
    """The first array in ``seen`` with ``texture``'s pixels (``texture``, and noted, if none).

    glTF materials that share an image may each get their own copy of it: drawing them with
    one array lets the world builder upload it, and merge the parts using it, once.
    """
    digest = (texture.shape, hashlib.blake2b(texture.data).digest())
    return seen.setdefault(digest, texture)


class _Reader:
    """Pieces of one parsed file (raises :class:`_OutsideError` beyond the written subset)."""

    def __init__(
        self, header: dict[str, Any], binary: bytes, path: Path, max_size: int | None
    ) -> None:
        self.header, self.binary, self.path, self.max_size = header, binary, path, max_size
        self.images: dict[int, np.ndarray] = {}  # image index -> pixels
        self.same_image: dict[tuple, np.ndarray] = {}  # pixels' digest -> first array

    def pieces(self) -> list[Piece]:
        h = self.header
        if h.get("extensionsUsed") or len(h.get("buffers", [])) > 1:
            raise _OutsideError
        if any("uri" in b for b in h.get("buffers", [])):
            raise _OutsideError
        scene = h["scenes"][h.get("scene", 0)]
        roots = scene.get("nodes", [])
        nodes = [h["nodes"][i] for i in roots]
        names = [m.get("name") for m in h.get("meshes", [])]
        node_names = [n.get("name") for n in nodes]
        if len(set(roots)) != len(roots) or None in names or len(set(names)) != len(names):
            raise _OutsideError
        if None in node_names or len(set(node_names)) != len(node_names):
            raise _OutsideError
        if any(set(n) - _PLAIN_NODE for n in nodes):
            raise _OutsideError
        out = []
        for node in reversed(nodes):  # trimesh pops its queue of roots from the end
            if "mesh" in node:
                piece = self._piece(h["meshes"][node["mesh"]])
                if piece is not None:
                    out.append(piece)
        return out

    def _piece(self, mesh: dict[str, Any]) -> Piece | None:
        if set(mesh) - {"name", "primitives", "extras"} or len(mesh["primitives"]) != 1:
            raise _OutsideError
        (prim,) = mesh["primitives"]
        attributes = prim["attributes"]
        if set(prim) - {"attributes", "indices", "mode", "material"} or "material" not in prim:
            raise _OutsideError
        if prim.get("mode", _TRIANGLES) != _TRIANGLES or set(attributes) - _ATTRIBUTES:
            raise _OutsideError
        if "indices" not in prim:
            raise _OutsideError
        vertices = self._accessor(attributes["POSITION"], "VEC3").astype(np.float64)
        flat = self._accessor(prim["indices"], "SCALAR")
        if flat.dtype.kind != "u":
            raise _OutsideError
        if len(flat) % 3:
            raise CorruptMeshError(f"{self.path}: {mesh['name']!r} has {len(flat)} indices")
        if len(flat) == 0:
            return None
        if int(flat.max()) >= len(vertices):
            raise CorruptMeshError(
                f"{self.path}: {mesh['name']!r} indexes vertex {int(flat.max())} of {len(vertices)}"
            )
        material = self.header["materials"][prim["material"]]
        rgba, shine, emission, image = self._look(material)
        uv = texture = None
        if image is not None and "TEXCOORD_0" in attributes:
            uv = self._accessor(attributes["TEXCOORD_0"], "VEC2").copy()
            uv[:, 1] = 1.0 - uv[:, 1]  # glTF's origin is the image's top left
            if uv.dtype != np.float32 or uv.shape != (len(vertices), 2):
                raise CorruptMeshError(
                    f"{self.path}: {mesh['name']!r} has {len(uv)} float texture "
                    f"coordinates for {len(vertices)} vertices"
                )
            texture = self._image(image)
        faces = flat.reshape(-1, 3)
        return Piece(mesh["name"], vertices, faces, uv, texture, rgba, shine, emission)

    def _look(self, material: dict[str, Any]) -> tuple[tuple, float, float, int | None]:
        """(rgba, shine, emission, image index or None) of a material, as trimesh reads it."""
        if set(material) - _MATERIAL_KEYS:
            raise _OutsideError
        pbr = material.get("pbrMetallicRoughness", {})
        if "baseColorFactor" not in pbr:
            raise _OutsideError
        # trimesh keeps the factor as uint8 RGBA; the part's colour is that over 255.
        factor = np.array(pbr["baseColorFactor"], dtype=np.float64)
        factor[~np.isfinite(factor)] = 0.0
        if factor.shape != (4,):
            raise _OutsideError
        colour = np.clip(factor * 255, 0.0, 255).round().astype(np.uint8).astype(float)
        if colour.max() > 1.0:
            colour = colour / 255.0
        rgba = tuple(float(v) for v in colour)
        roughness = pbr.get("roughnessFactor")
        shine = 0.0 if roughness is None else float(np.clip(1.0 - float(roughness), 0.0, 1.0))
        emissive = material.get("emissiveFactor")
        emission = 0.0
        if emissive is not None:
            emission = float(np.clip(np.max(np.array(emissive, np.float64).reshape(3)), 0, 1))
        texture = pbr.get("baseColorTexture")
        if texture is None:
            return rgba, shine, emission, None
        if set(texture) != {"index"}:
            raise _OutsideError
        entry = self.header["textures"][texture["index"]]
        if set(entry) != {"source"}:
            raise _OutsideError
        return rgba, shine, emission, entry["source"]

    def _image(self, index: int) -> np.ndarray:
        """An image's pixels (once per image; images with equal pixels share one array)."""
        texture = self.images.get(index)
        if texture is not None:
            return texture
        from PIL import Image  # only when a textured scan is read

        entry = self.header["images"][index]
        if set(entry) != {"bufferView", "mimeType"} or entry["mimeType"] not in _IMAGE_TYPES:
            raise _OutsideError
        view = self.header["bufferViews"][entry["bufferView"]]
        start, end = self._view_range(view)
        try:
            image = Image.open(io.BytesIO(self.binary[start:end]))
        except Exception as exc:  # PIL raises many types for bad images
            raise CorruptMeshError(
                f"{self.path}: cannot read image {index} ({type(exc).__name__}: {exc})"
            ) from exc
        texture = self.images[index] = first_alike(
            image_array(image, self.path, self.max_size), self.same_image
        )
        return texture

    def _view_range(self, view: dict[str, Any]) -> tuple[int, int]:
        if view.get("buffer", 0) != 0 or "byteStride" in view:
            raise _OutsideError
        start = int(view.get("byteOffset", 0))
        end = start + int(view["byteLength"])
        if start < 0 or end > len(self.binary):
            raise CorruptMeshError(f"{self.path}: a buffer view runs past the BIN chunk")
        return start, end

    def _accessor(self, index: int, kind: str) -> np.ndarray:
        """An accessor's values as a read-only (count, width) view (count, for scalars)."""
        acc = self.header["accessors"][index]
        if set(acc) - {"bufferView", "byteOffset", "componentType", "count", "type", "max", "min"}:
            raise _OutsideError
        if acc["type"] != kind or acc["componentType"] not in _COMPONENTS:
            raise _OutsideError
        dtype = np.dtype(_COMPONENTS[acc["componentType"]])
        width = _WIDTHS[kind]
        start, end = self._view_range(self.header["bufferViews"][acc["bufferView"]])
        start += int(acc.get("byteOffset", 0))
        count = int(acc["count"])
        if count < 0 or start + count * width * dtype.itemsize > end:
            raise CorruptMeshError(f"{self.path}: accessor {index} runs past its buffer view")
        values = np.frombuffer(self.binary, dtype, count * width, start)
        return values if width == 1 else values.reshape(count, width)
