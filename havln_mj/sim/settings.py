"""The simulator's settings: MatterSim's setters, their defaults and their checks.

:class:`SimulatorSettings` holds the settings of a :class:`~havln_mj.sim.simulator.Simulator`
and its MatterSim setters. As in MatterSim, setters called after ``initialize`` are ignored
(here with a warning), except the camera's resolution, field of view and elevation limits.
Every value is checked when it is set: a bad one raises at once, naming the value and what is
valid, and changes nothing.
"""

from __future__ import annotations

import math
import numbers
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.render.camera import MAX_SIZE
from havln_mj.sim.frame import ViewSettings
from havln_mj.sim.viewing import DEFAULT_ELEVATION_LIMITS, valid_elevation_limits
from havln_mj.sim.world import WorldOptions

COLOR_ORDERS = ("BGR", "RGB")
DEPTH_UNITS = ("mattersim", "metres")

# The public setter of each locked setting, for the warning when it is called too late.
_SETTERS = {
    "dataset_path": "setDatasetPath",
    "nav_graph_path": "setNavGraphPath",
    "rendering": "setRenderingEnabled",
    "discretized": "setDiscretizedViewingAngles",
    "restricted": "setRestrictedNavigation",
    "preloading": "setPreloadingEnabled",
    "depth": "setDepthEnabled",
    "batch_size": "setBatchSize",
    "cache_size": "setCacheSize",
    "seed": "setSeed",
    "color_order": "set_color_order",
    "depth_units": "set_depth_units",
    "human_mask": "set_human_mask_enabled",
    "labels": "set_segmentation_enabled",
    "skybox": "set_skybox_enabled",
    "world_options": "set_world_options",
}


@dataclass
class Settings:
    """MatterSim's settings with its defaults (paths default to the environment variables)."""

    dataset_path: str | None = None
    nav_graph_path: str | None = None
    rendering: bool = True
    width: int = 320
    height: int = 240
    vfov: float = 0.8
    elevation_limits: tuple[float, float] = DEFAULT_ELEVATION_LIMITS
    discretized: bool = False
    restricted: bool = True
    preloading: bool = False
    depth: bool = False
    batch_size: int = 1
    cache_size: int = 200
    seed: int = 1
    color_order: str = "BGR"
    depth_units: str = "mattersim"
    human_mask: bool = False
    labels: bool = False
    skybox: bool = False
    world_options: WorldOptions = field(default_factory=lambda: WorldOptions(collision="none"))
    revision: int = field(default=0, compare=False, repr=False)
    """Counts changes made through the setters (what is derived from the settings is kept
    until it changes)."""

    def view_settings(self) -> ViewSettings:
        """What each rendered frame looks like."""
        return ViewSettings(
            self.width, self.height, self.vfov, self.depth, self.human_mask, self.labels
        )

    def half_hfov(self) -> float:
        """Half the horizontal field of view, ``vfov · width / height / 2`` (MatterSim's)."""
        return self.vfov * self.width / self.height / 2.0

    def cos_half_hfov(self) -> float | None:
        """Restricted navigation's threshold on a neighbour's bearing cosine (None: off)."""
        return math.cos(self.half_hfov()) if self.restricted else None


def _check_bool(name: str, value: object) -> bool:
    if not isinstance(value, bool | np.bool_):
        raise InvalidArgumentError(f"{name} takes a bool, got {value!r}")
    return bool(value)


def _check_int(name: str, value: object, low: int, high: int | None = None) -> int:
    bad = isinstance(value, bool) or not isinstance(value, numbers.Integral)
    if bad or value < low or (high is not None and value > high):
        valid = f"≥ {low}" if high is None else f"in [{low}, {high}]"
        raise InvalidArgumentError(f"{name} takes an integer {valid}, got {value!r}")
    return int(value)


