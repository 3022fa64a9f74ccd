"""Camera angles as MatterSim keeps them: heading wrap, elevation limits, discretised views.

Continuous mode: heading wraps into [0, 2π); elevation is clamped to the limits (default
±0.94 rad). Discretised mode (12 headings × 3 elevations, 30° apart): heading snaps to the
nearest 30°, elevation to −30° below −15°, +30° above +15°, else 0, and the limits are
ignored; ``viewIndex = heading step + 12 × level`` with level 0 looking down. A discretised
turn uses only the sign of each delta, so elevation saturates at ±30°.
"""

from __future__ import annotations

import math

from havln_mj.frames import TWO_PI, wrap_heading

HEADING_COUNT = 12
ELEVATION_COUNT = 3
HEADING_INCREMENT = TWO_PI / HEADING_COUNT
ELEVATION_INCREMENT = math.pi / 6
NUM_VIEWS = HEADING_COUNT * ELEVATION_COUNT
DEFAULT_ELEVATION_LIMITS = (-0.94, 0.94)


def valid_elevation_limits(lo: float, hi: float) -> bool:
    """MatterSim's rule: lo in (−π/2, 0) and hi in (0, π/2)."""
    return -math.pi / 2 < lo < 0.0 < hi < math.pi / 2


def continuous_view(heading: float, elevation: float, limits: tuple[float, float]) -> tuple:
    """Returns ``(heading, elevation, 0)``: heading wrapped, elevation clamped."""
    return wrap_heading(heading), min(max(elevation, limits[0]), limits[1]), 0


def discrete_view(heading: float, elevation: float) -> tuple[float, float, int]:
    """Returns ``(heading, elevation, viewIndex)`` snapped to the 36 discrete views."""
    # Half away from zero, as C's lround (Python's round() goes to even).
    step = math.floor(wrap_heading(heading) / HEADING_INCREMENT + 0.5) % HEADING_COUNT
    half = ELEVATION_INCREMENT / 2
    level = 0 if elevation < -half else 2 if elevation > half else 1
    return step * HEADING_INCREMENT, (level - 1) * ELEVATION_INCREMENT, step + HEADING_COUNT * level


def discrete_delta(delta: float, increment: float) -> float:
    """A discretised turn: one increment in the direction of ``delta`` (0 stays 0)."""
    return increment if delta > 0.0 else -increment if delta < 0.0 else 0.0
