"""A person's built-in body: proportions from height, girth and clothing colours, as geoms.

The body is one rigid piece per joint of the skeleton (see :mod:`havln_mj.humans.skeleton`):
capsules for limbs and trunk, spheres for the head and hands, boxes for the feet. Each piece
is described in its joint's frame, so posing a person is writing each joint's world pose.
Sizes are fractions of height (scaled by girth across the limbs), close to the anthropometric
tables; colours are drawn from small palettes of skin tones and clothes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.humans.outfits import SKIN_TONES
from havln_mj.humans.skeleton import (
    FOOT_HEIGHT_FRACTION,
    JOINT,
    MAX_HEIGHT,
    MIN_HEIGHT,
    rest_offsets,
)

if TYPE_CHECKING:
    from havln_mj.humans.anny_mujoco import AnnyLook

CLOTHES = (
    (0.80, 0.15, 0.15),
    (0.15, 0.35, 0.75),
    (0.20, 0.55, 0.30),
    (0.90, 0.75, 0.20),
    (0.55, 0.30, 0.60),
    (0.95, 0.95, 0.92),
    (0.20, 0.20, 0.22),
    (0.85, 0.45, 0.15),
    (0.40, 0.60, 0.80),
)
TROUSERS = ((0.15, 0.18, 0.30), (0.25, 0.25, 0.27), (0.45, 0.35, 0.25), (0.60, 0.58, 0.52))
SHOES = ((0.08, 0.08, 0.08), (0.35, 0.20, 0.10), (0.90, 0.90, 0.90))
GIRTH_RANGE = (0.85, 1.25)


@dataclass(frozen=True)
class Piece:
    """One geom of the body, in its joint's frame.

    Attributes:
        joint: Index of the joint (body) carrying it.
        kind: ``"capsule"``, ``"sphere"`` or ``"box"``.
        size: Capsule/sphere radius, or box half-extents.
        a: Capsule start, or sphere/box centre (metres, joint frame).
        b: Capsule end (unused otherwise).
        part: ``"skin"``, ``"top"``, ``"bottom"`` or ``"shoes"`` (which colour).
    """

    joint: int
    kind: str
    size: tuple[float, ...]
    a: tuple[float, float, float]
    b: tuple[float, float, float] = (0.0, 0.0, 0.0)
    part: str = "top"


_O = (0.0, 0.0, 0.0)
# The trunk's capsules, in order: (joint, from (None: the joint), to, radius / height,
# scaled by girth, part). Hip girdle, lower back, belly, chest, shoulder girdle, neck.
_TRUNK = (
    ("pelvis", "left_hip", "right_hip", 0.056, True, "bottom"),
    ("pelvis", None, "spine1", 0.052, True, "top"),
    ("spine1", None, "spine2", 0.050, True, "top"),
    ("spine2", None, "spine3", 0.054, True, "top"),
    ("spine3", None, "neck", 0.052, True, "top"),
    ("spine3", "left_collar", "right_collar", 0.040, True, "top"),
    ("neck", None, "head", 0.026, False, "skin"),
)
# Each side's limb capsules from a joint to the next: (joint, to, radius / height, scaled by
# girth, part).
_LIMBS = (
    ("collar", "shoulder", 0.034, True, "top"),
    ("shoulder", "elbow", 0.029, True, "top"),
    ("elbow", "wrist", 0.023, True, "skin"),
    ("wrist", "hand", 0.019, False, "skin"),
    ("hip", "knee", 0.038, True, "bottom"),
    ("knee", "ankle", 0.030, True, "bottom"),
)


@dataclass(frozen=True)
class BodyShape:
    """A person's size and look.

    Attributes:
        height: Standing height in metres (1.0–1.95).
        girth: Limb and trunk thickness relative to average build (0.85–1.25).
        skin: Skin RGB.
        top: Shirt RGB.
        bottom: Trousers RGB.
        shoes: Shoe RGB.
        look: An Anny body and outfit to draw instead of the capsules (None: capsules).
    """

    height: float
    girth: float = 1.0
    skin: tuple[float, float, float] = SKIN_TONES[1]
    top: tuple[float, float, float] = CLOTHES[1]
    bottom: tuple[float, float, float] = TROUSERS[0]
    shoes: tuple[float, float, float] = SHOES[0]
    look: AnnyLook | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        if not MIN_HEIGHT <= self.height <= MAX_HEIGHT:
            raise InvalidArgumentError(
                f"body height {self.height!r} m outside {MIN_HEIGHT}–{MAX_HEIGHT} m"
            )
        if not GIRTH_RANGE[0] <= self.girth <= GIRTH_RANGE[1]:
            raise InvalidArgumentError(f"body girth {self.girth!r} outside {GIRTH_RANGE}")

    @property
    def offsets(self) -> np.ndarray:
        """Rest joint offsets ``(24, 3)``: the Anny body's, else ``skeleton.rest_offsets``."""
        return self.look.rig.offsets if self.look is not None else rest_offsets(self.height)

    def colour(self, part: str) -> tuple[float, float, float]:
        """RGB of a body part (the Anny look's outfit, when there is one)."""
        if self.look is not None:
            o = self.look.outfit
            return {"skin": o.skin, "top": o.top, "bottom": o.bottom_rgb, "shoes": o.shoes}[part]
        return {"skin": self.skin, "top": self.top, "bottom": self.bottom, "shoes": self.shoes}[
            part
        ]

    def pieces(self) -> list[Piece]:
        """The body's geoms, each in its joint's frame."""
        h, off = self.height, self.offsets
        out = [self._capsule(off, *row) for row in _TRUNK]
        out.append(
            Piece(JOINT["head"], "sphere", (0.060 * h,), (0.0, 0.008 * h, 0.040 * h), _O, "skin")
        )
        for side in ("left", "right"):
            out += [
                self._capsule(off, f"{side}_{joint}", None, f"{side}_{end}", *rest)
                for joint, end, *rest in _LIMBS
            ]
            out.append(self._foot(side))
        return out

    def _capsule(
        self,
        off: np.ndarray,
        joint: str,
        start: str | None,
        end: str,
        radius: float,
        girth: bool,
        part: str,
    ) -> Piece:
        """A capsule in ``joint``'s frame from ``start``'s origin (None: the joint's) to ``end``'s.

        ``radius`` is a fraction of height, times the girth when ``girth``.
        """

        def to(child: str) -> tuple[float, float, float]:
            return tuple(float(v) for v in off[JOINT[child]])

        r = radius * self.height * self.girth if girth else radius * self.height
        return Piece(
            JOINT[joint], "capsule", (r,), _O if start is None else to(start), to(end), part
        )

    def _foot(self, side: str) -> Piece:
        """A shoe: a box from behind the heel to past the toe joint, its sole on the floor."""
        h = self.height
        toe = self.offsets[JOINT[f"{side}_foot"]]
        heel_y, tip_y = -0.035 * h, toe[1] + 0.025 * h
        sole_z, top_z = -FOOT_HEIGHT_FRACTION * h, 0.2 * FOOT_HEIGHT_FRACTION * h
        half = (0.028 * h, (tip_y - heel_y) / 2, (top_z - sole_z) / 2)
        centre = (float(toe[0]) / 2, (tip_y + heel_y) / 2, (top_z + sole_z) / 2)
        return Piece(JOINT[f"{side}_ankle"], "box", half, centre, (0.0, 0.0, 0.0), "shoes")


def random_body(rng: np.random.Generator) -> BodyShape:
    """A body drawn from ``rng``: adult heights around 1.7 m, varied build and clothes."""
    height = float(np.clip(rng.normal(1.70, 0.09), MIN_HEIGHT, MAX_HEIGHT))
    girth = float(np.clip(rng.normal(1.0, 0.08), *GIRTH_RANGE))

    def pick(palette: tuple) -> tuple[float, float, float]:
        return palette[int(rng.integers(len(palette)))]

    return BodyShape(height, girth, pick(SKIN_TONES), pick(CLOTHES), pick(TROUSERS), pick(SHOES))
