"""Clothes, hair and skin for Anny bodies: a painted texture per person and a hair shell.

Clothes are painted into each person's texture through the catalog's UVs: every texel knows
the face it shows and where in it, hence its rest position on the body (our body frame) and
the joint that mostly carries it, so cuts (sleeves, neckline, waist, hems, shoe tops) follow
the body and fabric patterns (stripes, checks, denim, knit) are solid textures, continuous
across UV seams. Faces get eyes, brows and lips the same way. Hair is geometry: the scalp
(and for long hair the back of the neck) copied and pushed out along the normals, using the
scalp's hair-coloured texels. A skirt is a flared tube hanging from the waist
(:func:`skirt_mesh`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from havln_mj.humans.anny_data import AnnyBody
from havln_mj.humans.skeleton import JOINT
from havln_mj.humans.skinned import vertex_normals

RGB = tuple[float, float, float]

SKIN_TONES = (
    (0.96, 0.80, 0.69),
    (0.89, 0.68, 0.53),
    (0.78, 0.57, 0.42),
    (0.62, 0.43, 0.30),
    (0.45, 0.31, 0.21),
    (0.33, 0.22, 0.15),
)

TOPS = (
    (0.80, 0.15, 0.15), (0.15, 0.35, 0.75), (0.20, 0.55, 0.30), (0.90, 0.75, 0.20),
    (0.55, 0.30, 0.60), (0.95, 0.95, 0.92), (0.20, 0.20, 0.22), (0.85, 0.45, 0.15),
    (0.40, 0.60, 0.80), (0.70, 0.70, 0.72), (0.95, 0.60, 0.70), (0.35, 0.25, 0.20),
)  # fmt: skip
BOTTOMS = (
    (0.15, 0.18, 0.30), (0.25, 0.25, 0.27), (0.45, 0.35, 0.25), (0.60, 0.58, 0.52),
    (0.20, 0.28, 0.45), (0.10, 0.10, 0.12), (0.40, 0.42, 0.30),
)  # fmt: skip
SKIRTS = ((0.55, 0.15, 0.25), (0.15, 0.20, 0.40), (0.12, 0.12, 0.14), (0.45, 0.50, 0.30))
SHOES = (
    (0.08, 0.08, 0.08),
    (0.35, 0.20, 0.10),
    (0.78, 0.78, 0.80),
    (0.30, 0.30, 0.35),
    (0.15, 0.17, 0.30),
)
HAIR = (
    (0.08, 0.06, 0.05), (0.20, 0.12, 0.07), (0.38, 0.24, 0.12), (0.62, 0.45, 0.25),
    (0.80, 0.65, 0.40), (0.45, 0.18, 0.08),
)  # fmt: skip
GREY_HAIR = ((0.62, 0.62, 0.62), (0.82, 0.82, 0.80), (0.45, 0.45, 0.46))
TOP_PATTERNS = ("plain", "plain", "stripes", "checks", "knit")
HAIR_STYLES = ("none", "short", "long")

SKIN, TOP, BOTTOM, SHOES_PART, HAIR_PART, EYE_WHITE, IRIS, LIPS, BROWS = range(9)
SHORT_HAIR_M, LONG_HAIR_M = 0.010, 0.016  # how far hair stands off the scalp


@dataclass(frozen=True)
class Outfit:
    """How one person looks.

    Attributes:
        skin: Skin RGB.
        top: Shirt RGB.
        top_pattern: ``"plain"``, ``"stripes"``, ``"checks"`` or ``"knit"``.
        accent: Second colour of patterns.
        long_sleeves: Sleeves to the wrist (else to mid upper arm).
        bottom: ``"trousers"``, ``"shorts"`` or ``"skirt"``.
        bottom_rgb: Trousers, shorts or skirt RGB.
        denim: Trousers or shorts woven like denim.
        shoes: Shoe RGB.
        hair: ``"none"``, ``"short"`` or ``"long"``.
        hair_rgb: Hair (and brow) RGB.
    """

    skin: RGB
    top: RGB
    top_pattern: str
    accent: RGB
    long_sleeves: bool
    bottom: str
    bottom_rgb: RGB
    denim: bool
    shoes: RGB
    hair: str
    hair_rgb: RGB


def random_outfit(rng: np.random.Generator, body: AnnyBody) -> Outfit:
    """An outfit drawn from ``rng``, likelier choices depending on the body's age and sex."""

    def pick(options: tuple) -> tuple:
        return options[int(rng.integers(len(options)))]

    female = body.female > 0.5
    elder = body.age > 0.86
    bottom = "trousers"
    if female and rng.random() < 0.4:
        bottom = "skirt"
    elif rng.random() < 0.15:
        bottom = "shorts"
    if female:
        hair = "long" if rng.random() < 0.7 else "short"
    else:
        hair = "none" if rng.random() < (0.35 if elder else 0.08) else "short"
    hair_rgb = pick(GREY_HAIR) if elder and rng.random() < 0.8 else pick(HAIR)
    top = pick(TOPS)
    accent = pick([c for c in TOPS if c != top])
    return Outfit(
        skin=pick(SKIN_TONES),
        top=top,
        top_pattern=pick(TOP_PATTERNS),
        accent=accent,
        long_sleeves=bool(rng.random() < 0.5),
        bottom=bottom,
        bottom_rgb=pick(SKIRTS) if bottom == "skirt" else pick(BOTTOMS),
        denim=bottom != "skirt" and bool(rng.random() < 0.4),
        shoes=pick(SHOES),
        hair=hair,
        hair_rgb=hair_rgb,
    )