def _check_angle(what: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise InvalidArgumentError(f"{what} must be a finite number of radians, got {value!r}")
    return float(value)


class SimulatorSettings:
    """MatterSim's setters over a :class:`Settings` (the base of the simulator)."""

    def __init__(self) -> None:
        self._cfg = Settings()
        self._initialized = False

    def _set(self, name: str, value: object, *, locked: bool = True) -> None:
        if locked and self._initialized:
            warnings.warn(
                f"{_SETTERS[name]}() is ignored after initialize(), as in MatterSim; "
                "call it before",
                stacklevel=3,
            )
            return
        setattr(self._cfg, name, value)
        self._cfg.revision += 1

    def setDatasetPath(self, path: str | Path) -> None:  # noqa: N802 - MatterSim's names
        """Root of the user's Matterport3D data (raw or habitat layout), for real meshes."""
        self._set("dataset_path", str(path))

    def setNavGraphPath(self, path: str | Path) -> None:  # noqa: N802
        """Folder of ``<scan>_connectivity.json`` navigation graphs."""
        self._set("nav_graph_path", str(path))

    def setRenderingEnabled(self, value: bool) -> None:  # noqa: N802
        """Whether RGB (and depth) are rendered; off skips all GL work."""
        self._set("rendering", _check_bool("setRenderingEnabled", value))

    def setCameraResolution(self, width: int, height: int) -> None:  # noqa: N802
        """Image size in pixels, each in [1, 8192] (may change after ``initialize``)."""
        w = _check_int("setCameraResolution width", width, 1, MAX_SIZE)
        h = _check_int("setCameraResolution height", height, 1, MAX_SIZE)
        self._set("width", w, locked=False)
        self._set("height", h, locked=False)

    def setCameraVFOV(self, vfov: float) -> None:  # noqa: N802
        """Vertical field of view in radians, in (0, π) (may change after ``initialize``)."""
        v = _check_angle("setCameraVFOV", vfov)
        if not 0.0 < v < math.pi:
            raise InvalidArgumentError(f"setCameraVFOV takes radians in (0, π), got {vfov!r}")
        self._set("vfov", v, locked=False)

    def setElevationLimits(self, min: float, max: float) -> bool:  # noqa: N802
        """Continuous-mode elevation limits (may change after ``initialize``).

        Returns False, changing nothing, unless min ∈ (−π/2, 0) and max ∈ (0, π/2).
        """
        lo, hi = _check_angle("min elevation", min), _check_angle("max elevation", max)
        if not valid_elevation_limits(lo, hi):
            return False
        self._set("elevation_limits", (lo, hi), locked=False)
        return True

    def setDiscretizedViewingAngles(self, value: bool) -> None:  # noqa: N802
        """12 headings × 3 elevations, 30° apart, and ``viewIndex``."""
        self._set("discretized", _check_bool("setDiscretizedViewingAngles", value))

    def setRestrictedNavigation(self, value: bool) -> None:  # noqa: N802
        """Whether only neighbours within the horizontal field of view are navigable."""
        self._set("restricted", _check_bool("setRestrictedNavigation", value))

    def setPreloadingEnabled(self, value: bool) -> None:  # noqa: N802
        """Whether ``initialize`` loads every graph of the navigation-graph folder.

        With rendering on it also builds their worlds, up to the cache size.
        """
        self._set("preloading", _check_bool("setPreloadingEnabled", value))

    def setDepthEnabled(self, value: bool) -> None:  # noqa: N802
        """Whether depth is rendered."""
        self._set("depth", _check_bool("setDepthEnabled", value))

    def setBatchSize(self, size: int) -> None:  # noqa: N802
        """Number of agents stepped together."""
        self._set("batch_size", _check_int("setBatchSize", size, 1))

    def setCacheSize(self, size: int) -> None:  # noqa: N802
        """Number of built scan worlds kept for rendering."""
        self._set("cache_size", _check_int("setCacheSize", size, 1))

    def setSeed(self, seed: int) -> None:  # noqa: N802
        """Seed of the simulator's random generator (random episodes, crowds)."""
        self._set("seed", _check_int("setSeed", seed, 0))

    def set_color_order(self, order: str) -> None:
        """``"BGR"`` (MatterSim, the default) or ``"RGB"``."""
        if order not in COLOR_ORDERS:
            raise InvalidArgumentError(f"color order {order!r}; valid: {COLOR_ORDERS}")
        self._set("color_order", order)

    def set_depth_units(self, units: str) -> None:
        """Depth format: ``"mattersim"`` (the default) or ``"metres"``.

        MatterSim's is ``uint16`` H×W×1 in 0.25 mm units; metres are ``float32`` H×W×1.
        """
        if units not in DEPTH_UNITS:
            raise InvalidArgumentError(f"depth units {units!r}; valid: {DEPTH_UNITS}")
        self._set("depth_units", units)

    def set_human_mask_enabled(self, value: bool) -> None:
        """Whether states carry ``humanMask`` (a second, segmentation pass per frame)."""
        self._set("human_mask", _check_bool("set_human_mask_enabled", value))

    def set_segmentation_enabled(self, value: bool) -> None:
        """Whether states carry ``semantic`` (mpcat40 classes, people 42) and ``instance`` ids.

        One extra render pass per frame (it also gives ``humanMask``). Procedural houses are
        labelled by their generator; real scans by their ``.house`` objects when the user's
        Matterport3D data has them.
        """
        self._set("labels", _check_bool("set_segmentation_enabled", value))

    def set_skybox_enabled(self, value: bool) -> None:
        """Whether real scans show their Matterport3D skybox photographs, as MatterSim does.

        Needs the user's ``matterport_skybox_images`` under the dataset path
        (``setDatasetPath``); the people MuJoCo draws are composited over the photographs
        where they are nearer than the scan's mesh. A viewpoint whose files are missing is
        named in a warning and rendered from the mesh.
        """
        self._set("skybox", _check_bool("set_skybox_enabled", value))

    def set_world_options(self, options: WorldOptions) -> None:
        """How rendered worlds are built.

        The default builds no collision geometry, which the point body does not need.
        """
        if not isinstance(options, WorldOptions):
            raise InvalidArgumentError(f"expected WorldOptions, got {options!r}")
        self._set("world_options", options)

    @property
    def batch_size(self) -> int:
        """The number of batch elements (``setBatchSize``)."""
        return self._cfg.batch_size

    @property
    def half_hfov(self) -> float:
        """Half the horizontal field of view (radians), as MatterSim approximates it.

        ``vfov · width / height / 2``; restricted navigation and FORWARD use it.
        """
        return self._cfg.half_hfov()
