"""Every view of every viewpoint, rendered through the simulator at several moments.

HA3D's agents read precomputed features: per viewpoint, 36 views (12 headings × 3 elevations,
MatterSim's ``viewIndex`` order) × 5 time slots. We render the same grid through
:class:`havln_mj.sim.simulator.Simulator` (a batch of 36 elements standing on the viewpoint,
with the scan's people for the seed), at ``slots`` moments ``slot_seconds`` apart: slot ``k``
is the scene at simulated time ``k · slot_seconds`` (the simulator's ``wait``). An agent at time
``t`` reads slot ``round(t / slot_seconds) mod slots``, as HA3D's reads ``step mod 5``: the
people in a feature are where they were at that slot's moment, while the collision signal
stays the simulator's exact one.

Besides the images, each view carries the ground truth the vision encoder is pretrained on:
the fraction of pixels that show a person, whether FORWARD would move from it, and the
region label of the viewpoint.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.scene.regions import REGION_LABELS
from havln_mj.sim.egocentric import EgoAction, ego_to_mattersim
from havln_mj.sim.simulator import Simulator
from havln_mj.sim.state import SimState
from havln_mj.sim.viewing import (
    ELEVATION_INCREMENT,
    HEADING_COUNT,
    HEADING_INCREMENT,
    NUM_VIEWS,
)

REGION_CODES = tuple(sorted(REGION_LABELS))
"""Region label codes, in the order of the pretraining target's region classes."""
MAX_DEPTH = 10.0  # metres; depth targets and inputs are clipped here


@dataclass(frozen=True)
class ViewConfig:
    """How views are rendered.

    The default camera is the simulator's own (MatterSim's 0.8 rad VFOV, 4:3), so FORWARD
    means the same in the features and in an evaluation run with default settings.

    Attributes:
        width: Image width in pixels.
        height: Image height in pixels.
        vfov: Vertical field of view in radians.
        slots: Moments rendered per view.
        slot_seconds: Simulated seconds between slots.
        depth: Whether depth is rendered (a fourth input channel).
    """

    width: int = 64
    height: int = 48
    vfov: float = 0.8
    slots: int = 4
    slot_seconds: float = 4.0
    depth: bool = True

    def __post_init__(self) -> None:
        if not (16 <= self.width <= 1024 and 16 <= self.height <= 1024):
            raise InvalidArgumentError(
                f"view size {self.width}×{self.height} px; valid: 16–1024 px per side"
            )
        if not 0.1 <= self.vfov <= 2.5:
            raise InvalidArgumentError(f"vfov {self.vfov!r} rad; valid: 0.1–2.5")
        if self.slots < 1 or not (self.slot_seconds > 0 and math.isfinite(self.slot_seconds)):
            raise InvalidArgumentError(
                f"slots={self.slots!r}, slot_seconds={self.slot_seconds!r}; valid: slots ≥ 1 "
                "and a positive number of seconds"
            )

    @property
    def half_hfov(self) -> float:
        """Half the horizontal field of view as the simulator computes it (FORWARD's cone)."""
        return self.vfov * self.width / self.height / 2.0

    def key(self) -> str:
        """A short name for cache folders."""
        d = asdict(self)
        return "{width}x{height}-v{vfov:g}-s{slots}x{slot_seconds:g}-{d}".format(
            **d, d="rgbd" if self.depth else "rgb"
        )

    def slot(self, time: float) -> int:
        """The slot an agent at simulated ``time`` reads."""
        return math.floor(time / self.slot_seconds + 0.5) % self.slots


