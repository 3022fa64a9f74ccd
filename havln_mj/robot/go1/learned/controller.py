"""The terrain gait with a learned residual: the policy corrects its joint targets at 50 Hz.

The terrain gait (:mod:`~havln_mj.robot.go1.terrain_gait`) plans footholds and swings from the
height scan; the policy sees the robot, the command, the gait's targets and the scan
(:mod:`~havln_mj.robot.go1.learned.observation`) and adds ``action_scale × action`` to the
targets. Residuals train far faster than a policy that must first learn to walk, and a zero
residual is the terrain gait itself. While the gait stands (not walking) no residual is added.

A policy step is ``spec.decimation`` physics steps; the gait runs every
``control_decimation`` of them, so the policy acts on every ``decimation /
control_decimation``-th gait tick and its action holds in between. :meth:`LearnedGait.step`
does all of it; a trainer that batches many robots calls ``reference``, ``observe``
and ``targets`` itself and sets ``action``.
"""

from __future__ import annotations

import mujoco
import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.robot.go1.actuation import clip_joints
from havln_mj.robot.go1.gains import TerrainGains
from havln_mj.robot.go1.height_scan import HeightScan
from havln_mj.robot.go1.learned.observation import Observer, PolicySpec
from havln_mj.robot.go1.learned.policy import LearnedPolicy
from havln_mj.robot.go1.terrain_gait import TerrainGait


class LearnedGait(TerrainGait):
    """The terrain gait plus a learned residual on its joint targets.

    A :class:`~havln_mj.robot.go1.terrain_gait.TerrainGait` whose targets the policy corrects.

    Args:
        gains: The terrain gait's gains.
        data: The robot's data.
        est: The trunk state estimator.
        joint_qadr: qpos addresses of the 12 leg joints.
        joint_dadr: dof addresses of the 12 leg joints.
        foot_geoms: The 4 foot geom ids.
        scan: The height scan.
        trunk_id: The trunk body.
        dadr: dof address of the free joint.
        policy: The policy; None when the caller sets ``action`` itself.
        spec: The observation layout (default: the policy's).
    """

    def __init__(
        self,
        gains: TerrainGains,
        data: mujoco.MjData,
        est,
        joint_qadr: list[int],
        joint_dadr: list[int],
        foot_geoms: list[int],
        scan: HeightScan,
        trunk_id: int,
        dadr: int,
        policy: LearnedPolicy | None,
        spec: PolicySpec | None = None,
    ) -> None:
        super().__init__(gains, data, est, joint_qadr, joint_dadr, foot_geoms, scan)
        spec = spec or (policy.spec if policy is not None else PolicySpec())
        if spec.decimation % gains.control_decimation:
            raise InvalidArgumentError(
                f"the policy's decimation ({spec.decimation} physics steps) must be a multiple "
                f"of the terrain gait's control_decimation ({gains.control_decimation})"
            )
        self.policy, self.spec = policy, spec
        self.ticks = spec.decimation // gains.control_decimation
        self.observer = Observer(spec, data, trunk_id, dadr, joint_qadr, joint_dadr, scan)
        self.action = np.zeros(spec.action_size)
        self.command = (0.0, 0.0, 0.0)
        self._tick = 0

    def start(self) -> None:
        """Begins walking; the policy acts on the first tick."""
        super().start()
        self.action = np.zeros(self.spec.action_size)
        self._tick = 0

    def reference(
        self, dt: float, vx: float, vy: float, wz: float, ex: float = 0.0, ey: float = 0.0
    ) -> list[float]:
        """Advances the terrain gait and returns its targets.

        See :meth:`~havln_mj.robot.go1.terrain_gait.TerrainGait.step`.
        """
        self.command = (vx, vy, wz)
        return TerrainGait.step(self, dt, vx, vy, wz, ex, ey)

    def observe(self, reference: list[float]) -> np.ndarray:
        """The policy's observation now, given the gait's targets of this tick."""
        return self.observer(self.command, self.action, reference, self._cycle)

    def targets(self, reference: list[float]) -> list[float]:
        """The gait's targets plus the scaled residual (none while standing), in range."""
        if not self.walking:
            return reference
        q = np.asarray(reference) + self.spec.action_scale * self.action
        out: list[float] = []
        for leg in range(4):
            out.extend(clip_joints(q[3 * leg : 3 * leg + 3].tolist()))
        return out

    def step(
        self, dt: float, vx: float, vy: float, wz: float, ex: float = 0.0, ey: float = 0.0
    ) -> list[float]:
        """Advances the gait by ``dt``; every ``ticks`` ticks asks the policy for a residual."""
        ref = self.reference(dt, vx, vy, wz, ex, ey)
        if not self.walking:
            self.action = np.zeros(self.spec.action_size)
            self._tick = 0
            return ref
        if self._tick % self.ticks == 0 and self.policy is not None:
            self.action = self.policy.act(self.observe(ref))
        self._tick += 1
        return self.targets(ref)
