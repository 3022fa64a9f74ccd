"""Registers the environments with gymnasium under versioned ids.

====================  ========================================  =================
id                    environment                               max episode steps
====================  ========================================  =================
``HAVLN-Graph-v0``    :class:`~havln_mj.gym.envs.GraphEnv`      40
``HAVLN-Ego-v0``      :class:`~havln_mj.gym.envs.EgoEnv`        120
``HAVLN-Go1-v0``      :class:`~havln_mj.gym.envs.Go1Env`        200
====================  ========================================  =================

Importing :mod:`havln_mj.gym` registers them; ``gymnasium.make("havln_mj.gym:HAVLN-Graph-v0")``
works without that import. The step limits are the ``TimeLimit`` truncation; override with
``gymnasium.make(id, max_episode_steps=n)``.
"""

from __future__ import annotations

import gymnasium as gym

ENV_IDS: dict[str, tuple[str, int]] = {
    "HAVLN-Graph-v0": ("havln_mj.gym.envs:GraphEnv", 40),
    "HAVLN-Ego-v0": ("havln_mj.gym.envs:EgoEnv", 120),
    "HAVLN-Go1-v0": ("havln_mj.gym.envs:Go1Env", 200),
}
"""The registered ids, each with its entry point and step limit."""


def register_envs() -> None:
    """Registers every id of :data:`ENV_IDS` (ids already registered are left alone)."""
    for env_id, (entry_point, steps) in ENV_IDS.items():
        if env_id not in gym.registry:
            gym.register(id=env_id, entry_point=entry_point, max_episode_steps=steps)
