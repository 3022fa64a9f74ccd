"""The activity catalog: what people do in each kind of room, and the motion that shows it.

The catalog (``humans/activities.json``) is keyed by Matterport3D region label codes
(:data:`~havln_mj.scene.regions.REGION_LABELS`); every activity has a stable id, a short
sentence, a verb phrase for instructions, and a motion recipe with its parameters (the
keyword arguments of the recipe in :mod:`havln_mj.humans.motion`; ``needs_seat`` marks
sitting). :func:`make_clip` builds an activity's clip for one person, and
:meth:`Catalog.map_ha3d` maps HA3D's ``"region:sentence"`` placements onto our activities.
"""

from __future__ import annotations

import inspect
import json
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from havln_mj.errors import InvalidArgumentError, MalformedDataError, did_you_mean
from havln_mj.humans.clip import Clip
from havln_mj.humans.motion import RECIPES
from havln_mj.paths import asset_path
from havln_mj.scene.regions import REGION_LABELS

WALK_RECIPES = ("walk_path", "pace")
# HA3D's region names (the part before ':' in its placements) → our label codes.
HA3D_REGIONS: dict[str, str] = {
    "bathroom": "a",
    "bedroom": "b",
    "closet": "c",
    "dining room": "d",
    "entryway/foyer/lobby": "e",
    "familyroom": "f",
    "garage": "g",
    "hallway": "h",
    "library": "i",
    "laundryroom/mudroom": "j",
    "kitchen": "k",
    "living room": "l",
    "meetingroom/conferenceroom": "m",
    "lounge": "n",
    "office": "o",
    "porch/terrace/deck/driveway": "p",
    "rec/game": "r",
    "stairs": "s",
    "toilet": "t",
    "utilityroom/toolroom": "u",
    "tv": "v",
    "workout/gym/exercise": "w",
    "outdoor areas containing grass, plants, bushes, trees, etc.": "x",
    "balcony": "y",
    "other room": "z",
    "bar": "B",
    "classroom": "C",
    "dining booth": "D",
    "spa/sauna": "S",
}
_STOPWORD_TEXT = (
    "a an the and or of to in on at by for with from into over their his her its they them "
    "someone person individual people while some who is are be as up down out off this that "
    "before after during"
)
_STOPWORDS = frozenset(_STOPWORD_TEXT.split())
# Word stems that mean much the same here, mapped onto one (for matching HA3D sentences).
_SYNONYMS = {
    "convers": "chat",
    "talk": "chat",
    "discuss": "chat",
    "speak": "chat",
    "call": "phone",
    "napp": "relax",
    "rest": "relax",
    "sleep": "relax",
    "snuggl": "relax",
    "unwind": "relax",
    "run": "hurry",
    "rush": "hurry",
    "shoe": "lace",
    "vacuum": "clean",
    "tidy": "clean",
    "organiz": "sort",
    "sett": "lay",
    "couch": "sofa",
    "movie": "film",
    "tv": "television",
    "watch": "film",
    "workout": "exercise",
    "yoga": "stretch",
    "pilat": "stretch",
    "meal": "eat",
    "dinner": "eat",
    "lunch": "eat",
    "food": "eat",
    "book": "read",
    "magazine": "read",
    "stud": "read",
}
# Parameters the catalog may set per recipe: keyword arguments after the required ones.
_FIXED = {"height", "rng", "seat_height", "waypoints", "a", "b"}


@dataclass(frozen=True)
class Activity:
    """One thing a person does in a region.

    Attributes:
        id: Stable slug, e.g. ``"kitchen/dishwasher"``.
        region: Matterport3D region label code, e.g. ``"k"``.
        text: A short sentence, e.g. ``"A person loading the dishwasher."``.
        verb: A verb phrase for instructions, e.g. ``"loading the dishwasher"``.
        recipe: Motion recipe name (a key of :data:`havln_mj.humans.motion.RECIPES`).
        params: The recipe's keyword arguments (plus ``needs_seat`` for sitting), read-only.
    """

    id: str
    region: str
    text: str
    verb: str
    recipe: str
    params: Mapping[str, Any]

    @property
    def needs_seat(self) -> bool:
        """Whether the clip needs a seat height (sitting)."""
        return self.recipe == "sit"

    @property
    def needs_path(self) -> bool:
        """Whether the clip needs a ground path (walking, pacing)."""
        return self.recipe in WALK_RECIPES