def _landmarks(body: AnnyBody) -> dict[str, np.ndarray | float]:
    a, eyes = body.joints, body.eyes
    j = JOINT
    return {
        "eyes": eyes,
        "eye_z": float(eyes[:, 2].mean()),
        "eye_y": float(eyes[:, 1].mean()),
        "head": float(np.linalg.norm(eyes[0] - eyes[1])),  # interpupillary distance
        "waist_z": float(a[j["pelvis"], 2] + 0.35 * (a[j["spine1"], 2] - a[j["pelvis"], 2])),
        "neck_z": float(0.6 * a[j["neck"], 2] + 0.4 * a[j["spine3"], 2]),
        "knee_z": float(a[j["left_knee"], 2]),
        "hip_z": float(a[j["left_hip"], 2]),
        "ankle_z": float(a[j["left_ankle"], 2]),
        "front_y": float(a[j["neck"], 1]),
    }


def _arm_fraction(p: np.ndarray, owner: np.ndarray, body: AnnyBody) -> np.ndarray:
    """How far along the arm each point lies: 0 at the shoulder, 1 at the elbow, 2 at the wrist."""
    a = body.joints
    out = np.full(len(p), -1.0)
    for side in ("left", "right"):
        s, e, w = (a[JOINT[f"{side}_{n}"]] for n in ("shoulder", "elbow", "wrist"))
        upper = owner == JOINT[f"{side}_shoulder"]
        lower = np.isin(owner, [JOINT[f"{side}_elbow"], JOINT[f"{side}_wrist"]])
        for mask, start, end, base in ((upper, s, e, 0.0), (lower, e, w, 1.0)):
            d = end - start
            out[mask] = base + (p[mask] - start) @ d / (d @ d)
    return out


def part_labels(p: np.ndarray, owner: np.ndarray, body: AnnyBody, outfit: Outfit) -> np.ndarray:
    """What covers each rest point ``p (N, 3)`` whose main joint is ``owner (N,)``: SKIN … BROWS."""
    lm = _landmarks(body)
    _x, y, z = p[:, 0], p[:, 1], p[:, 2]
    out = np.full(len(p), SKIN, np.int8)
    trunk = np.isin(owner, [JOINT[n] for n in ("spine1", "spine2", "spine3")])
    trunk |= np.isin(owner, [JOINT["left_collar"], JOINT["right_collar"], JOINT["pelvis"]])
    trunk &= z > lm["waist_z"]
    neckline = z > lm["neck_z"] - np.where(y > lm["front_y"], 0.02 * lm["head"] / 0.063, 0.0)
    out[trunk & ~neckline] = TOP
    arm = _arm_fraction(p, owner, body)
    sleeve_end = 1.92 if outfit.long_sleeves else 0.5
    out[(arm >= -0.5) & (arm <= sleeve_end)] = TOP
    legs = np.isin(owner, [JOINT[n] for n in ("left_hip", "right_hip", "left_knee", "right_knee")])
    legs |= (owner == JOINT["pelvis"]) & (z <= lm["waist_z"])
    hem = {
        "trousers": lm["ankle_z"] + 0.03,
        "shorts": lm["knee_z"] + 0.08,
        "skirt": lm["hip_z"] - 0.1,  # briefs under the skirt; the skirt itself is geometry
    }[outfit.bottom]
    out[legs & (z > hem)] = BOTTOM
    feet = np.isin(
        owner, [JOINT[n] for n in ("left_ankle", "right_ankle", "left_foot", "right_foot")]
    )
    feet |= np.isin(owner, [JOINT["left_knee"], JOINT["right_knee"]]) & (z < lm["ankle_z"] + 0.03)
    out[feet & (z < lm["ankle_z"] + 0.035)] = SHOES_PART
    if outfit.hair != "none":
        out[hair_mask(p, owner, body, outfit.hair)] = HAIR_PART
    _face(p, owner, out, lm)
    return out


