"""Gymnasium environments for HA-VLN (the ``gym`` extra: ``pip install havln_mj[gym]``).

Importing this package registers ``HAVLN-Graph-v0``, ``HAVLN-Ego-v0`` and ``HAVLN-Go1-v0``
(see :mod:`havln_mj.gym.registration`); the simulator core never imports gymnasium.

Example:
    >>> import gymnasium as gym  # doctest: +SKIP
    >>> import havln_mj.gym
    >>> env = gym.make("HAVLN-Graph-v0", width=64, height=64)
    >>> obs, info = env.reset(seed=0)
    >>> obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
"""

from __future__ import annotations

try:
    import gymnasium  # noqa: F401 - only to fail early with an actionable message
except ImportError as exc:  # pragma: no cover - depends on the installation
    from havln_mj.errors import DependencyNotInstalledError

    raise DependencyNotInstalledError(
        "havln_mj.gym needs gymnasium: pip install 'havln_mj[gym]' (or gymnasium>=1.0)"
    ) from exc

from havln_mj.gym.envs import EgoEnv, Go1Env, GraphEnv, HAVLNEnv
from havln_mj.gym.registration import ENV_IDS, register_envs
from havln_mj.tasks.vocab import Vocabulary

register_envs()

__all__ = ["ENV_IDS", "EgoEnv", "Go1Env", "GraphEnv", "HAVLNEnv", "Vocabulary", "register_envs"]
