"""Every name and number of the GO1 model in one place (names without the attach prefix).

Legs are ordered FR, FL, RR, RL (front/rear, right/left), each with three joints (abduction
"hip", "thigh", knee "calf"), the order of the Menagerie model's joints and actuators. Body
frame: x forward, y left, z up.
"""

from __future__ import annotations

import math

LEGS = ("FR", "FL", "RR", "RL")
LEG_PARTS = ("hip", "thigh", "calf")

CONTROLLERS = ("trot", "terrain", "learned", "crawl", "hybrid")
"""The gaits a :class:`~havln_mj.robot.go1.primitives.Go1Body` can walk with."""

TRUNK = "trunk"
FREE_JOINT = "root"
JOINTS = tuple(f"{leg}_{part}_joint" for leg in LEGS for part in LEG_PARTS)
ACTUATORS = tuple(f"{leg}_{part}" for leg in LEGS for part in LEG_PARTS)
HIP_BODIES = tuple(f"{leg}_hip" for leg in LEGS)
CALF_BODIES = tuple(f"{leg}_calf" for leg in LEGS)
FOOT_GEOMS = LEGS  # the foot spheres share the leg names, as in the Menagerie model
FOOT_SITES = LEGS
IMU_SITE = "imu"
HEAD_SITE = "head"
HEAD_CAMERA = "head_cam"
CAMERA_MAST = "camera_mast"
GYRO = "gyro"
ACCELEROMETER = "accelerometer"

# Kinematics (metres): hip joints relative to the trunk origin, abduction offset to the thigh
# joint (+ left), thigh and calf lengths, foot sphere radius.
HIP_X = 0.1881
HIP_Y = 0.04675
HIP_OFFSETS = ((HIP_X, -HIP_Y), (HIP_X, HIP_Y), (-HIP_X, -HIP_Y), (-HIP_X, HIP_Y))
LEG_SIDE = (-1.0, 1.0, -1.0, 1.0)  # +1 for left legs
ABDUCTION = 0.08
THIGH = 0.213
CALF = 0.213
FOOT_RADIUS = 0.023

# Joint ranges (radians) per leg part, from the model.
JOINT_RANGES = {"hip": (-0.863, 0.863), "thigh": (-0.686, 4.501), "calf": (-2.818, -0.888)}

# Home pose: every leg (abduction, thigh, knee); trunk spawn height with feet on the floor.
HOME_LEG = (0.0, 0.9, -1.8)
HOME_TRUNK_Z = 0.29
STAND_HEIGHT = 0.27  # nominal trunk height above the floor while standing and walking

# Head camera mount (trunk frame): front of the head, looking along +x.
HEAD_CAMERA_POS = (0.262, 0.0, 0.01)
HEAD_CAMERA_FOVY = 60.0
MAST_X = 0.2  # where a raised camera's mast stands on the trunk (trunk frame x)

# Timing and falls.
TIMESTEP = 0.002  # physics step (s), 500 Hz
FALL_UP_Z = 0.5  # fallen when the trunk's up axis has world z below this
FALL_HEIGHT = 0.12  # fallen when the trunk is lower than this above its lowest foot's floor

TOTAL_MASS = 12.743  # kg
MAX_YAW_RATE = 2.0  # rad/s; above this the trot is no longer stable
HALF_PI = 0.5 * math.pi
