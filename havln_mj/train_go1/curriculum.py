"""Terrain levels per robot, moved up or down by how far each episode got (as legged_gym does)."""

from __future__ import annotations

import numpy as np

from havln_mj.train_go1.config import CurriculumConfig


class Curriculum:
    """The terrain level of each robot.

    Args:
        cfg: Promotion and demotion thresholds.
        levels: Number of levels.
        start: Each robot's first level.
        rng: The run's generator (a robot past the last level goes to a random one).
    """

    def __init__(
        self, cfg: CurriculumConfig, levels: int, start: np.ndarray, rng: np.random.Generator
    ) -> None:
        self.cfg, self.levels, self.rng = cfg, levels, rng
        self.level = np.asarray(start, dtype=np.int64).copy()

    def update(self, env: int, progress: float, fell: bool) -> int:
        """Moves robot ``env`` after an episode and returns its new level.

        Args:
            env: The robot.
            progress: Distance walked over the distance asked for.
            fell: Whether the episode ended in a fall.
        """
        c, lv = self.cfg, int(self.level[env])
        if not fell and progress >= c.promote:
            lv = lv + 1 if lv + 1 < self.levels else int(self.rng.integers(0, self.levels))
        elif fell or progress < c.demote:
            lv = max(lv - 1, 0)
        self.level[env] = lv
        return lv

    @property
    def mean(self) -> float:
        """Mean level over the robots."""
        return float(self.level.mean())
