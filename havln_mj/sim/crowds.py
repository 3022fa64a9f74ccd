"""The people of one simulator: which crowd each scan gets, and how people behave.

:class:`CrowdBook` holds a simulator's choices about people — whether scans have people
(HA3D's placement rule through :class:`~havln_mj.sim.people.HumanCrowds`, or a user's
factory), the user's data files, how often people come together, whether they react to the
agent, whether they stay pinned to their spots — and makes each scan's crowd once, from the
simulator's seed and the scan's id (not from the order scans are visited).
"""

from __future__ import annotations

import numbers
import zlib
from collections.abc import Callable
from pathlib import Path

import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.scan import Scan
from havln_mj.sim.crowd import NO_CROWD, Crowd

CrowdFactory = Callable[[str, NavGraph, np.random.Generator], Crowd]
"""Makes a scan's crowd from ``(scan id, graph, generator)``."""


def reactions_of(value: object) -> object | None:
    """The reactions ``reactions=`` asks for (None when people do not react).

    Raises:
        InvalidArgumentError: Neither a bool nor a :class:`~havln_mj.humans.reactions.Reactions`.
    """
    if value is False:
        return None
    from havln_mj.humans.reactions import Reactions  # the humans package, only when used

    if value is True:
        return Reactions()
    if isinstance(value, Reactions):
        return value if value.enabled else None
    raise InvalidArgumentError(f"reactions takes a bool or a Reactions, got {value!r}")


class CrowdBook:
    """A simulator's people, scan by scan.

    Args:
        humans: Whether scans have people (HA3D's rule), or a :data:`CrowdFactory`.
        files: The user's placement file, HAPS motion folder and SMPL model (or None each).
        together: Chance that a person placed by HA3D's rule is joined by others.
        reactions: Whether people notice the agent (a bool, or a ``Reactions``).
        pinned: Whether people stay on the floor points they were placed at.

    Raises:
        InvalidArgumentError: A bad value, or pinned people who react.
    """

    def __init__(
        self,
        humans: bool | CrowdFactory,
        files: tuple[Path | str | None, Path | str | None, Path | str | None],
        together: float = 0.0,
        reactions: object = False,
        pinned: bool = False,
    ) -> None:
        if not (isinstance(humans, bool) or callable(humans)):
            raise InvalidArgumentError(f"humans must be a bool or a crowd factory, got {humans!r}")
        if not (isinstance(together, numbers.Real) and 0.0 <= together <= 1.0):
            raise InvalidArgumentError(f"together must be a chance in [0, 1], got {together!r}")
        if not isinstance(pinned, bool):
            raise InvalidArgumentError(f"pinned_people takes a bool, got {pinned!r}")
        self.reactions = reactions_of(reactions)
        if pinned and self.reactions is not None:
            raise InvalidArgumentError("pinned_people=True needs people who do not react")
        self.humans, self.files = humans, files
        self.together, self.pinned = float(together), pinned
        self._factory: CrowdFactory | None = None
        self._crowds: dict[str, Crowd] = {}
        self._seed = 0

    def start(self, load_scan: Callable[[str], Scan], seed: int, mp3d_dir: str | None) -> None:
        """Forgets every crowd made so far; new ones come from ``seed``."""
        self._crowds, self._seed = {}, seed
        if self.humans is True:
            from havln_mj.sim.people import HumanCrowds  # the humans package, only when used

            self._factory = HumanCrowds(
                load_scan, *self.files, together=self.together, mp3d_dir=mp3d_dir
            )
        else:
            self._factory = self.humans or None

    def crowd(self, scan_id: str, graph: NavGraph) -> Crowd:
        """The people of ``scan_id`` (made on first use)."""
        crowd = self._crowds.get(scan_id)
        if crowd is None:
            crowd = NO_CROWD
            if self._factory is not None:
                # Each scan's people depend on the seed and the scan, not on visiting order.
                rng = np.random.default_rng([self._seed, zlib.crc32(scan_id.encode())])
                crowd = self._factory(scan_id, graph, rng)
                if self.pinned and len(crowd):
                    from havln_mj.sim.people import PinnedCrowd  # the humans package, when used

                    crowd = PinnedCrowd(crowd)
            self._crowds[scan_id] = crowd
        return crowd

    def source(self, scan_id: str) -> str:
        """Where the people of ``scan_id`` come from, in words (for banners and reports)."""
        if self._factory is None:
            return "none (humans=False)"
        source = getattr(self._factory, "source", None)
        return source(scan_id) if source is not None else "the simulator's crowd factory"
