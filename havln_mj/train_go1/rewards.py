"""The reward: a weighted sum of terms, each a rate (per second) times the policy period.

=================  =====================================================================
tracking_lin_vel   ``exp(-(v_x - v_pace)² / σ)``: forward speed (yaw frame) against the
                   terrain gait's own pace (the command after its acceleration limit and its
                   speed cap on rough ground), so a robot is asked only what the gait asks
tracking_ang_vel   ``exp(-(ω_z - ω_cmd)² / σ)``: yaw rate against the command
upright            ``roll² + (pitch - pitch_ref)²``: the trunk level across, and pitched as the
                   gait's line through the feet asks along
torque             ``Σ τ²`` over the 12 actuators (N·m): effort and heat
action_rate        ``Σ (a - a_prev)²``: smooth residuals
action_size        ``Σ a²``: stay near the gait where it needs no help
clearance          ``Σ_swing feet max(0, h_c - h) · |v_xy|``: a swinging foot moving forward
                   lower than ``clearance_height`` over the ground under it (stubbed toes)
collision          number of contacts of the trunk, hips, thighs or upper shins with the terrain
fall               once, when the episode ends in a fall (not a rate)
=================  =====================================================================

Positive weights reward, negative penalise (``RewardConfig``).
"""

from __future__ import annotations

import math

from havln_mj.train_go1.config import RewardConfig

RATE_TERMS = (
    "tracking_lin_vel",
    "tracking_ang_vel",
    "upright",
    "torque",
    "action_rate",
    "action_size",
    "clearance",
    "collision",
)


def reward(
    cfg: RewardConfig, raw: dict[str, float], dt: float, fell: bool
) -> tuple[float, dict[str, float]]:
    """The step's reward and its weighted terms.

    Args:
        cfg: Weights.
        raw: Unweighted values: ``lin_vel_error`` and ``ang_vel_error`` (squared errors) and
            the other rate terms by name.
        dt: Policy period (s).
        fell: Whether the robot fell this step.
    """
    s = cfg.tracking_sigma
    values = dict(raw)
    values["tracking_lin_vel"] = math.exp(-raw["lin_vel_error"] / s)
    values["tracking_ang_vel"] = math.exp(-raw["ang_vel_error"] / s)
    terms = {name: getattr(cfg, name) * values[name] * dt for name in RATE_TERMS}
    terms["fall"] = cfg.fall if fell else 0.0
    return sum(terms.values()), terms
