"""Scenes as MJCF: a built world written out as an MJCF file with its meshes and textures.

:func:`export_scene` builds a scene's world as the simulator does (the building's visual
meshes, its collision geometry, lights, the point-body camera rig, the people of the
simulator's seed and optionally a GO1), poses the people at a chosen simulated time and the
agent at a viewpoint, and writes:

* ``<out>/<scene>.xml``: the model (``MjSpec.to_xml``), loadable with plain
  ``mujoco.MjModel.from_xml_path`` and MuJoCo's viewer (``python -m mujoco.viewer
  --mjcf=<file>``);
* ``<out>/meshes/*.obj``: every mesh (vertices exact to float32, texture coordinates kept);
* ``<out>/textures/*.png``: every texture the world holds in memory.

Mocap bodies (people, the camera rig) keep the pose they had at the chosen time as their
initial pose; a skinned person's mesh is written in that pose. Paths in the file are relative,
so the folder can be moved or shared as a whole.
"""

from __future__ import annotations

import shutil
import zlib
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from havln_mj.cache import atomic_write_bytes
from havln_mj.errors import (
    InvalidArgumentError,
    MissingDataError,
    UnknownViewpointError,
    did_you_mean,
)
from havln_mj.humans.drawing import PeopleDrawing
from havln_mj.robot.point_body import PointBody
from havln_mj.scene.scan import Scan, load_scan
from havln_mj.sim.crowd import NO_CROWD, Crowd
from havln_mj.sim.visual import safe_name
from havln_mj.sim.world import WorldOptions, world_spec

BODIES = ("point", "go1")
GO1_PREFIX = "go1/"  # the simulator's prefix of the GO1's elements


@dataclass(frozen=True)
class ExportedScene:
    """What :func:`export_scene` wrote.

    Attributes:
        xml: The MJCF file.
        meshes: Mesh files written (under ``meshes/``).
        textures: Texture files written (under ``textures/``).
        ngeom: Geoms of the exported model.
        people: People in the scene.
    """

    xml: Path
    meshes: int
    textures: int
    ngeom: int
    people: int


def scene_crowd(
    scan: Scan, seed: int, human_placements: str | Path | None = None, together: float = 0.0
) -> Crowd:
    """The people the simulator gives ``scan`` under ``seed`` (its per-scan generator rule)."""
    from havln_mj.sim.people import HumanCrowds  # the humans package, only when used

    rng = np.random.default_rng([seed, zlib.crc32(scan.scene_id.encode())])
    crowds = HumanCrowds(lambda _: scan, human_placements, together=together)
    return crowds(scan.scene_id, scan.graph, rng)


def _start(scan: Scan, viewpoint: str | None) -> tuple[str, np.ndarray, float]:
    """The viewpoint the agent stands at, its camera position and its floor height."""
    nodes = list(scan.graph.nodes)
    vp = nodes[0] if viewpoint is None else viewpoint
    if vp not in nodes:
        raise UnknownViewpointError(
            f"viewpoint {vp!r} is not in {scan.scene_id} ({len(nodes)} viewpoints, e.g. "
            f"{nodes[0]}).{did_you_mean(vp, nodes)}"
        )
    return vp, np.asarray(scan.graph.position(vp), float), float(scan.graph.floor_z(vp))


def build_spec(
    scan: Scan,
    people: PeopleDrawing,
    body: str,
    options: WorldOptions,
    viewpoint: str | None = None,
    solid_people: bool = False,
) -> mujoco.MjSpec:
    """The world spec the simulator compiles for ``body``, before posing.

    The point body's world is :func:`~havln_mj.sim.world.world_spec` plus the people; the
    GO1's adds the robot standing at the viewpoint's floor. ``solid_people`` makes people's
    geoms collide, as the legged world builds them when people push the robot.
    """
    if body not in BODIES:
        raise InvalidArgumentError(f"body {body!r} unknown; valid: {', '.join(BODIES)}")
    if body == "go1" and options.collision == "none":
        raise InvalidArgumentError("a GO1 needs floors to stand on: collision 'none' is invalid")
    spec, _, _ = world_spec(scan, options)
    people.add_to(spec, solid=solid_people)
    if body == "go1":
        from havln_mj.robot.go1.model import add_go1

        _, position, floor = _start(scan, viewpoint)
        add_go1(spec, (position[0], position[1], floor), prefix=GO1_PREFIX)
    return spec


