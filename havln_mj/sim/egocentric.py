"""HA-VLN's egocentric action set and how each action maps to ``makeAction``.

=============  ==========================================================================
action         ``makeAction(index, dHeading, dElevation)``
=============  ==========================================================================
STOP           nothing: the simulator is not called for this element (no step, no time);
               ending the episode is the task's business
FORWARD        ``(k, 0, 0)``, k = the first navigable location (nearest the view centre)
               whose bearing is within half the horizontal field of view; ``(0, 0, 0)``
               (wait in place) when there is none
TURN_LEFT      ``(0, −turn, 0)``
TURN_RIGHT     ``(0, +turn, 0)``
LOOK_UP        ``(0, 0, +turn)``
LOOK_DOWN      ``(0, 0, −turn)``
=============  ==========================================================================

``turn`` is 30° (π/6), one discrete view step. The numbering follows HA-VLN's action list.
HA3D's task code writes the same moves as ``(1, 0, 0)``, ``(0, ±1, 0)`` and ``(0, 0, ±1)`` in
discretised mode; FORWARD here also works with continuous angles and unrestricted navigation.
"""

from __future__ import annotations

import math
from enum import IntEnum

from havln_mj.errors import InvalidActionError
from havln_mj.sim.state import SimState

DEFAULT_TURN = math.pi / 6


class EgoAction(IntEnum):
    """The six egocentric actions."""

    STOP = 0
    FORWARD = 1
    TURN_LEFT = 2
    TURN_RIGHT = 3
    LOOK_UP = 4
    LOOK_DOWN = 5


def parse_ego_action(action: object) -> EgoAction:
    """An ``EgoAction`` from itself, its number or its name (any case).

    Raises:
        InvalidActionError: ``action`` names no egocentric action.
    """
    try:
        if isinstance(action, str):
            return EgoAction[action.strip().upper()]
        if isinstance(action, bool):
            raise ValueError
        return EgoAction(action)
    except (KeyError, ValueError, TypeError):
        valid = ", ".join(f"{a.value}={a.name}" for a in EgoAction)
        raise InvalidActionError(f"unknown egocentric action {action!r}; valid: {valid}") from None


def ego_to_mattersim(
    action: EgoAction, state: SimState, half_hfov: float, turn: float = DEFAULT_TURN
) -> tuple[int, float, float] | None:
    """The ``makeAction`` arguments for ``action`` in ``state`` (None for STOP)."""
    if action is EgoAction.STOP:
        return None
    if action is EgoAction.FORWARD:
        for k, loc in enumerate(state.navigableLocations[1:], start=1):
            if abs(loc.rel_heading) <= half_hfov:
                return k, 0.0, 0.0
        return 0, 0.0, 0.0
    return {
        EgoAction.TURN_LEFT: (0, -turn, 0.0),
        EgoAction.TURN_RIGHT: (0, turn, 0.0),
        EgoAction.LOOK_UP: (0, 0.0, turn),
        EgoAction.LOOK_DOWN: (0, 0.0, -turn),
    }[action]