def hair_mask(p: np.ndarray, owner: np.ndarray, body: AnnyBody, style: str) -> np.ndarray:
    """Which rest points ``p`` lie under hair of ``style`` (``"short"`` or ``"long"``)."""
    lm = _landmarks(body)
    s = lm["head"] / 0.063
    head = body.joints[JOINT["head"]]
    rel_z, rel_y = p[:, 2] - lm["eye_z"], p[:, 1] - lm["eye_y"]
    on_head = owner == JOINT["head"]
    # The hairline: high over the face, lower toward the nape, above the ears at the side.
    front = rel_y > -0.03 * s
    line = np.where(front, 0.045 * s - 0.25 * np.maximum(rel_y + 0.03 * s, 0.0), 0.02 * s)
    line = np.where(rel_y < -0.07 * s, -0.04 * s, line)
    mask = on_head & (rel_z > line)
    if style == "long":
        behind = p[:, 1] < head[1] - 0.035 * s
        shoulders = body.joints[JOINT["left_shoulder"], 2]
        neck = np.isin(owner, [JOINT["neck"], JOINT["head"], JOINT["spine3"]])
        mask |= neck & behind & (p[:, 2] > shoulders - 0.02)
    return mask


def _face(p: np.ndarray, owner: np.ndarray, out: np.ndarray, lm: dict) -> None:
    on_head = (owner == JOINT["head"]) & (out == SKIN)
    s = lm["head"] / 0.063
    for eye in lm["eyes"]:
        d = p - eye
        front = on_head & (d[:, 1] > 0.004 * s)
        r = np.hypot(d[:, 0], (d[:, 2]) * 1.6)
        out[front & (r < 0.011 * s)] = EYE_WHITE
        out[front & (np.hypot(d[:, 0], d[:, 2]) < 0.0062 * s)] = IRIS
        brow = front & (np.abs(d[:, 0]) < 0.018 * s) & (d[:, 2] > 0.014 * s)
        brow &= d[:, 2] < 0.014 * s + 0.005 * s - 0.08 * np.abs(d[:, 0])
        out[brow] = BROWS
    centre = lm["eyes"].mean(axis=0)
    d = p - centre
    mouth = on_head & (d[:, 1] > 0.0) & (np.abs(d[:, 0]) < 0.021 * s)
    mouth &= np.abs(d[:, 2] + 0.068 * s) < 0.006 * s * (1 - (d[:, 0] / (0.022 * s)) ** 2)
    out[mouth] = LIPS


