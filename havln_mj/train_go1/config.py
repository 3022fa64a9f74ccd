"""The training configuration: a JSON object of four sections, each a dataclass here.

Keys starting with ``_`` are comments; missing keys keep their defaults; unknown keys raise.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

from havln_mj.errors import InvalidArgumentError, MalformedDataError
from havln_mj.robot.go1.gains import known_fields


@dataclass(frozen=True)
class EnvConfig:
    """The simulated robots and their terrains.

    Attributes:
        num_envs: Robots stepped in one process (one MjData each).
        episode_seconds: Episode length (s).
        levels: Terrain levels; 0 is flat, the last the hardest.
        risers: Riser heights from level 1 to the last (m), linear in between.
        treads: Tread depths (m); each stair level is built once per tread.
        max_ramp_deg: Ramp angle of the last level (degrees), linear from 0.
        flight_risers: Risers per flight (the course climbs one flight, then descends one).
        ramp_share: Share of the robots that train on ramps (the others on stairs).
        turn_share: Share of episodes that turn in place instead of walking.
        speed: Range of commanded forward speed (m/s).
        turn_rate: Range of the absolute yaw rate of turning episodes (rad/s).
        max_init_level: Robots start at a random level up to this one.
    """

    num_envs: int = 48
    episode_seconds: float = 8.0
    levels: int = 10
    risers: tuple[float, float] = (0.02, 0.19)
    treads: tuple[float, ...] = (0.25, 0.3, 0.35)
    max_ramp_deg: float = 30.0
    flight_risers: int = 5
    ramp_share: float = 0.25
    turn_share: float = 0.1
    speed: tuple[float, float] = (0.2, 0.7)
    turn_rate: tuple[float, float] = (0.4, 1.2)
    max_init_level: int = 2


@dataclass(frozen=True)
class RewardConfig:
    """Weights of the reward terms (per second of simulated time; see ``rewards.py``)."""

    tracking_lin_vel: float = 1.0
    tracking_ang_vel: float = 0.5
    tracking_sigma: float = 0.05
    upright: float = -2.0
    torque: float = -2e-4
    action_rate: float = -0.02
    action_size: float = -0.01
    clearance: float = -2.0
    clearance_height: float = 0.05
    collision: float = -1.0
    fall: float = -2.0


@dataclass(frozen=True)
class CurriculumConfig:
    """When a robot moves up or down a terrain level (at the end of each episode).

    Progress is the distance walked along the command over the distance the gait's own pace
    asked for. At or above ``promote`` without a fall: one level up (from the last level, a
    random level). Below ``demote``, or fallen: one level down.
    """

    promote: float = 0.8
    demote: float = 0.4


@dataclass(frozen=True)
class PPOConfig:
    """Proximal policy optimisation (clipped surrogate, GAE, adaptive learning rate)."""

    steps_per_env: int = 48
    epochs: int = 5
    minibatches: int = 4
    gamma: float = 0.99
    lam: float = 0.95
    clip: float = 0.2
    value_coef: float = 1.0
    entropy_coef: float = 0.003
    learning_rate: float = 1e-3
    desired_kl: float = 0.01
    max_grad_norm: float = 1.0
    init_std: float = 0.5
    hidden: tuple[int, ...] = (128, 64)


@dataclass(frozen=True)
class TrainConfig:
    """Everything a training run needs.

    Attributes:
        seed: Seeds the one numpy Generator and torch.
        iterations: PPO iterations (each ``num_envs × steps_per_env`` transitions).
        checkpoint_every: Iterations between checkpoints (and exported policies).
        env: The robots and terrains.
        reward: Reward weights.
        curriculum: Level changes.
        ppo: The optimiser.
    """

    seed: int = 0
    iterations: int = 1000
    checkpoint_every: int = 20
    env: EnvConfig = field(default_factory=EnvConfig)
    reward: RewardConfig = field(default_factory=RewardConfig)
    curriculum: CurriculumConfig = field(default_factory=CurriculumConfig)
    ppo: PPOConfig = field(default_factory=PPOConfig)

    def __post_init__(self) -> None:
        e = self.env
        checks = (
            ("env.num_envs", e.num_envs, e.num_envs >= 1),
            ("env.levels", e.levels, e.levels >= 2),
            ("env.max_init_level", e.max_init_level, 0 <= e.max_init_level < e.levels),
            ("env.risers", e.risers, 0 < e.risers[0] <= e.risers[1] <= 0.3),
            ("env.treads", e.treads, len(e.treads) > 0 and min(e.treads) >= 0.15),
            ("env.flight_risers", e.flight_risers, 2 <= e.flight_risers <= 20),
            ("env.episode_seconds", e.episode_seconds, 0.5 <= e.episode_seconds <= 60),
            ("iterations", self.iterations, self.iterations >= 0),
            ("checkpoint_every", self.checkpoint_every, self.checkpoint_every >= 1),
            ("ppo.steps_per_env", self.ppo.steps_per_env, self.ppo.steps_per_env >= 2),
        )
        for name, value, ok in checks:
            if not ok:
                raise InvalidArgumentError(f"training config {name} is out of range: {value!r}")
        c = self.curriculum
        if not 0.0 <= c.demote <= c.promote <= math.inf:
            raise InvalidArgumentError(
                f"need 0 <= curriculum.demote <= curriculum.promote, got {c.demote}, {c.promote}"
            )

    def to_json(self) -> dict:
        """The configuration as a JSON object."""
        return asdict(self)


_SECTIONS = {
    "env": EnvConfig,
    "reward": RewardConfig,
    "curriculum": CurriculumConfig,
    "ppo": PPOConfig,
}


def config_from_json(raw: dict, where: str = "config") -> TrainConfig:
    """A :class:`TrainConfig` from its JSON object.

    Raises:
        MalformedDataError: Not an object, unknown keys, or badly typed values.
    """
    if not isinstance(raw, dict):
        raise MalformedDataError(f"{where} must be a JSON object")
    top = known_fields(raw, TrainConfig, where)
    try:
        for name, cls in _SECTIONS.items():
            section = top.get(name, {})
            if not isinstance(section, dict):
                raise MalformedDataError(f"{where}: {name!r} must be a JSON object")
            values = known_fields(section, cls, f"{where}: {name}")
            top[name] = cls(
                **{k: tuple(v) if isinstance(v, list) else v for k, v in values.items()}
            )
        return TrainConfig(**top)
    except TypeError as err:
        raise MalformedDataError(f"{where}: {err}") from err


def load_config(path: str | Path | None) -> TrainConfig:
    """Reads a configuration file (None: the defaults)."""
    if path is None:
        return TrainConfig()
    path = Path(path)
    try:
        raw = json.loads(path.read_text())
    except FileNotFoundError as err:
        raise InvalidArgumentError(f"training config not found: {path}") from err
    except json.JSONDecodeError as err:
        raise MalformedDataError(f"{path} is not valid JSON: {err}") from err
    return config_from_json(raw, str(path))
