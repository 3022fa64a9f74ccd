"""Procedural texture images: wood, parquet, tiles, carpet, paint, wallpaper, fabric, metal...

Every image is drawn from a ``numpy.random.Generator`` (the house's look generator), so a
seed always gives the same pixels. Images are ``float32`` H×W×3 in [0, 1], top row first;
:func:`to_uint8` converts them for a mesh. Surface textures tile seamlessly: their noise is
white noise low-passed in Fourier space, which is periodic by construction, and every
pattern (planks, tiles, stripes) repeats a whole number of times across the image.
Greyscale textures (carpet, paint, fabric, metal) are meant to be tinted by the material
colour, which MuJoCo multiplies with the texture.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

Image = np.ndarray  # float32 (H, W, 3) in [0, 1]


def to_uint8(image: Image) -> np.ndarray:
    """An image in [0, 1] as H×W×C ``uint8``."""
    return np.round(np.clip(image, 0.0, 1.0) * 255.0).astype(np.uint8)


def noise(rng: np.random.Generator, size: int, cycles: float, aspect: float = 1.0) -> np.ndarray:
    """Tileable smooth noise in [0, 1]: white noise keeping about ``cycles`` waves per image.

    ``aspect`` > 1 stretches the noise along the image's x axis (rows keep detail that
    columns lose), as in wood grain or brushed metal.
    """
    white = rng.standard_normal((size, size))
    fy = np.fft.fftfreq(size)[:, None] * size
    fx = np.fft.rfftfreq(size)[None, :] * size * aspect
    spectrum = np.fft.rfft2(white) * np.exp(-(fx**2 + fy**2) / (2.0 * cycles**2))
    out = np.fft.irfft2(spectrum, s=(size, size))
    lo, hi = out.min(), out.max()
    return ((out - lo) / max(hi - lo, 1e-12)).astype(np.float32)


def fbm(rng: np.random.Generator, size: int, cycles: float, octaves: int = 4) -> np.ndarray:
    """Fractal noise in [0, 1]: octaves of :func:`noise`, each twice as fine and half as loud."""
    total, weight = np.zeros((size, size), np.float32), 0.0
    for k in range(octaves):
        total += 0.5**k * noise(rng, size, cycles * 2**k)
        weight += 0.5**k
    return total / weight


def _rgb(grey: np.ndarray, colour: tuple[float, ...] = (1.0, 1.0, 1.0)) -> Image:
    return np.clip(grey[..., None] * np.asarray(colour[:3], np.float32), 0.0, 1.0)


def _grid(size: int) -> tuple[np.ndarray, np.ndarray]:
    """Pixel-centre coordinates in [0, 1): (u across, v down), each (size, size)."""
    t = (np.arange(size, dtype=np.float32) + 0.5) / size
    return np.meshgrid(t, t)


def _grain(rng: np.random.Generator, size: int, rings: float) -> np.ndarray:
    """Wood grain running along x: ring bands bent by low noise, plus fine streaks."""
    _, v = _grid(size)
    bend = noise(rng, size, 3.0, aspect=4.0)
    bands = 0.5 + 0.5 * np.sin(2 * np.pi * (v * rings + 3.0 * bend))
    streaks = noise(rng, size, size / 6.0, aspect=12.0)
    return 0.75 + 0.12 * bands**3 + 0.13 * streaks


def wood(rng: np.random.Generator, size: int) -> Image:
    """Fine furniture grain along x (grey, to be tinted): no boards, no seams."""
    _, v = _grid(size)
    bend = noise(rng, size, 3.0, aspect=4.0)
    bands = 0.5 + 0.5 * np.sin(2 * np.pi * (v * 14.0 + 2.0 * bend))
    streaks = noise(rng, size, size / 8.0, aspect=10.0)
    return _rgb(0.84 + 0.08 * bands**2 + 0.08 * streaks)


def planks(rng: np.random.Generator, size: int, boards: int = 6) -> Image:
    """Floorboards along x (grey, to be tinted).

    ``boards`` rows, staggered end joints, a tone per board, dark seams.
    """
    grain = _grain(rng, size, rings=boards * 3.0)
    u, v = _grid(size)
    row = np.minimum((v * boards).astype(int), boards - 1)
    joints = rng.uniform(0.0, 1.0, boards)  # one end joint per row per tile
    board = row * 2 + ((u - joints[row]) % 1.0 > 0.5)
    tone = rng.uniform(0.82, 1.12, 2 * boards)[board]
    seam = (np.abs((v * boards + 0.5) % 1.0 - 0.5) < 0.012 * boards) | (
        np.abs(((u - joints[row]) % 0.5) - 0.25) > 0.247
    )
    return _rgb(grain * tone * np.where(seam, 0.55, 1.0))


def parquet(rng: np.random.Generator, size: int, blocks: int = 4) -> Image:
    """Basket-weave parquet (grey, to be tinted).

    ``blocks`` × ``blocks`` squares of three slats, turned a quarter from square to square.
    """
    cell = size // blocks
    along = _grain(rng, cell * 1, rings=9.0)
    u, v = np.meshgrid(np.arange(cell), np.arange(cell))
    grey = np.empty((size, size), np.float32)
    for i in range(blocks):
        for j in range(blocks):
            g = along if (i + j) % 2 == 0 else along.T
            across = v if (i + j) % 2 == 0 else u
            slat = (across * 3) // cell
            seam = np.abs((across * 3 / cell) % 1.0 - 0.5) > 0.46
            tone = rng.uniform(0.85, 1.1, 3)[slat]
            edge = (u == 0) | (v == 0)
            grey[i * cell : (i + 1) * cell, j * cell : (j + 1) * cell] = (
                g * tone * np.where(seam | edge, 0.6, 1.0)
            )
    return _rgb(grey)


def tiles(
    rng: np.random.Generator,
    size: int,
    colour: tuple,
    count: int | None = None,
    layout: str | None = None,
    alternate: tuple | None = None,
    grout: tuple | None = None,
) -> Image:
    """Ceramic tiles, ``count`` (4) per side.

    Laid in a ``"grid"``, running bond (``"brick"``) or ``"checker"`` (with an ``alternate``
    colour). Each tile gets a slight tone of its own and a darker bevel at its edges; grout lines
    are about 1/40 of a tile wide.
    """
    count, layout = count or 4, layout or "grid"
    grout = grout or (0.78, 0.77, 0.74)
    u, v = _grid(size)
    rows = count * (2 if layout == "brick" else 1)
    y = v * rows
    x = u * count + np.where(layout == "brick", 0.5 * (np.floor(y) % 2), 0.0)
    fx, fy = x % 1.0, y % 1.0
    ix, iy = np.floor(x).astype(int) % count, np.floor(y).astype(int) % rows
    tone = rng.uniform(0.94, 1.04, (rows, count))[iy, ix]
    base = np.broadcast_to(np.asarray(colour[:3], np.float32), (size, size, 3)).copy()
    if layout == "checker" and alternate is not None:
        odd = (ix + iy) % 2 == 1
        base[odd] = np.asarray(alternate[:3], np.float32)
    edge = np.minimum(np.minimum(fx, 1 - fx) * (rows / count if layout == "brick" else 1.0), 1.0)
    edge = np.minimum(edge, np.minimum(fy, 1 - fy))
    bevel = np.clip(edge / 0.06, 0.0, 1.0) ** 0.5
    speckle = 0.97 + 0.06 * noise(rng, size, size / 8.0)
    out = base * (tone * (0.88 + 0.12 * bevel) * speckle)[..., None]
    out[edge < 0.018] = np.asarray(grout, np.float32)
    return np.clip(out, 0.0, 1.0)


def carpet(rng: np.random.Generator, size: int) -> Image:
    """Cut-pile carpet (grey, to be tinted): fine fibre noise over soft mottling."""
    grey = 0.78 + 0.14 * noise(rng, size, size / 3.0) + 0.08 * fbm(rng, size, 4.0, 3)
    return _rgb(grey)


def paint(rng: np.random.Generator, size: int) -> Image:
    """Matt paint (grey, to be tinted): faint roller marks and orange peel."""
    grey = 0.94 + 0.035 * fbm(rng, size, 3.0, 3) + 0.025 * noise(rng, size, size / 4.0)
    return _rgb(grey)


def wallpaper(rng: np.random.Generator, size: int, pattern: str) -> Image:
    """Wallpaper (grey, to be tinted): ``"stripes"`` or a ``"lattice"`` of small diamonds."""
    u, v = _grid(size)
    if pattern == "stripes":
        mask = np.abs(((u * 8) % 1.0) - 0.5) < 0.18
    else:
        d = np.abs(((u * 6) % 1.0) - 0.5) + np.abs(((v * 6) % 1.0) - 0.5)
        mask = (d < 0.16) | (np.abs(d - 0.5) < 0.02)
    paper = 0.95 + 0.05 * noise(rng, size, size / 5.0)
    return _rgb(np.where(mask, 0.84, 1.0) * paper)


def fabric(rng: np.random.Generator, size: int, threads: int = 48) -> Image:
    """Woven upholstery (grey, to be tinted): a fine basket weave with slubs."""
    u, v = _grid(size)
    weave = 0.5 + 0.25 * (np.sin(2 * np.pi * u * threads) + np.sin(2 * np.pi * v * threads))
    slub = noise(rng, size, size / 10.0, aspect=3.0)
    return _rgb(0.72 + 0.14 * weave + 0.14 * slub)


def brushed(rng: np.random.Generator, size: int) -> Image:
    """Brushed metal (grey, to be tinted): long streaks along x."""
    return _rgb(0.78 + 0.2 * noise(rng, size, size / 4.0, aspect=40.0))


def marble(rng: np.random.Generator, size: int, colour: tuple, vein: tuple) -> Image:
    """Stone worktop: ``vein`` coloured veins wandering across a ``colour`` ground."""
    u, v = _grid(size)
    turb = fbm(rng, size, 2.0, 5)
    line = np.abs(np.sin(2 * np.pi * (u + v + 2.5 * turb)))
    veins = np.exp(-line / 0.08)[..., None]
    ground = np.asarray(colour[:3]) * (0.93 + 0.07 * noise(rng, size, size / 6.0))[..., None]
    return np.clip(ground * (1 - veins) + np.asarray(vein[:3]) * veins, 0, 1).astype(np.float32)


def leaves(rng: np.random.Generator, size: int) -> Image:
    """Foliage: clumps of leaves in several greens, darker in the gaps."""
    greens = np.array([[0.16, 0.36, 0.12], [0.24, 0.48, 0.16], [0.33, 0.56, 0.2]], np.float32)
    pick = noise(rng, size, size / 10.0)
    shade = fbm(rng, size, size / 16.0, 2)
    idx = np.minimum((pick * 3).astype(int), 2)
    return np.clip(greens[idx] * (0.45 + 0.8 * shade)[..., None], 0, 1)


def books(rng: np.random.Generator, size: int) -> Image:
    """A row of book spines filling the height, with shadowed gaps above shorter books."""
    palette = np.array(
        [[0.55, 0.12, 0.1], [0.12, 0.2, 0.42], [0.16, 0.34, 0.2], [0.8, 0.7, 0.5], [0.2, 0.2, 0.22],
         [0.62, 0.42, 0.16], [0.85, 0.84, 0.8], [0.4, 0.15, 0.3]], np.float32)  # fmt: skip
    out = np.full((size, size, 3), 0.08, np.float32)
    x = 0
    while x < size:
        w = int(rng.integers(size // 40 + 2, size // 14 + 3))
        top = int(rng.integers(0, size // 4))
        colour = palette[rng.integers(len(palette))] * rng.uniform(0.8, 1.1)
        band = int(rng.integers(size // 6, size // 2))
        out[top:, x : x + w - 1] = colour
        out[band : band + max(2, size // 40), x : x + w - 1] *= 0.6
        x += w
    return np.clip(out, 0, 1)


def art(rng: np.random.Generator, size: int) -> Image:
    """A painting: a landscape with hills, or an abstract of coloured blocks."""
    u, v = _grid(size)
    if rng.random() < 0.5:
        sky = (
            np.array([0.5, 0.68, 0.9])
            + (np.array([0.95, 0.85, 0.7]) - [0.5, 0.68, 0.9]) * v[..., None]
        )
        out = sky.astype(np.float32)
        for k, colour in enumerate(([0.45, 0.55, 0.35], [0.3, 0.45, 0.25], [0.25, 0.32, 0.18])):
            ridge = 0.45 + 0.12 * k + 0.12 * (noise(rng, size, 2.0 + k)[0] - 0.5)
            out[v > ridge[None, :]] = np.asarray(colour) * rng.uniform(0.85, 1.15)
        return np.clip(out, 0, 1)
    out = np.full((size, size, 3), rng.uniform(0.75, 0.95), np.float32)
    for _ in range(int(rng.integers(4, 8))):
        x0, y0 = rng.uniform(0, 0.8, 2)
        x1, y1 = x0 + rng.uniform(0.1, 0.5), y0 + rng.uniform(0.1, 0.5)
        out[(u > x0) & (u < x1) & (v > y0) & (v < y1)] = rng.uniform(0.1, 0.9, 3)
    return out


def sky(rng: np.random.Generator, size: int) -> Image:
    """A daylight view through a window: sky with clouds over trees and a lawn."""
    _, v = _grid(size)
    top, horizon = np.array([0.5, 0.68, 0.93]), np.array([0.88, 0.93, 0.98])
    out = (top + (horizon - top) * (v / 0.62)[..., None]).astype(np.float32)
    clouds = np.clip((fbm(rng, size, 3.0, 4) - 0.55) * 4.0, 0, 1)[..., None]
    out = out * (1 - clouds) + clouds
    trees = 0.55 + 0.1 * (noise(rng, size, 6.0)[0] - 0.5)
    canopy = leaves(rng, size) * 1.1
    out = np.where((v > trees[None, :])[..., None], canopy, out)
    lawn = np.array([0.35, 0.55, 0.22]) * (0.85 + 0.3 * noise(rng, size, size / 8.0))[..., None]
    out = np.where((v > 0.8)[..., None], lawn, out)
    return np.clip(out, 0, 1).astype(np.float32)


def rug(rng: np.random.Generator, size: int, colour: tuple, accent: tuple) -> Image:
    """A rug: bordered bands around a field of diamonds (one image per rug, not tiled)."""
    u, v = _grid(size)
    edge = np.minimum(np.minimum(u, 1 - u), np.minimum(v, 1 - v))
    d = np.abs(((u * 5) % 1.0) - 0.5) + np.abs(((v * 3) % 1.0) - 0.5)
    field = np.where((d < 0.25)[..., None], np.asarray(accent[:3]), np.asarray(colour[:3]))
    band = ((edge > 0.04) & (edge < 0.07)) | ((edge > 0.1) & (edge < 0.11))
    out = np.where(band[..., None], np.asarray(accent[:3]), field)
    out = np.where((edge < 0.04)[..., None], np.asarray(colour[:3]) * 0.7, out)
    pile = 0.85 + 0.15 * noise(rng, size, size / 3.0)
    return np.clip(out * pile[..., None], 0, 1).astype(np.float32)


def shade_ramp(size: int, strength: float) -> np.ndarray:
    """A black RGBA ``uint8`` strip, clear at its top row and ``strength`` opaque at its bottom.

    Its bottom row is texture v = 0.

    Laid along a corner (wall foot, ceiling edge), it darkens the corner like the ambient
    occlusion a renderer without global illumination leaves out.
    """
    t = (np.arange(size, dtype=np.float32) + 0.5) / size
    alpha = strength * t**2
    out = np.zeros((size, 4, 4), np.float32)
    out[..., 3] = alpha[:, None]
    return to_uint8(out)


def soft_patch(size: int, colour: tuple, strength: float, feather: float = 0.3) -> np.ndarray:
    """An RGBA ``uint8`` square of ``colour`` whose alpha falls smoothly to 0 at its border.

    Dark, it is the contact shadow under furniture; warm white, a patch of daylight.
    """
    u, v = _grid(size)
    edge = np.minimum(np.minimum(u, 1 - u), np.minimum(v, 1 - v)) / (0.5 * feather)
    alpha = strength * np.clip(edge, 0.0, 1.0) ** 2
    out = np.empty((size, size, 4), np.float32)
    out[..., :3] = np.asarray(colour[:3], np.float32)
    out[..., 3] = alpha
    return to_uint8(out)


GENERATORS: dict[str, Callable[..., Image]] = {
    "planks": planks,
    "parquet": parquet,
    "tiles": tiles,
    "carpet": carpet,
    "paint": paint,
    "wood": wood,
    "wallpaper": wallpaper,
    "fabric": fabric,
    "brushed": brushed,
    "marble": marble,
    "leaves": leaves,
    "books": books,
    "art": art,
    "sky": sky,
    "rug": rug,
}
"""Texture kinds by name, as the material library names them."""
