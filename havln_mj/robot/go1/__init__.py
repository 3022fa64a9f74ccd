"""The Unitree GO1 quadruped: model builder, gaits and navigation primitives.

Two gaits: a blind trot, and a terrain-aware one that reads a height scan of the collision
geometry.

Typical use::

    spec = flat_floor_spec()  # or world_spec(scan, WorldOptions(collision="boxes"))[0]
    add_go1(spec, (x, y, z_floor), yaw=math.pi / 2 - heading)
    model = spec.compile()
    data = mujoco.MjData(model)
    robot = Go1Body(model, data)  # controller="terrain" for stairs, ramps and steps
    robot.reset(x, y, z_floor, heading)
    result = robot.forward(0.5, on_tick=move_people)
"""

from havln_mj.robot.go1.gains import Go1Gains, TerrainGains, load_gains
from havln_mj.robot.go1.model import Go1Handles, add_go1, flat_floor_spec
from havln_mj.robot.go1.primitives import Go1Body, Go1Pose, PrimitiveResult

__all__ = [
    "Go1Body",
    "Go1Gains",
    "Go1Handles",
    "Go1Pose",
    "PrimitiveResult",
    "TerrainGains",
    "add_go1",
    "flat_floor_spec",
    "load_gains",
]
