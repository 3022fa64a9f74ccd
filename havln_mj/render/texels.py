"""Texture sizes fitted to what the camera resolves: no texel is kept that a frame cannot show.

A camera whose frames are ``H`` pixels tall with a vertical field of view ``vfov`` sees, at
distance ``d``, about ``H / (2 · tan(vfov / 2) · d)`` pixels per metre. A texture drawn on a
surface at more texels per metre than that is only ever sampled through its coarser mipmap
levels, yet its full size is kept twice: in the model (``tex_data``) and, with its mipmaps,
by the OpenGL driver (a CPU renderer holds it in host memory, as RGBA). So the world builder
halves such a texture (2×2 box filter, the mipmap's own rule) until its density on the
surfaces using it is at most the camera's at :data:`REACH_M`: about the camera's height
over the floor, nearer than which it seldom sees a surface. At 640×480 and 60° that is 277
texels per metre; the built-in houses' floor, clothes and picture textures drop from 512 or
256 to 256, 128 or 64 texels a side, and frames change by under one grey level on average
(a wall seen from closer than the reach looks slightly softer side by side).

The density of a texture is measured on its surfaces: ``sqrt(texel area / surface area)``,
summing each triangle's area in texture space (in texels, repeats included) and in metres.
"""

from __future__ import annotations

import math

import numpy as np

REACH_M = 1.5
"""The distance in metres at which textures keep the detail a frame resolves."""

MIN_SIZE = 8
"""The fewest texels on a texture's shorter side that halving leaves."""


def resolved_density(height_px: int, vfov_deg: float, reach_m: float = REACH_M) -> float:
    """Pixels per metre a frame ``height_px`` tall at ``vfov_deg`` shows at ``reach_m``."""
    return height_px / (2.0 * math.tan(math.radians(vfov_deg) / 2.0) * reach_m)


def surface_areas(vertices: np.ndarray, faces: np.ndarray, uv: np.ndarray) -> tuple[float, float]:
    """``(texture-space area in UV units², surface area in m²)`` of a textured mesh.

    Args:
        vertices: (V, 3) positions in metres.
        faces: (F, 3) vertex indices.
        uv: (V, 2) texture coordinates (1 spans the image once).
    """
    if len(faces) == 0:
        return 0.0, 0.0
    tri = np.asarray(vertices, np.float64)[faces]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = 0.5 * float(np.sqrt(np.einsum("ij,ij->i", cross, cross)).sum())
    t = np.asarray(uv, np.float64)[faces]
    a, b = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
    uv_area = 0.5 * float(np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]).sum())
    return uv_area, area


def halvings(shape: tuple[int, ...], uv_area: float, area: float, limit: float | None) -> int:
    """How many times a texture of ``shape`` (H, W, ...) is halved to be at most ``limit``.

    ``uv_area`` and ``area`` are its surfaces' sums (:func:`surface_areas`); ``limit`` is in
    texels per metre (None, or surfaces without area: never halved). Halving stops at
    :data:`MIN_SIZE` texels.
    """
    if limit is None or area <= 0.0 or uv_area <= 0.0:
        return 0
    height, width = shape[0], shape[1]
    density = math.sqrt(uv_area * height * width / area)
    times = 0
    while density > limit and min(height, width) >= 2 * MIN_SIZE:
        density, height, width, times = density / 2.0, height // 2, width // 2, times + 1
    return times


def shrink(image: np.ndarray, times: int) -> np.ndarray:
    """``image`` (H×W×C ``uint8``) halved ``times`` times by 2×2 box filtering, rounded.

    An odd last row or column is dropped before each halving (a texture's UVs address the
    whole image, so a lost edge line shifts it by under half a texel of the result).
    """
    out = image
    for _ in range(times):
        h, w = out.shape[0] // 2, out.shape[1] // 2
        blocks = out[: 2 * h, : 2 * w].reshape(h, 2, w, 2, out.shape[2]).astype(np.uint16)
        out = ((blocks.sum(axis=(1, 3)) + 2) // 4).astype(np.uint8)
    return out