class Catalog:
    """Activities by region label code."""

    def __init__(self, activities: Mapping[str, list[Activity]]):
        self._by_region = {code: list(acts) for code, acts in activities.items()}
        self._by_id = {a.id: a for acts in self._by_region.values() for a in acts}

    def regions(self) -> list[str]:
        """Region label codes that have activities."""
        return list(self._by_region)

    def region_code(self, region: str) -> str:
        """The label code of a region given as a code, our name or an HA3D region name.

        Raises:
            InvalidArgumentError: An unknown region, naming the valid codes.
        """
        if region in self._by_region:
            return region
        key = str(region).strip().lower()
        for code, name in REGION_LABELS.items():
            if key == name and code in self._by_region:
                return code
        if HA3D_REGIONS.get(key) in self._by_region:
            return HA3D_REGIONS[key]
        valid = ", ".join(f"{c} ({REGION_LABELS.get(c, c)})" for c in self._by_region)
        names = [*self._by_region, *(REGION_LABELS[c] for c in self._by_region), *HA3D_REGIONS]
        raise InvalidArgumentError(
            f"unknown region {region!r}; valid region codes: {valid}.{did_you_mean(key, names)}"
        )

    def activities(self, region: str) -> list[Activity]:
        """The activities of a region (a label code or a region name).

        Raises:
            InvalidArgumentError: An unknown region, naming the valid codes.
        """
        return list(self._by_region[self.region_code(region)])

    def get(self, activity_id: str) -> Activity:
        """The activity with this id.

        Raises:
            InvalidArgumentError: No such activity.
        """
        if activity_id not in self._by_id:
            raise InvalidArgumentError(
                f"unknown activity {activity_id!r}.{did_you_mean(activity_id, self._by_id)}"
            )
        return self._by_id[activity_id]

    def __iter__(self):
        return iter(self._by_id.values())

    def __len__(self) -> int:
        return len(self._by_id)

    def map_ha3d(self, region_activity: str, rng: np.random.Generator) -> Activity:
        """Our activity closest to an HA3D placement such as ``"tv:Someone cheering."``.

        The region picks the candidates; among them the one sharing the most content words
        with the sentence wins, ties (and no overlap at all) broken by ``rng``.

        Raises:
            InvalidArgumentError: No ``region:`` prefix, or an unknown region.
        """
        region, sep, sentence = str(region_activity).partition(":")
        if not sep:
            raise InvalidArgumentError(
                f"expected an HA3D 'region:activity' string, got {region_activity!r}"
            )
        candidates = self.activities(region)
        words = _content_words(sentence)
        scores = np.array([len(words & _content_words(f"{a.text} {a.verb}")) for a in candidates])
        best = np.flatnonzero(scores == scores.max())
        return candidates[int(best[rng.integers(len(best))])]


def _content_words(text: str) -> set[str]:
    """Lower-case word stems without stop words ("cheering" and "cheers" both → "cheer")."""
    out = set()
    for w in re.findall(r"[a-z]+", text.lower()):
        if w in _STOPWORDS or len(w) < 3:
            continue
        for suffix in ("ing", "ers", "es", "ed", "s"):
            if w.endswith(suffix) and len(w) - len(suffix) >= 3:
                w = w[: -len(suffix)]
                break
        out.add(_synonym(w))
    return out


def _synonym(stem: str) -> str:
    if stem in _SYNONYMS:
        return _SYNONYMS[stem]
    for key, canon in _SYNONYMS.items():
        if len(key) >= 5 and stem.startswith(key):
            return canon
    return stem


def _allowed_params(recipe: str) -> set[str]:
    sig = inspect.signature(RECIPES[recipe])
    return {p for p in sig.parameters if p not in _FIXED}


