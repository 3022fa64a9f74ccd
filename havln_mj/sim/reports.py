"""The simulator's reports: its people as each state has them, and its timers.

:class:`SimulatorReports` is the part of :class:`~havln_mj.sim.simulator.Simulator` that
answers questions about the running batch without changing it: ``getHumanState``,
``getHumanPositions`` (HA3D's) and MatterSim's ``resetTimers``/``timingInfo``.
"""

from __future__ import annotations

import numpy as np

from havln_mj.errors import NotInitializedError
from havln_mj.sim.batch import Batch


class SimulatorReports:
    """People and timing queries over the simulator's batch (a base of the simulator)."""

    _batch: Batch | None
    _timers: dict

    def getHumanState(self) -> list[list]:  # noqa: N802
        """Each element's people as its state has them: a list of states per element.

        People are posed at the element's time (on HA3D's clock, at the shared counter's
        time of the element's last state). A state
        (:class:`havln_mj.humans.crowd.PersonState`) has ``position`` (pelvis), ``heading``,
        ``velocity``, ``activity``, ``text`` and ``region``.
        """
        self._started("getHumanState")
        return [el.crowd.states(el.people_t) for el in self._batch.elements]

    def getHumanPositions(self) -> list[np.ndarray]:  # noqa: N802 - getHumanState's sibling
        """Each element's people's pelvis positions ``(K, 3)`` as its state has them.

        The ``position`` of every :meth:`getHumanState` entry, without computing the rest.
        """
        self._started("getHumanPositions")
        return [self._batch.people_at(el).copy() for el in self._batch.elements]

    def _started(self, what: str) -> None:
        if self._batch is None or not self._batch.elements:
            raise NotInitializedError(f"{what} called before newEpisode()")

    # ------------------------------------------------------------------ timing

    def resetTimers(self) -> None:  # noqa: N802
        """Zeroes the timers ``timingInfo`` reports."""
        self._timers.update(process=0.0, render=0.0, frames=0)  # the batch shares the dict

    def timingInfo(self) -> str:  # noqa: N802
        """Time spent in simulator calls and in rendering since the last reset."""
        t = self._timers
        frames = t["frames"]
        fps = f"{frames / t['render']:.1f} fps" if t["render"] > 0 else "n/a"
        return (
            f"Rendered {frames} frames\n"
            f"Process time: {t['process'] * 1e3:.1f} ms\n"
            f"\tRendering: {t['render'] * 1e3:.1f} ms ({fps})\n"
        )

    get_human_state = getHumanState
