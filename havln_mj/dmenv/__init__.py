"""A ``dm_env`` adapter for dm_control users (the ``dm`` extra: ``pip install havln_mj[dm]``).

:func:`load` makes a :class:`~havln_mj.dmenv.environment.HAVLNEnvironment` for one of the
action sets (``"graph"``, ``"ego"``, ``"robot"``); the simulator core never imports
``dm_env``.

Example:
    >>> from havln_mj import dmenv  # doctest: +SKIP
    >>> env = dmenv.load("ego", rgb=False, seed=0)
    >>> timestep = env.reset()
    >>> timestep = env.step(1)  # FORWARD
"""

from __future__ import annotations

try:
    import dm_env  # noqa: F401 - only to fail early with an actionable message
except ImportError as exc:  # pragma: no cover - depends on the installation
    from havln_mj.errors import DependencyNotInstalledError

    raise DependencyNotInstalledError(
        "havln_mj.dmenv needs dm_env: pip install 'havln_mj[dm]' (dm-control, or dm-env)"
    ) from exc

from havln_mj.dmenv.environment import ACTION_SETS, MAX_STEPS, HAVLNEnvironment, load

__all__ = ["ACTION_SETS", "MAX_STEPS", "HAVLNEnvironment", "load"]