def view_angles() -> tuple[np.ndarray, np.ndarray]:
    """Heading and elevation of the 36 views in ``viewIndex`` order (level 0 looks down)."""
    index = np.arange(NUM_VIEWS)
    headings = (index % HEADING_COUNT) * HEADING_INCREMENT
    elevations = (index // HEADING_COUNT - 1) * ELEVATION_INCREMENT
    return headings, elevations


def forward_possible(state: SimState, half_hfov: float) -> bool:
    """Whether FORWARD would move (the simulator's own rule: a viewpoint within the HFOV)."""
    return ego_to_mattersim(EgoAction.FORWARD, state, half_hfov)[0] != 0


@dataclass(frozen=True)
class ViewpointViews:
    """The 36 × ``slots`` views of one viewpoint and their pretraining targets.

    Attributes:
        viewpoint: Viewpoint id.
        rgb: ``(36, S, H, W, 3)`` uint8.
        depth: ``(36, S, H, W)`` float16 metres (0 = no reading), or None.
        person: ``(36, S)`` float32 fraction of pixels showing a person (None when the
            renderer draws no person masks).
        forward: ``(36,)`` bool, FORWARD would move from the view.
        region: Region class (index into :data:`REGION_CODES`), -1 when unknown.
    """

    viewpoint: str
    rgb: np.ndarray
    depth: np.ndarray | None
    person: np.ndarray | None
    forward: np.ndarray
    region: int


class ViewRenderer:
    """Renders the views of scans' viewpoints (one GL context, a batch-36 simulator).

    Args:
        config: Image size, camera and slots.
        seed: The simulator seed, which places the people (use the dataset's seed).
        humans: Whether scans have people.
        connectivity_dir: Navigation graphs of real scans (graph proxies or meshes).
        human_placements: HA3D placement file for the real scans.
        person_masks: Whether to draw the person masks of the ``person`` target (pretraining
            needs them; encoding views does not, and skips their second render pass).
    """

    def __init__(
        self,
        config: ViewConfig,
        *,
        seed: int = 0,
        humans: bool = True,
        connectivity_dir: str | Path | None = None,
        human_placements: str | Path | None = None,
        person_masks: bool = True,
    ) -> None:
        self.config = config
        self._person_masks = person_masks
        self._connectivity_dir = connectivity_dir
        sim = Simulator(humans=humans, human_placements=human_placements)
        if connectivity_dir is not None:
            sim.setNavGraphPath(str(connectivity_dir))
        sim.setBatchSize(NUM_VIEWS)
        sim.setCameraResolution(config.width, config.height)
        sim.setCameraVFOV(config.vfov)
        sim.setDepthEnabled(config.depth)
        sim.set_depth_units("metres")
        sim.set_color_order("RGB")
        sim.set_human_mask_enabled(person_masks)
        sim.setDiscretizedViewingAngles(True)
        sim.setRenderingEnabled(True)
        sim.setCacheSize(1)  # scans are rendered one after another
        sim.setSeed(seed)
        sim.initialize()
        self._sim = sim
        self._headings, self._elevations = (a.tolist() for a in view_angles())

    def viewpoints(self, scan_id: str) -> list[str]:
        """The included viewpoints of a scan, in graph order."""
        return list(self._sim.graph(scan_id).nodes)

    def _regions(self, scan_id: str) -> dict[str, int]:
        from havln_mj.scene.scan import load_scan  # the scan is cached on disk already

        regions = load_scan(scan_id, connectivity_dir=self._connectivity_dir).regions
        if regions is None:
            return {}
        codes = {c: i for i, c in enumerate(REGION_CODES)}
        out = {}
        for vp in self.viewpoints(scan_id):
            region = regions.region_of(vp)
            if region is not None and region.label in codes:
                out[vp] = codes[region.label]
        return out

    def render(
        self, scan_id: str, viewpoints: Sequence[str] | None = None
    ) -> Iterator[ViewpointViews]:
        """Yields the views of ``viewpoints`` (default: every included one) of ``scan_id``."""
        cfg, sim = self.config, self._sim
        vps = self.viewpoints(scan_id) if viewpoints is None else list(viewpoints)
        regions = self._regions(scan_id)
        n, shape = NUM_VIEWS, (NUM_VIEWS, cfg.slots, cfg.height, cfg.width)
        for vp in vps:
            sim.newEpisode([scan_id] * n, [vp] * n, self._headings, self._elevations)
            rgb = np.empty((*shape, 3), np.uint8)
            depth = np.empty(shape, np.float16) if cfg.depth else None
            person = np.empty((n, cfg.slots), np.float32) if self._person_masks else None
            for k in range(cfg.slots):
                if k:
                    sim.wait([cfg.slot_seconds] * n)
                states = sim.getState()
                for v, state in enumerate(states):
                    rgb[v, k] = state.rgb
                    if depth is not None:
                        depth[v, k] = np.minimum(state.depth[..., 0], MAX_DEPTH)
                    if person is not None:
                        person[v, k] = float(state.humanMask.mean())
                if k == 0:
                    forward = np.array([forward_possible(s, cfg.half_hfov) for s in states])
            yield ViewpointViews(vp, rgb, depth, person, forward, regions.get(vp, -1))

    def close(self) -> None:
        """Releases the simulator and its GL resources."""
        self._sim.close()

    def __enter__(self) -> ViewRenderer:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()
