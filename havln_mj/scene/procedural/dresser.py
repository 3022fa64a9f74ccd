"""The collector of a house's look: triangles by (object instance, material), and labels."""

from __future__ import annotations

import numpy as np

from havln_mj.scene.matterport.categories import Instance, SceneLabels, mpcat40_index
from havln_mj.scene.mesh import MeshPart
from havln_mj.scene.procedural.materials import Material, Palette
from havln_mj.scene.procedural.primitives import Solid, merge


class Dresser:
    """Collects a house's triangles by (instance, material) and its instances' labels."""

    def __init__(self, palette: Palette) -> None:
        self.palette = palette
        self.instances: list[Instance] = []
        self._pieces: dict[tuple[int, str], list[Solid]] = {}

    def instance(
        self, category: str, mpcat40: str, region: int = -1, obj: int | None = None
    ) -> int:
        """A new instance id (1, 2, ...) of an object of ``category`` in mpcat40 ``mpcat40``."""
        iid = len(self.instances) + 1
        self.instances.append(Instance(iid, category, mpcat40_index(mpcat40), region, obj))
        return iid

    def add(self, instance: int, material: Material, solid: Solid) -> None:
        """Draws ``solid`` in ``material`` as part of ``instance``."""
        self._pieces.setdefault((instance, material.key), []).append(solid)

    def parts(self) -> tuple[list[MeshPart], SceneLabels]:
        """The mesh parts, one per (instance, material), and their labels."""
        parts, names = [], {}
        textures = self.palette.textures
        for (iid, key), solids in self._pieces.items():
            material = self.palette.materials[key]
            solid = merge(solids)
            uv = None
            if material.texture is not None:
                scale = material.tile_m if material.tile_m > 0 else 1.0
                uv = (solid.uv / scale).astype(np.float32)
            name = f"{iid}:{key}"
            names[name] = iid
            parts.append(
                MeshPart(
                    name,
                    solid.vertices,
                    solid.faces,
                    material.rgba,
                    uv,
                    None if material.texture is None else textures[material.texture],
                    material.shine,
                    material.emission,
                )
            )
        return parts, SceneLabels(tuple(self.instances), names)