def _bake_mesh(spec: mujoco.MjSpec, model: mujoco.MjModel, mesh: int) -> None:
    """Writes a compiled mesh's current vertices back into the spec, in its body's frame.

    A skinned person's mesh is posed in the compiled model (vertices in the mesh's own frame,
    placed by its geom); the spec's mesh takes them in the body frame and its geom sits at
    the body's origin, so compiling the spec again gives the same surface.
    """
    adr, num = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
    for g in np.flatnonzero(
        (model.geom_type == mujoco.mjtGeom.mjGEOM_MESH) & (model.geom_dataid == mesh)
    ):
        rot = np.empty(9)
        mujoco.mju_quat2Mat(rot, model.geom_quat[g])
        local = model.mesh_vert[adr : adr + num] @ rot.reshape(3, 3).T + model.geom_pos[g]
        target = spec.mesh(model.mesh(mesh).name)
        target.uservert = local.astype(np.float32).ravel()
        target.usernormal = []  # recomputed from the posed surface
        geom = spec.geom(model.geom(g).name)
        geom.pos, geom.quat = (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)


def pose_spec(
    spec: mujoco.MjSpec, people: PeopleDrawing, time: float, camera: PointBody
) -> mujoco.MjModel:
    """Poses the people at ``time`` and the camera rig, writing the poses into the spec.

    Every mocap body's initial pose becomes the pose it has at ``time``; skinned meshes take
    their posed vertices. Returns the model compiled before posing.
    """
    model = spec.compile()
    data = mujoco.MjData(model)
    for mesh in people.poser(model).pose(data, time):
        _bake_mesh(spec, model, mesh)
    camera.write(model, data)
    for b in range(model.nbody):
        mocap = int(model.body_mocapid[b])
        if mocap >= 0:
            moved = spec.body(model.body(b).name)
            moved.pos = data.mocap_pos[mocap].copy()
            moved.quat = data.mocap_quat[mocap].copy()
    return model


def _obj_text(
    vertices: np.ndarray,
    faces: np.ndarray,
    texcoords: np.ndarray | None,
    normals: np.ndarray | None,
) -> str:
    """An OBJ file: float32 numbers at 9 significant digits (exact), 1-based faces.

    Texture coordinates and normals, when given, are one per vertex (MuJoCo's user arrays).
    """
    lines = [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in vertices]
    if texcoords is not None:
        # MuJoCo flips v when it reads an OBJ file (OBJ puts v = 0 at the image's bottom).
        lines += [f"vt {u:.9g} {1.0 - v:.9g}" for u, v in texcoords]
    if normals is not None:
        lines += [f"vn {x:.9g} {y:.9g} {z:.9g}" for x, y, z in normals]
    pattern = {(False, False): "{0}", (True, False): "{0}/{0}", (False, True): "{0}//{0}"}.get(
        (texcoords is not None, normals is not None), "{0}/{0}/{0}"
    )
    lines += ["f " + " ".join(pattern.format(i) for i in face) for face in faces + 1]
    return "\n".join(lines) + "\n"


def _unique(name: str, used: set[str], suffix: str) -> str:
    stem, k = safe_name(name) or "asset", 1
    file = f"{stem}{suffix}"
    while file in used:
        k += 1
        file = f"{stem}_{k}{suffix}"
    used.add(file)
    return file


def _source_file(spec: mujoco.MjSpec, file: str, folder: str) -> Path:
    """Where an asset given by file name lies (absolute, or under the spec's folders)."""
    base = Path(spec.modelfiledir or ".")
    for candidate in (Path(file), base / folder / file, base / file):
        if candidate.is_file():
            return candidate
    raise MissingDataError(f"asset file {file!r} of the world not found (looked in {base})")


def write_meshes(spec: mujoco.MjSpec, out: Path) -> int:
    """Writes every mesh to ``out/meshes`` and points the spec's meshes at the files."""
    used: set[str] = set()
    for mesh in spec.meshes:
        file = _unique(mesh.name, used, ".obj")
        target = out / "meshes" / file
        if len(mesh.uservert):
            vertices = np.asarray(mesh.uservert, np.float32).reshape(-1, 3)
            faces = np.asarray(mesh.userface, np.int64).reshape(-1, 3)
            uv = np.asarray(mesh.usertexcoord, np.float32).reshape(-1, 2)
            normals = np.asarray(mesh.usernormal, np.float32).reshape(-1, 3)
            text = _obj_text(
                vertices,
                faces,
                uv if len(uv) else None,
                normals if len(normals) == len(vertices) else None,
            )
            atomic_write_bytes(target, text.encode())
            mesh.uservert, mesh.userface, mesh.usertexcoord, mesh.usernormal = [], [], [], []
        else:
            source = _source_file(spec, mesh.file, spec.meshdir)
            target = target.with_suffix(source.suffix)
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(source, target)
        mesh.file = f"meshes/{target.name}"
    return len(used)


