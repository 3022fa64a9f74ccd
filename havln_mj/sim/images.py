"""Rendered views in the simulator's image formats (MatterSim's by default).

MatterSim hands out BGR ``uint8`` colour and ``uint16`` depth in 0.25 mm units (planar
z-distance, 0 = no reading, so anything beyond 16.38 m reads 0). Users who prefer RGB or
``float32`` metres ask the simulator for them. States that are not rendered share read-only
zero images.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from havln_mj.sim.frame import View, ViewSettings

DEPTH_UNITS_PER_M = 4000.0  # MatterSim / Matterport depth: 0.25 mm per unit
_UINT16_MAX = 65535


def depth_to_mattersim(depth_m: np.ndarray) -> np.ndarray:
    """Metres to MatterSim's H×W×1 ``uint16`` in 0.25 mm units (out of range reads 0)."""
    units = np.multiply(depth_m, DEPTH_UNITS_PER_M)
    np.rint(units, out=units)
    units *= units <= _UINT16_MAX  # out of range reads 0 (a product: masked writes are slow)
    return units.astype(np.uint16)[..., None]


class ImageFormat:
    """Turns views into state images, and makes the blank images of unrendered states.

    Args:
        color_order: ``"BGR"`` or ``"RGB"``.
        depth_units: ``"mattersim"`` (``uint16``, 0.25 mm) or ``"metres"`` (``float32``).
    """

    def __init__(self, color_order: str, depth_units: str) -> None:
        self.bgr = color_order == "BGR"
        self.metres = depth_units == "metres"
        self._blank: tuple[np.ndarray, np.ndarray] | None = None

    def blank(self, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        """Shared read-only zero colour and depth images of the given size."""
        if self._blank is None or self._blank[0].shape[:2] != (height, width):
            rgb = np.zeros((height, width, 3), np.uint8)
            depth = np.zeros((height, width, 1), np.float32 if self.metres else np.uint16)
            rgb.flags.writeable = depth.flags.writeable = False
            self._blank = (rgb, depth)
        return self._blank

    def settings(self, settings: ViewSettings) -> ViewSettings:
        """``settings`` asking the renderer for colour in this format's order."""
        return replace(settings, bgr=True) if self.bgr else settings

    def images(self, view: View) -> tuple:
        """``(colour, depth, human mask, semantic, instance)`` of a rendered view.

        The view was rendered with :meth:`settings`: its colour is in this format's order.
        Depth is blank when not rendered; the mask and labels are None when not asked for.
        """
        rgb = view.rgb
        if view.depth is None:
            h, w = view.rgb.shape[:2]
            depth = self.blank(w, h)[1]
        elif self.metres:
            depth = view.depth[..., None]
        else:
            depth = depth_to_mattersim(view.depth)
        return rgb, depth, view.human_mask, view.semantic, view.instance
