"""Checks of the simulator's action arguments: the whole batch is checked before anything moves.

Every bad value raises :class:`~havln_mj.errors.InvalidActionError` (or
:class:`~havln_mj.errors.BatchSizeError` for a list of the wrong length) naming the batch
element, the value and what is valid.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence

import numpy as np

from havln_mj.errors import BatchSizeError, InvalidActionError, InvalidArgumentError
from havln_mj.sim.egocentric import DEFAULT_TURN, EgoAction, ego_to_mattersim
from havln_mj.sim.settings import _check_angle
from havln_mj.sim.state import ViewPoint

GraphStep = tuple[int, int, float, float]  # (element, navigable index, dHeading, dElevation)


def per_element(name: str, values: object, batch_size: int) -> list:
    """``values`` as a list with one entry per batch element (a list given is not copied)."""
    if type(values) is list and len(values) == batch_size:
        return values  # the common case, checked cheaply
    if isinstance(values, str) or not isinstance(values, Sequence | np.ndarray):
        raise BatchSizeError(
            f"{name} takes a list with one entry per batch element (batch size {batch_size}), "
            f"got {values!r}"
        )
    if len(values) != batch_size:
        raise BatchSizeError(
            f"{name} has {len(values)} entries but the batch size is {batch_size} (setBatchSize)"
        )
    return list(values)


def check_index(i: int, navigable: Sequence[ViewPoint], k: object) -> int:
    """Element ``i``'s navigable-location index ``k``."""
    n = len(navigable)
    if type(k) is int and 0 <= k < n:
        return k  # the common case, checked cheaply
    if isinstance(k, bool) or not isinstance(k, numbers.Integral) or not 0 <= k < n:
        raise InvalidActionError(
            f"action index {k!r} for batch element {i} is out of range: "
            f"{n} navigable locations, valid 0–{n - 1}"
        )
    return int(k)


def check_graph_steps(
    elements: Sequence, indices: object, headings: object, elevations: object
) -> list[GraphStep]:
    """Each element's ``makeAction`` arguments checked: ``(element, index, dh, de)``.

    Raises:
        BatchSizeError: A list's length is not the number of elements.
        InvalidActionError: An index is out of range or a delta is not finite.
    """
    n = len(elements)
    if not (type(indices) is list and len(indices) == n):
        indices = per_element("index", indices, n)
    if not (type(headings) is list and len(headings) == n):
        headings = per_element("heading", headings, n)
    if not (type(elevations) is list and len(elevations) == n):
        elevations = per_element("elevation", elevations, n)
    steps = []
    for i, el in enumerate(elements):
        k, dh, de = indices[i], headings[i], elevations[i]
        if not (type(k) is int and 0 <= k < len(el.navigable)):
            k = check_index(i, el.navigable, k)
        if not (type(dh) is float and math.isfinite(dh)):
            dh = check_delta(i, dh)
        if not (type(de) is float and math.isfinite(de)):
            de = check_delta(i, de)
        steps.append((i, k, dh, de))
    return steps


def check_delta(i: int, value: object) -> float:
    """Element ``i``'s heading or elevation change (finite radians)."""
    if isinstance(value, float) and math.isfinite(value):
        return value  # the common case, checked cheaply
    try:
        return _check_angle(f"turn for batch element {i}", value)
    except InvalidArgumentError as exc:
        raise InvalidActionError(str(exc)) from None


def check_robot_action(action: object, valid: Sequence[str]) -> str:
    """A robot action name the body takes (``valid``), or ``"stop"``."""
    if action == "stop" or action in valid:
        return action
    if not valid:
        raise InvalidActionError(
            f'robot action {action!r} needs a robot body (Simulator(body="go1")); this '
            "simulator drives a point body"
        )
    raise InvalidActionError(f"robot action {action!r} unknown; valid: stop, {', '.join(valid)}")


def parse_mixed(
    elements: Sequence, actions: Sequence[object], half_hfov: float, robot_actions: Sequence[str]
) -> tuple[list[GraphStep], list[str]]:
    """Splits one action of any kind per element into graph steps and robot actions.

    A graph action is ``(index, dHeading, dElevation)``, an
    :class:`~havln_mj.sim.egocentric.EgoAction` becomes its graph step (none for STOP), a string is
    a robot action, None leaves the element alone.

    Returns:
        The graph steps, and one robot action per element (``"stop"``: none).
    """
    graph, robot = [], ["stop"] * len(elements)
    for i, (el, act) in enumerate(zip(elements, actions, strict=True)):
        if act is None:
            continue
        if isinstance(act, EgoAction):
            args = ego_to_mattersim(act, el.state, half_hfov, DEFAULT_TURN)
            if args is not None:
                graph.append((i, *args))
        elif isinstance(act, str):
            robot[i] = check_robot_action(act, robot_actions)
        elif isinstance(act, tuple | list) and len(act) == 3:
            k, dh, de = act
            graph.append(
                (i, check_index(i, el.navigable, k), check_delta(i, dh), check_delta(i, de))
            )
        else:
            raise InvalidActionError(
                f"action {act!r} for batch element {i} is no action: give (index, dHeading, "
                "dElevation), an EgoAction, a robot action name or None"
            )
    return graph, robot
