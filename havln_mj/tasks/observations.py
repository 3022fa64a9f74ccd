"""What an HA-VLN agent observes, described once for every environment API.

:class:`Observations` lists the fields (name, shape, dtype, bounds) and builds them from a
simulator state; the gymnasium environments turn the fields into ``spaces`` and the
``dm_env`` adapter into ``specs``, so both hand out the same arrays. ``H×W`` is
``height×width``:

=================  ==========================================================================
``rgb``            ``H×W×3 uint8`` RGB camera image (unless ``rgb=False``)
``depth``          ``H×W×1 float32`` planar depth in metres, 0 = no reading, clipped to
                   ``max_depth`` (only with ``depth=True``)
``human_mask``     ``H×W uint8``, 1 where a person is seen (only with ``human_mask=True``)
``instruction``    ``L int64`` token ids of the vocabulary, 0-padded (``L`` =
                   ``instruction_length``)
``heading``        ``(1,) float32`` radians in [0, 2π), 0 facing +y, right positive
``elevation``      ``(1,) float32`` radians, up positive
``candidates``     ``(K+1)×4 float32``: row 0 is the agent's own location (zeros), row k ≥ 1
                   the k-th navigable viewpoint (nearest the view centre first):
                   ``sin rel_heading, cos rel_heading, rel_elevation, rel_distance`` (metres,
                   clipped to 50); zeros where there is none (``K`` = ``max_candidates``)
``candidate_mask`` ``(K+1,) int8``, binary: 1 for row 0 and for every row holding a viewpoint
``collision``      ``() int64`` in {0, 1}: 1 when the last action (or the start) came within
                   the collision distance of a person
=================  ==========================================================================

Every observation holds fresh arrays: consecutive observations share no memory.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from havln_mj.sim.state import SimState

MAX_CANDIDATE_DISTANCE = 50.0  # metres; candidate distances are clipped so the bounds hold
CANDIDATE_FEATURES = 4


@dataclass(frozen=True)
class Field:
    """One observation entry.

    Attributes:
        name: Its key.
        shape: Array shape (``()`` for a scalar).
        dtype: Array dtype.
        low: Lower bound (scalar or array of ``shape``).
        high: Upper bound.
        kind: ``"box"``, ``"binary"`` (0/1 per element) or ``"discrete"`` (an integer scalar
            in ``[low, high]``).
    """

    name: str
    shape: tuple[int, ...]
    dtype: type
    low: float | np.ndarray
    high: float | np.ndarray
    kind: str = "box"


class Observations:
    """The observation fields of one configuration, and their values for a state.

    Args:
        width: Image width (pixels).
        height: Image height (pixels).
        rgb: Whether the RGB image is observed.
        depth: Whether depth is observed.
        human_mask: Whether the human mask is observed.
        max_depth: Depth clip (metres).
        instruction_length: Token ids per instruction.
        vocab_size: Number of tokens.
        max_candidates: Navigable viewpoints described.
    """

    def __init__(
        self,
        *,
        width: int,
        height: int,
        rgb: bool,
        depth: bool,
        human_mask: bool,
        max_depth: float,
        instruction_length: int,
        vocab_size: int,
        max_candidates: int,
    ) -> None:
        self.width, self.height = width, height
        self.rgb, self.depth, self.human_mask = rgb, depth, human_mask
        self.max_depth = max_depth
        self.length, self.k = instruction_length, max_candidates
        h, w, k = height, width, max_candidates
        fields = []
        if rgb:
            fields.append(Field("rgb", (h, w, 3), np.uint8, 0, 255))
        if depth:
            fields.append(Field("depth", (h, w, 1), np.float32, 0.0, max_depth))
        if human_mask:
            fields.append(Field("human_mask", (h, w), np.uint8, 0, 1))
        fields += [
            Field("instruction", (instruction_length,), np.int64, 0, vocab_size - 1),
            Field("heading", (1,), np.float32, 0.0, 2 * math.pi),
            Field("elevation", (1,), np.float32, -math.pi / 2, math.pi / 2),
            Field(
                "candidates",
                (k + 1, CANDIDATE_FEATURES),
                np.float32,
                np.tile(np.array([-1.0, -1.0, -math.pi, 0.0], np.float32), (k + 1, 1)),
                np.tile(
                    np.array([1.0, 1.0, math.pi, MAX_CANDIDATE_DISTANCE], np.float32), (k + 1, 1)
                ),
            ),
            Field("candidate_mask", (k + 1,), np.int8, 0, 1, "binary"),
            Field("collision", (), np.int64, 0, 1, "discrete"),
        ]
        self.fields = fields

    @property
    def rendering(self) -> bool:
        """Whether any field needs the camera."""
        return self.rgb or self.depth or self.human_mask

    def build(self, state: SimState, tokens: np.ndarray, collided: bool) -> dict[str, object]:
        """The observation of ``state`` (images in RGB and metres, as the simulator is set)."""
        obs: dict[str, object] = {}
        if self.rgb:
            obs["rgb"] = np.array(state.rgb, np.uint8, copy=True)
        if self.depth:
            obs["depth"] = np.clip(state.depth, 0.0, self.max_depth).astype(np.float32)
        if self.human_mask:
            mask = state.humanMask
            shape = (self.height, self.width)
            obs["human_mask"] = np.zeros(shape, np.uint8) if mask is None else mask.astype(np.uint8)
        obs["instruction"] = np.array(tokens, np.int64, copy=True)
        obs["heading"] = np.array([state.heading], np.float32)
        obs["elevation"] = np.array([state.elevation], np.float32)
        cands = np.zeros((self.k + 1, CANDIDATE_FEATURES), np.float32)
        mask = np.zeros(self.k + 1, np.int8)
        mask[0] = 1
        for k, vp in enumerate(state.navigableLocations[1 : self.k + 1], start=1):
            cands[k] = (
                math.sin(vp.rel_heading),
                math.cos(vp.rel_heading),
                min(max(vp.rel_elevation, -math.pi), math.pi),
                min(vp.rel_distance, MAX_CANDIDATE_DISTANCE),
            )
            mask[k] = 1
        obs["candidates"] = cands
        obs["candidate_mask"] = mask
        obs["collision"] = np.int64(collided)
        return obs
