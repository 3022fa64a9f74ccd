"""The point body: a kinematic camera rig that moves instantly along graph edges.

In the MuJoCo world it is a mocap body ``agent`` at the camera position, oriented like the
camera, carrying the camera ``agent_cam``. Moving it costs simulated time: distance / speed
plus turned angle / turn rate (defaults below; the simulator's clock,
:class:`~havln_mj.sim.point.PointKind`, charges it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from havln_mj.errors import InvalidArgumentError
from havln_mj.frames import camera_quat, wrap_heading

BODY = "agent"
CAMERA = "agent_cam"
DEFAULT_SPEED = 1.0  # m/s, a slow indoor walk
DEFAULT_TURN_RATE = math.pi / 2  # rad/s


def add_point_body(spec: mujoco.MjSpec, vfov_deg: float = 60.0) -> None:
    """Adds the agent's mocap body and camera to a world spec."""
    body = spec.worldbody.add_body(name=BODY, mocap=True)
    cam = body.add_camera(name=CAMERA)
    cam.fovy = vfov_deg


@dataclass
class PointBody:
    """Pose of the kinematic agent.

    Attributes:
        position: Camera position (x, y, z), metres.
        heading: Radians in [0, 2π), 0 facing +y, turning right positive.
        elevation: Radians, up positive.
    """

    position: np.ndarray
    heading: float = 0.0
    elevation: float = 0.0

    def __post_init__(self) -> None:
        self.position = np.asarray(self.position, dtype=float).reshape(3)
        if not np.all(np.isfinite(self.position)):
            raise InvalidArgumentError(f"position must be finite, got {self.position.tolist()}")
        self.set_pose(self.position, self.heading, self.elevation)

    def set_pose(self, position: np.ndarray, heading: float, elevation: float = 0.0) -> None:
        """Teleports the agent (no time cost)."""
        p = np.asarray(position, dtype=float).reshape(3)
        if not (np.all(np.isfinite(p)) and math.isfinite(heading) and math.isfinite(elevation)):
            raise InvalidArgumentError(
                f"pose must be finite, got position={p.tolist()} heading={heading!r} "
                f"elevation={elevation!r}"
            )
        self.position = p
        self.heading = wrap_heading(heading)
        self.elevation = float(elevation)

    def write(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Writes the pose into the model's mocap body and updates kinematics."""
        mocap = model.body(BODY).mocapid[0]
        data.mocap_pos[mocap] = self.position
        data.mocap_quat[mocap] = camera_quat(self.heading, self.elevation)
        mujoco.mj_kinematics(model, data)
        mujoco.mj_camlight(model, data)
