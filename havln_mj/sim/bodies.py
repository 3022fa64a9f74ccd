"""The body kinds a simulator can have, made by name: the point camera rig or the GO1.

:mod:`havln_mj.sim.body` is the protocol; this module picks its implementation
(:mod:`havln_mj.sim.point`, :mod:`havln_mj.sim.legged_body`), loading the GO1's physics only
when it is asked for.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

from havln_mj.errors import InvalidArgumentError
from havln_mj.sim.body import BodyKind


def make_kind(
    name: str,
    load_scan: Callable[[str], object],
    cfg: object,
    speed: float,
    turn_rate: float,
    legged: object | None,
) -> BodyKind:
    """The body kind called ``name`` (:data:`BODY_KINDS`) for a simulator's settings.

    Args:
        name: ``"point"`` or ``"go1"``.
        load_scan: Loads a scan by id.
        cfg: The simulator's :class:`~havln_mj.sim.settings.Settings`.
        speed: The point body's speed (m/s).
        turn_rate: The point body's turning rate (rad/s).
        legged: The GO1's :class:`~havln_mj.sim.legged.LeggedOptions` (None: defaults).

    Raises:
        InvalidArgumentError: Unknown name, or ``legged`` of the wrong type.
    """
    if name == "go1":
        from havln_mj.sim.legged import LeggedOptions  # the GO1's physics, only when used
        from havln_mj.sim.legged_body import LeggedKind

        options = legged or LeggedOptions()
        if not isinstance(options, LeggedOptions):
            raise InvalidArgumentError(f"legged takes LeggedOptions, got {options!r}")
        return LeggedKind(load_scan, cfg.world_options, options)
    if name == "point":
        from havln_mj.sim.point import PointKind

        skybox = cfg.dataset_path if cfg.skybox else None
        # Segmentation is fixed at initialize: without it, worlds need no label meshes.
        options = cfg.world_options if cfg.labels else replace(cfg.world_options, labels=False)
        return PointKind(load_scan, options, cfg.cache_size, speed, turn_rate, skybox_root=skybox)
    raise InvalidArgumentError(f"body {name!r} unknown; valid: {', '.join(BODY_KINDS)}")


BODY_KINDS = ("point", "go1")
"""The bodies a simulator can have (MatterSim's point camera rig, or the simulated GO1)."""
