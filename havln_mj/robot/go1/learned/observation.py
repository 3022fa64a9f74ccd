"""What a learned GO1 policy sees, and how its action is applied (:class:`PolicySpec`).

The observation is one vector, in this order (trunk frame: x forward, y left, z up):

=====================  ====  =========================================================
base angular velocity     3  rad/s, trunk frame
projected gravity         3  the unit gravity vector in the trunk frame
command                   3  commanded forward and leftward speed (m/s), yaw rate (rad/s)
joint positions          12  minus the home pose (rad)
joint velocities         12  rad/s
last action              12  the policy's previous output
gait reference           12  the terrain gait's joint targets minus the home pose (rad)
gait phase                2  sin, cos of the gait cycle
height scan             n·m  ground height minus trunk height (m) at ``scan_x × scan_y``
=====================  ====  =========================================================

The height scan is read through :class:`~havln_mj.robot.go1.height_scan.HeightScan` at points
on a grid around the trunk that turns with its yaw (not its pitch or roll); a cell inside a
solid (``inf``) reads ``scan_clip[1]``, no ground (``-inf``) reads ``scan_clip[0]``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import mujoco
import numpy as np

from havln_mj.errors import MalformedDataError
from havln_mj.robot.go1 import constants as const
from havln_mj.robot.go1.height_scan import HeightScan

PROPRIO = 3 + 3 + 3 + 12 + 12 + 12 + 12 + 2
HOME = np.array(const.HOME_LEG * 4)


@dataclass(frozen=True)
class PolicySpec:
    """The observation layout and action rule a policy was trained with.

    Attributes:
        scan_x: Forward offsets of the scan grid from the trunk (m).
        scan_y: Leftward offsets (m).
        scan_clip: Range the scan's heights are clipped to (m, relative to the trunk).
        action_scale: Radians per unit of action.
        clip_actions: Actions are clipped to ``±clip_actions``.
        clip_obs: Normalised observations are clipped to ``±clip_obs``.
        decimation: Physics steps per policy step (10 × 2 ms: 50 Hz).
        action: ``"residual"``: ``action_scale × action`` is added to the terrain gait's joint
            targets while the gait walks.
    """

    scan_x: tuple[float, ...] = tuple(round(-0.3 + 0.1 * k, 2) for k in range(11))
    scan_y: tuple[float, ...] = (-0.2, -0.1, 0.0, 0.1, 0.2)
    scan_clip: tuple[float, float] = (-1.0, 0.5)
    action_scale: float = 0.02
    clip_actions: float = 10.0
    clip_obs: float = 5.0
    decimation: int = 10
    action: str = "residual"

    @property
    def obs_size(self) -> int:
        """Length of the observation vector."""
        return PROPRIO + len(self.scan_x) * len(self.scan_y)

    @property
    def action_size(self) -> int:
        """Length of the action vector (one per joint)."""
        return 12

    def scan_points(self) -> np.ndarray:
        """The scan grid in the trunk's yaw frame, ``(n, 2)``."""
        return np.array([(x, y) for x in self.scan_x for y in self.scan_y], dtype=np.float64)

    def to_json(self) -> dict:
        """The spec as a JSON object."""
        return asdict(self)

    @classmethod
    def from_json(cls, raw: dict) -> PolicySpec:
        """The spec from :meth:`to_json`'s object.

        Raises:
            MalformedDataError: Unknown or badly typed fields.
        """
        if not isinstance(raw, dict):
            raise MalformedDataError(f"a policy spec must be a JSON object, got {raw!r}")
        known = set(cls.__dataclass_fields__)
        unknown = sorted(set(raw) - known)
        if unknown:
            raise MalformedDataError(
                f"unknown policy spec fields {unknown}; valid: {sorted(known)}"
            )
        values = {k: tuple(v) if isinstance(v, list) else v for k, v in raw.items()}
        try:
            spec = cls(**values)
        except TypeError as err:
            raise MalformedDataError(f"bad policy spec: {err}") from err
        if spec.action != "residual" or spec.decimation < 1 or len(spec.scan_clip) != 2:
            raise MalformedDataError(f"unsupported policy spec: {raw}")
        return spec


class Observer:
    """Builds observation vectors of one robot.

    Args:
        spec: The layout.
        data: The robot's data.
        trunk_id: The trunk body.
        dadr: dof address of the free joint.
        joint_qadr: qpos addresses of the 12 leg joints.
        joint_dadr: dof addresses of the 12 leg joints.
        scan: The height scan.
    """

    def __init__(
        self,
        spec: PolicySpec,
        data: mujoco.MjData,
        trunk_id: int,
        dadr: int,
        joint_qadr: list[int],
        joint_dadr: list[int],
        scan: HeightScan,
    ) -> None:
        self.spec, self.data, self.trunk_id, self.dadr = spec, data, trunk_id, dadr
        self.joint_qadr, self.joint_dadr = np.array(joint_qadr), np.array(joint_dadr)
        self.scan = scan
        self._points = spec.scan_points()

    def scan_heights(self) -> np.ndarray:
        """Ground height minus trunk height at the scan points, clipped."""
        d = self.data
        x, y, z = d.xpos[self.trunk_id]
        r = d.xmat[self.trunk_id]
        yaw = math.atan2(r[3], r[0])
        c, s = math.cos(yaw), math.sin(yaw)
        p = self._points
        wx, wy = x + c * p[:, 0] - s * p[:, 1], y + s * p[:, 0] + c * p[:, 1]
        h = self.scan.heights(np.stack([wx, wy], axis=1), z)
        lo, hi = self.spec.scan_clip
        return np.clip(h - z, lo, hi)

    def __call__(
        self,
        command: tuple[float, float, float],
        last_action: np.ndarray,
        reference: list[float],
        phase: float,
    ) -> np.ndarray:
        """The observation vector.

        Args:
            command: Commanded (vx, vy, wz) in the trunk's yaw frame.
            last_action: The policy's previous action.
            reference: The terrain gait's 12 joint targets.
            phase: The gait cycle (its fraction is used).
        """
        d = self.data
        r = d.xmat[self.trunk_id]
        a = 2.0 * math.pi * phase
        return np.concatenate(
            (
                d.qvel[self.dadr + 3 : self.dadr + 6],  # the free joint's is in the trunk frame
                (-r[6], -r[7], -r[8]),
                command,
                d.qpos[self.joint_qadr] - HOME,
                d.qvel[self.joint_dadr],
                last_action,
                np.asarray(reference) - HOME,
                (math.sin(a), math.cos(a)),
                self.scan_heights(),
            )
        )