def write_textures(spec: mujoco.MjSpec, out: Path) -> int:
    """Writes every texture to ``out/textures`` (in-memory ones as PNG, files as they are)."""
    import cv2

    used: set[str] = set()
    for texture in spec.textures:
        data = bytes(texture.data)
        if not data and not texture.file:
            continue  # a builtin texture (checker, gradient): MJCF describes it itself
        source = None if data else _source_file(spec, texture.file, spec.texturedir)
        file = _unique(texture.name, used, ".png" if source is None else source.suffix)
        target = out / "textures" / file
        if source is None:
            c = texture.nchannel
            image = np.frombuffer(data, np.uint8).reshape(texture.height, texture.width, c)
            order = {1: [0], 3: [2, 1, 0], 4: [2, 1, 0, 3]}[c]  # OpenCV writes BGR(A)
            ok, png = cv2.imencode(".png", np.ascontiguousarray(image[..., order]))
            if not ok:
                raise InvalidArgumentError(f"texture {texture.name!r} cannot be encoded as PNG")
            atomic_write_bytes(target, png.tobytes())
            texture.data = b""
        else:
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(source, target)
        texture.file = f"textures/{file}"
    return len(used)


def export_scene(
    scene: str,
    out: str | Path,
    *,
    time: float = 0.0,
    body: str = "point",
    seed: int = 0,
    humans: bool = True,
    together: float = 0.0,
    people_style: str = "pieces",
    viewpoint: str | None = None,
    collision: str = "auto",
    solid_people: bool = False,
    mp3d_dir: str | Path | None = None,
    connectivity_dir: str | Path | None = None,
    human_placements: str | Path | None = None,
) -> ExportedScene:
    """Writes a scene's world as MJCF with its assets (see the module docstring).

    Args:
        scene: Scene id (``proc-<seed>``, a Matterport scan id, a scan folder).
        out: Output folder (created).
        time: Simulated seconds at which people are posed.
        body: ``"point"`` (the camera rig) or ``"go1"`` (adds the robot).
        seed: The simulator's seed: which people the scene has and what they do.
        humans: Include people.
        together: The chance that a placed person is joined by others (the simulator's).
        people_style: How people are drawn (:data:`~havln_mj.humans.mujoco_people.DRAW_STYLES`).
        viewpoint: Where the agent stands (default: the graph's first viewpoint).
        collision: Collision geometry mode (see :class:`~havln_mj.sim.world.WorldOptions`).
        solid_people: People's geoms collide (the GO1's ``physical_humans`` setting).
        mp3d_dir: Root of the user's Matterport3D data.
        connectivity_dir: Folder of navigation graphs.
        human_placements: HA3D placement file.

    Returns:
        What was written.

    Raises:
        InvalidArgumentError: Unknown body or people style, a negative or non-finite time.
        UnknownViewpointError: A viewpoint not in the scan.
        UnknownSceneError: Unknown scene id.
    """
    if not np.isfinite(time) or time < 0:
        raise InvalidArgumentError(f"time must be a finite number of seconds ≥ 0, got {time!r}")
    if not 0.0 <= together <= 1.0:
        raise InvalidArgumentError(f"together must be a chance in [0, 1], got {together!r}")
    scan = load_scan(scene, mp3d_dir=mp3d_dir, connectivity_dir=connectivity_dir)
    crowd = scene_crowd(scan, seed, human_placements, together) if humans else NO_CROWD
    # Exported files are drawn by other tools at any size: their textures stay whole.
    options = WorldOptions(collision=collision, people_style=people_style, texel_reach_m=None)
    people = PeopleDrawing(crowd, options.people_style)
    spec = build_spec(scan, people, body, options, viewpoint, solid_people)
    _, position, _ = _start(scan, viewpoint)
    pose_spec(spec, people, time, PointBody(position))
    out = Path(out).expanduser().resolve()
    out.mkdir(parents=True, exist_ok=True)
    meshes, textures = write_meshes(spec, out), write_textures(spec, out)
    spec.meshdir = spec.texturedir = ""
    spec.modelfiledir = str(out)  # the relative asset paths resolve here
    xml = spec.to_xml()  # compiles from the written files: they are checked here
    path = out / f"{safe_name(scan.scene_id)}.xml"
    atomic_write_bytes(path, xml.encode())
    return ExportedScene(path, meshes, textures, len(spec.geoms), len(crowd))
