"""Builds the GO1 into a world spec: ours (``robots/go1/go1.xml``) or a user's Menagerie file.

The robot is attached with ``MjSpec.attach`` under a name prefix (default ``go1/``) at a floor
point and yaw, so several robots, people and a building can share one model. Attaching sets
the world's physics options to the GO1's (timestep 0.002 s, elliptic cones, impratio 100):
MuJoCo keeps only the parent's options and the soft feet need these to hold without slipping.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from havln_mj import groups
from havln_mj.errors import InvalidArgumentError, MalformedDataError, MissingDataError
from havln_mj.paths import asset_path
from havln_mj.robot.go1 import constants as const

CAMERA_HEIGHT_RANGE = (0.35, 2.5)  # metres above the floor a raised camera may sit
_VISIBLE_RGBA = (0.12, 0.12, 0.13, 1.0)


@dataclass(frozen=True)
class Go1Handles:
    """Names (with prefix) of the attached robot's parts, valid once the spec is compiled.

    Attributes:
        prefix: The attach prefix, e.g. ``"go1/"``.
        trunk: Trunk body (carries the free joint).
        camera: The head camera (on the mast when a camera height was asked for).
        imu: The IMU site at the trunk origin.
        joints: The 12 leg joints, FR, FL, RR, RL × (hip, thigh, calf).
        actuators: The 12 position actuators, same order.
        feet: The 4 foot geoms.
        camera_height: Height of the camera above the floor when standing (metres).
        source: ``"havln_mj"`` or the path of the Menagerie file used.
        meshes: Whether the Menagerie visual meshes were kept.
    """

    prefix: str
    trunk: str
    camera: str
    imu: str
    joints: tuple[str, ...]
    actuators: tuple[str, ...]
    feet: tuple[str, ...]
    camera_height: float
    source: str
    meshes: bool


def yaw_quat(yaw: float) -> np.ndarray:
    """The (w, x, y, z) quaternion of a rotation by ``yaw`` about world z."""
    return np.array([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])


def _check_args(pos: Sequence[float], yaw: float, prefix: str, camera_height: float | None):
    p = np.asarray(pos, dtype=float)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise InvalidArgumentError(f"pos must be 3 finite numbers (x, y, z_floor), got {pos!r}")
    if not math.isfinite(yaw):
        raise InvalidArgumentError(f"yaw must be a finite number of radians, got {yaw!r}")
    if not isinstance(prefix, str) or not prefix or any(ch.isspace() for ch in prefix):
        raise InvalidArgumentError(
            f"prefix must be a non-empty string without spaces, e.g. 'go1/', got {prefix!r}"
        )
    if camera_height is not None:
        lo, hi = CAMERA_HEIGHT_RANGE
        if not (isinstance(camera_height, int | float) and lo <= camera_height <= hi):
            raise InvalidArgumentError(
                f"camera_height must be None or metres in [{lo}, {hi}], got {camera_height!r}"
            )
    return p


def _load_menagerie(path: str | Path) -> tuple[mujoco.MjSpec, bool]:
    """Loads a Menagerie ``go1.xml``; keeps its visual meshes only if all their files exist."""
    path = Path(path).expanduser()
    if not path.is_file():
        raise MissingDataError(
            f"Menagerie GO1 file not found: {path}; pass the path of unitree_go1/go1.xml from a "
            "mujoco_menagerie checkout, or menagerie_xml=None for the built-in model"
        )
    try:
        child = mujoco.MjSpec.from_file(str(path))
    except Exception as err:  # MuJoCo raises ValueError with the parser's message
        raise MalformedDataError(f"cannot parse {path} as a MuJoCo model: {err}") from err
    missing = [n for n in const.JOINTS if child.joint(n) is None] + [
        n for n in (const.TRUNK, const.IMU_SITE) if child.body(n) is None and child.site(n) is None
    ]
    if missing or len(child.actuators) != len(const.ACTUATORS):
        raise MalformedDataError(
            f"{path} is not a GO1 model: missing {missing or 'the 12 actuators'} (expected the "
            "Menagerie unitree_go1 names, e.g. FR_hip_joint)"
        )
    meshdir = path.parent / (child.meshdir or "")
    keep = all((meshdir / m.file).is_file() for m in child.meshes)
    mesh_geoms = [g for g in child.geoms if g.type == mujoco.mjtGeom.mjGEOM_MESH]
    if keep:
        child.meshdir = str(meshdir.resolve())
        for g in mesh_geoms:
            g.group = groups.ROBOT  # Menagerie draws them in group 2, our people's group
    else:
        # Without the mesh files, draw the collision primitives instead.
        for g in mesh_geoms:
            child.delete(g)
        for m in list(child.meshes):
            child.delete(m)
        for g in list(child.geoms):
            if g.group == groups.COLLISION:
                copy = g.parent.add_geom(
                    type=g.type, size=g.size, pos=g.pos, quat=g.quat, fromto=g.fromto
                )
                copy.contype = copy.conaffinity = 0
                copy.group = groups.ROBOT
                copy.rgba = _VISIBLE_RGBA
    for light in list(child.lights):
        child.delete(light)  # a robot's tracking light would relight the building
    existing = {s.name for s in child.sensors}
    for name, kind in ((const.GYRO, "GYRO"), (const.ACCELEROMETER, "ACCELEROMETER")):
        if name not in existing:
            child.add_sensor(
                name=name,
                type=getattr(mujoco.mjtSensor, f"mjSENS_{kind}"),
                objtype=mujoco.mjtObj.mjOBJ_SITE,
                objname=const.IMU_SITE,
            )
    return child, keep


def _add_camera(child: mujoco.MjSpec, camera_height: float | None) -> float:
    """Adds (or moves) the head camera; on a mast when ``camera_height`` is set."""
    trunk = child.body(const.TRUNK)
    cam = child.camera(const.HEAD_CAMERA)
    if cam is None:
        cam = trunk.add_camera(name=const.HEAD_CAMERA, fovy=const.HEAD_CAMERA_FOVY)
        cam.pos = const.HEAD_CAMERA_POS
        # Looks along the trunk's +x with z up: camera x (right) = -y, camera y (up) = +z.
        cam.alt.xyaxes = (0.0, -1.0, 0.0, 0.0, 0.0, 1.0)
    if camera_height is None:
        return const.STAND_HEIGHT + const.HEAD_CAMERA_POS[2]
    z = camera_height - const.STAND_HEIGHT
    # A thin massless mast: it shows in renders but neither collides nor changes the dynamics.
    trunk.add_geom(
        name=const.CAMERA_MAST,
        type=mujoco.mjtGeom.mjGEOM_CAPSULE,
        fromto=(const.MAST_X, 0.0, 0.05, const.MAST_X, 0.0, z - 0.02),
        size=(0.01, 0.0, 0.0),
        contype=0,
        conaffinity=0,
        group=groups.ROBOT,
        rgba=_VISIBLE_RGBA,
        mass=0.0,
    )
    cam.pos = (const.MAST_X + 0.02, 0.0, z)
    return float(camera_height)


def _name_geoms(child: mujoco.MjSpec) -> None:
    """Names every unnamed geom ``<body>/geom<k>`` (its index among its body's geoms)."""
    for body in child.bodies:
        for k, geom in enumerate(body.geoms):
            if not geom.name:
                geom.name = f"{body.name}/geom{k}"


def add_go1(
    spec: mujoco.MjSpec,
    pos: Sequence[float] = (0.0, 0.0, 0.0),
    yaw: float = 0.0,
    *,
    prefix: str = "go1/",
    camera_height: float | None = None,
    menagerie_xml: str | Path | None = None,
) -> Go1Handles:
    """Attaches a GO1 standing at a floor point into an uncompiled world spec.

    Args:
        spec: The world (e.g. from :func:`havln_mj.sim.world.world_spec`); gets the robot and
            the GO1's physics options (timestep 0.002, elliptic cone, impratio 100).
        pos: The floor point under the trunk (x, y, z_floor); the trunk spawns 0.29 m above.
        yaw: Trunk yaw (radians about +z, 0 = facing +x). From a heading: π/2 − heading.
        prefix: Name prefix of every robot element, so names do not clash.
        camera_height: None keeps the head camera on the face of the head (≈0.28 m above the
            floor); a height in metres (e.g. 1.5, MatterSim's eye height) raises it on a mast.
        menagerie_xml: Path of a user's Menagerie ``unitree_go1/go1.xml`` to use instead of the
            built-in model. Its visual meshes are kept when their files exist, else replaced
            by the collision primitives.

    Returns:
        The prefixed names of the robot's parts.

    Raises:
        InvalidArgumentError: Bad pose, prefix or camera height.
        MissingDataError: ``menagerie_xml`` does not exist.
        MalformedDataError: ``menagerie_xml`` is not a GO1 model.
    """
    p = _check_args(pos, yaw, prefix, camera_height)
    if any(b.name.startswith(prefix) for b in spec.bodies):
        raise InvalidArgumentError(f"prefix {prefix!r} is already used in this spec")
    if menagerie_xml is None:
        child = mujoco.MjSpec.from_file(str(asset_path("robots", "go1", "go1.xml")))
        source, meshes = "havln_mj", False
    else:
        child, meshes = _load_menagerie(menagerie_xml)
        source = str(menagerie_xml)
    for key in list(child.keys):
        child.delete(key)  # keyframes would not match the world's qpos size
    child.body(const.TRUNK).pos = (0.0, 0.0, const.HOME_TRUNK_Z)
    height = _add_camera(child, camera_height)
    _name_geoms(child)

    spec.option.timestep = const.TIMESTEP
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.impratio = 100.0
    frame = spec.worldbody.add_frame(pos=p, quat=yaw_quat(yaw))
    spec.attach(child, prefix=prefix, frame=frame)
    return Go1Handles(
        prefix=prefix,
        trunk=prefix + const.TRUNK,
        camera=prefix + const.HEAD_CAMERA,
        imu=prefix + const.IMU_SITE,
        joints=tuple(prefix + n for n in const.JOINTS),
        actuators=tuple(prefix + n for n in const.ACTUATORS),
        feet=tuple(prefix + n for n in const.FOOT_GEOMS),
        camera_height=height,
        source=source,
        meshes=meshes,
    )


def flat_floor_spec(size: float = 50.0, friction: float = 1.0) -> mujoco.MjSpec:
    """An empty world: a plane floor at z = 0 and a light (for tests and benchmarks).

    Args:
        size: Half-size of the floor plane (metres).
        friction: Floor sliding friction (foot contacts use the feet's 0.8 regardless).
    """
    spec = mujoco.MjSpec()
    spec.modelname = "flat"
    spec.worldbody.add_geom(
        name="floor",
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=(size, size, 0.1),
        friction=(friction, 0.005, 0.0001),
        group=groups.COLLISION,
        rgba=(0.6, 0.6, 0.6, 1.0),
    )
    spec.worldbody.add_light(name="sun", pos=(0, 0, 5), dir=(0.2, 0.1, -1.0))
    return spec