def _fabric(p: np.ndarray, base: RGB, accent: RGB, pattern: str, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    base_a, acc = np.array(base), np.array(accent)
    out = np.broadcast_to(base_a, (len(p), 3)).copy()
    if pattern == "stripes":
        period = rng.uniform(0.04, 0.09)
        on = np.mod(p[:, 2] / period, 1.0) < rng.uniform(0.25, 0.5)
        out[on] = acc
    elif pattern == "checks":
        size = rng.uniform(0.03, 0.06)
        cells = np.floor(p[:, 0] / size) + np.floor(p[:, 2] / size) + np.floor(p[:, 1] / size)
        out = np.where((np.mod(cells, 2) == 0)[:, None], out, 0.6 * out + 0.4 * acc)
    elif pattern == "knit":
        rib = 0.5 + 0.5 * np.sin(p[:, 0] * 2 * np.pi / 0.008 + 3 * np.sin(p[:, 2] * 40))
        out *= (0.9 + 0.1 * rib)[:, None]
    elif pattern == "denim":
        twill = 0.5 + 0.5 * np.sin((p[:, 0] + p[:, 2] + p[:, 1]) * 2 * np.pi / 0.004)
        out *= (0.88 + 0.12 * twill)[:, None]
    return out


def paint(body: AnnyBody, outfit: Outfit, seed: int = 0) -> np.ndarray:
    """The person's texture ``(S, S, 3)`` uint8 (rows top first) for the catalog UVs."""
    topo = body.topology
    face = np.maximum(topo.texel_face, 0).ravel()
    b = topo.texel_bary.reshape(-1, 2).astype(float)
    bary = np.column_stack([1.0 - b.sum(axis=1), b])
    corners = topo.uv_vertex[topo.uv_faces[face]]  # (N, 3) geometric vertices
    p = np.einsum("nk,nkc->nc", bary, body.vertices[corners])
    nearest = corners[np.arange(len(corners)), bary.argmax(axis=1)]
    owner = topo.joint_index[nearest, 0]
    label = part_labels(p, owner, body, outfit)
    rgb = np.empty((len(p), 3))
    skin = np.array(outfit.skin)
    colour = {
        SKIN: skin,
        SHOES_PART: np.array(outfit.shoes),
        HAIR_PART: np.array(outfit.hair_rgb),
        EYE_WHITE: np.array([0.93, 0.92, 0.90]),
        IRIS: np.array([0.16, 0.10, 0.07]),
        LIPS: skin * np.array([0.78, 0.55, 0.55]),
        BROWS: 0.7 * np.array(outfit.hair_rgb) if outfit.hair != "none" else 0.55 * skin,
    }
    for part, c in colour.items():
        rgb[label == part] = c
    top = label == TOP
    rgb[top] = _fabric(p[top], outfit.top, outfit.accent, outfit.top_pattern, seed)
    bottom = label == BOTTOM
    pattern = "denim" if outfit.denim else "plain"
    rgb[bottom] = _fabric(p[bottom], outfit.bottom_rgb, outfit.bottom_rgb, pattern, seed + 1)
    # Soles and a little shade under the hair keep shapes readable without shadows.
    rgb[(label == SHOES_PART) & (p[:, 2] < 0.012)] *= 0.45
    size = topo.texel_face.shape[0]
    return np.clip(rgb * 255.0 + 0.5, 0, 255).astype(np.uint8).reshape(size, size, 3)


def hair_layer(body: AnnyBody, outfit: Outfit) -> tuple[np.ndarray, np.ndarray] | None:
    """The hair shell as (geometric vertex ids it copies, outward offsets ``(H, 3)``).

    Its faces are the topology faces whose corners are all hair; None for no hair.
    """
    if outfit.hair == "none":
        return None
    topo = body.topology
    owner = topo.joint_index[:, 0]
    mask = hair_mask(body.vertices, owner, body, outfit.hair)
    ids = np.flatnonzero(mask)
    normals = vertex_normals(body.vertices, topo.faces)[ids]
    lift = SHORT_HAIR_M if outfit.hair == "short" else LONG_HAIR_M
    return ids, lift * normals


def skirt_mesh(body: AnnyBody, segments: int = 20) -> tuple[np.ndarray, np.ndarray]:
    """A flared skirt from the waist to above the knees: vertices (pelvis frame) and faces.

    Vertices are relative to the pelvis joint's rest position; the tube is open at both ends
    (both sides drawn: MuJoCo culls back faces, so each quad is added twice).
    """
    a = body.joints
    lm = _landmarks(body)
    v = body.vertices
    trunk = np.isin(
        body.topology.joint_index[:, 0],
        [JOINT[n] for n in ("pelvis", "spine1", "left_hip", "right_hip")],
    )  # not the hands, which hang at hip height
    band = trunk & (np.abs(v[:, 2] - lm["waist_z"]) < 0.02)
    hips = trunk & (np.abs(v[:, 2] - a[JOINT["left_hip"], 2]) < 0.02)
    waist_r = np.percentile(np.hypot(v[band, 0], v[band, 1] - a[0, 1]), 90)
    hip_r = np.percentile(np.hypot(v[hips, 0], v[hips, 1] - a[0, 1]), 95)
    top_z, bottom_z = lm["waist_z"], lm["knee_z"] + 0.06
    rings = [(top_z, waist_r + 0.006), (a[JOINT["left_hip"], 2], hip_r + 0.012)]
    rings.append((bottom_z, hip_r + 0.03 + 0.2 * (a[JOINT["left_hip"], 2] - bottom_z)))
    theta = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    verts = np.array([[r * np.sin(t), a[0, 1] + r * np.cos(t), z] for z, r in rings for t in theta])
    faces = []
    for ring in range(len(rings) - 1):
        for k in range(segments):
            i0, i1 = ring * segments + k, ring * segments + (k + 1) % segments
            j0, j1 = i0 + segments, i1 + segments
            faces += [(i0, j0, i1), (i1, j0, j1), (i0, i1, j0), (i1, j1, j0)]
    return verts - a[0], np.array(faces, np.int32)