def load_catalog(path: Path | str | None = None) -> Catalog:
    """Reads the activity catalog (default: the built-in ``humans/activities.json``).

    Raises:
        MissingDataError: The file does not exist.
        MalformedDataError: It does not follow the schema (unknown region code or recipe,
            parameters the recipe does not take, duplicate ids).
    """
    path = Path(path) if path is not None else asset_path("humans", "activities.json")
    try:
        raw = json.loads(Path(path).read_text())
        regions = raw["regions"]
        out: dict[str, list[Activity]] = {}
        seen: set[str] = set()
        for code, entry in regions.items():
            if code not in REGION_LABELS:
                raise MalformedDataError(
                    f"{path}: unknown region code {code!r}.{did_you_mean(code, REGION_LABELS)}"
                )
            acts = []
            for item in entry["activities"]:
                act = _activity(code, item, path)
                if act.id in seen:
                    raise MalformedDataError(f"{path}: duplicate activity id {act.id!r}")
                seen.add(act.id)
                acts.append(act)
            out[code] = acts
    except (KeyError, TypeError, AttributeError, ValueError) as exc:
        if isinstance(exc, MalformedDataError):
            raise
        raise MalformedDataError(
            f"{path}: expected {{'regions': {{code: {{'activities': [{{id, text, verb, recipe, "
            f"params}}]}}}}}} ({type(exc).__name__}: {exc})"
        ) from None
    return Catalog(out)


def _activity(code: str, item: dict, path: Path | str) -> Activity:
    recipe = item["recipe"]
    if recipe not in RECIPES:
        raise MalformedDataError(
            f"{path}: activity {item.get('id')!r} has unknown recipe {recipe!r}; valid: "
            f"{', '.join(RECIPES)}"
        )
    params = dict(item.get("params", {}))
    extra = set(params) - _allowed_params(recipe) - {"needs_seat"}
    if extra:
        raise MalformedDataError(
            f"{path}: activity {item['id']!r}: recipe {recipe!r} takes no {sorted(extra)}; "
            f"valid: {sorted(_allowed_params(recipe))}"
        )
    if recipe == "sit":
        params["needs_seat"] = True
    return Activity(
        id=str(item["id"]),
        region=code,
        text=str(item["text"]),
        verb=str(item["verb"]),
        recipe=recipe,
        params=MappingProxyType(params),
    )


def make_clip(
    activity: Activity,
    height: float,
    rng: np.random.Generator,
    *,
    seat_height: float | None = None,
    path: np.ndarray | None = None,
) -> Clip:
    """Builds an activity's looping clip for one person (anchor frame, facing +y).

    Args:
        activity: What they do.
        height: Their height (m).
        rng: Source of their per-person variation.
        seat_height: Seat surface height (m), required by sitting activities.
        path: Ground points ``(K, 2)`` in the anchor frame, required by walking activities
            (pacing goes back and forth between the first and last point).

    Raises:
        InvalidArgumentError: A needed seat height or path is missing (or a recipe rejects
            its arguments).
    """
    params = {k: v for k, v in activity.params.items() if k != "needs_seat"}
    recipe = RECIPES[activity.recipe]
    if activity.needs_seat:
        if seat_height is None:
            raise InvalidArgumentError(
                f"activity {activity.id!r} sits: pass seat_height (metres above the floor)"
            )
        return recipe(height, seat_height, rng, **params)
    if activity.needs_path:
        if path is None:
            raise InvalidArgumentError(
                f"activity {activity.id!r} walks ({activity.recipe}): pass path, ground "
                "points (K, 2) in the anchor frame"
            )
        pts = np.asarray(path, float)
        if activity.recipe == "pace":
            if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 2:
                raise InvalidArgumentError(
                    f"pacing needs a path of at least two ground points (K, 2), got {pts.shape}"
                )
            return recipe(height, pts[0], pts[-1], rng, **params)
        return recipe(height, pts, rng, **params)
    return recipe(height, rng, **params)
