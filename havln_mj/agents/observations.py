"""What an egocentric agent observes at each step, and which actions it may take.

An observation is the cached feature of the view the agent looks at (its viewpoint,
``viewIndex`` and time slot, see :mod:`havln_mj.agents.features`) followed by
:data:`PROPRIO_DIM` values the agent knows about itself: its camera level (one-hot down /
level / up), whether FORWARD would move (HA3D masks FORWARD when no viewpoint is ahead), and
whether its last action came within the collision distance of a person (HA3D's
``isCrashed`` observation).
"""

from __future__ import annotations

import numpy as np

from havln_mj.agents.demos import N_ACTIONS
from havln_mj.agents.features import FeatureStore
from havln_mj.agents.views import forward_possible
from havln_mj.sim.egocentric import EgoAction
from havln_mj.sim.state import SimState
from havln_mj.sim.viewing import HEADING_COUNT

PROPRIO_DIM = 5
"""Values an observation holds about the agent itself, after the view feature."""


def action_mask(state: SimState, half_hfov: float) -> np.ndarray:
    """``(6,)`` bool: the actions that change something (STOP always may be taken)."""
    level = state.viewIndex // HEADING_COUNT
    mask = np.ones(N_ACTIONS, bool)
    mask[EgoAction.FORWARD] = forward_possible(state, half_hfov)
    mask[EgoAction.LOOK_UP] = level < 2
    mask[EgoAction.LOOK_DOWN] = level > 0
    return mask


def observe(store: FeatureStore, state: SimState, mask: np.ndarray) -> np.ndarray:
    """``(D + PROPRIO_DIM,)`` float32: the view feature, then the agent's own inputs.

    ``mask`` is the state's :func:`action_mask` (its FORWARD entry is an input).
    """
    out = np.zeros(store.dim + PROPRIO_DIM, np.float32)
    out[: store.dim] = store.feature(
        state.scanId, state.location.viewpointId, state.viewIndex, state.time
    )
    out[store.dim + state.viewIndex // HEADING_COUNT] = 1.0
    out[store.dim + 3] = float(mask[EgoAction.FORWARD])
    out[store.dim + 4] = float(state.isCrushed)
    return out
