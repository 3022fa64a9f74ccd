"""Diverged physics, told by MuJoCo's warning counters.

When a simulation diverges, MuJoCo resets the state and counts a warning (bad positions,
velocities or accelerations; a full contact or constraint buffer). Comparing the counters
before and after a step tells that it happened, so a body's pose after it is not trusted.
"""

from __future__ import annotations

import mujoco


class DivergedError(Exception):
    """Raised inside a step when MuJoCo reports diverged physics."""


DIVERGENCE_WARNINGS = tuple(
    int(w)
    for w in (
        mujoco.mjtWarning.mjWARN_BADQPOS,
        mujoco.mjtWarning.mjWARN_BADQVEL,
        mujoco.mjtWarning.mjWARN_BADQACC,
        mujoco.mjtWarning.mjWARN_CONTACTFULL,
        mujoco.mjtWarning.mjWARN_CNSTRFULL,
    )
)
"""The warnings that mean the physics diverged."""


def warning_counts(data: mujoco.MjData) -> tuple[int, ...]:
    """How often each of :data:`DIVERGENCE_WARNINGS` has been raised in ``data``."""
    return tuple(int(data.warning[w].number) for w in DIVERGENCE_WARNINGS)
