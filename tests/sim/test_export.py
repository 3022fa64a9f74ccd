"""Scenes as MJCF: the exported file loads in a fresh process with plain MuJoCo and holds the
world the simulator builds (same geoms, people posed at the chosen time, assets on disk)."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import mujoco
import numpy as np
import pytest

from havln_mj.cli import main as cli_main
from havln_mj.errors import InvalidArgumentError, UnknownViewpointError
from havln_mj.frames import camera_quat
from havln_mj.humans.mujoco_people import PARK_Z, body_name
from havln_mj.scene.mesh import MeshPart
from havln_mj.scene.scan import load_scan
from havln_mj.sim.export import export_scene, scene_crowd, write_meshes, write_textures
from havln_mj.sim.frame import ViewSettings
from havln_mj.sim.legged import LeggedOptions, LeggedWorld
from havln_mj.sim.point import Stage
from havln_mj.sim.visual import add_visual_parts
from havln_mj.sim.world import WorldOptions, build_world

SCENE = "proc-3"
VFOV = math.radians(60.0)  # the world camera's own: renders here leave its field of view as built

# Run in a fresh interpreter: nothing of havln_mj is imported, only MuJoCo reads the file.
_LOAD = """
import json, sys
import mujoco
m = mujoco.MjModel.from_xml_path(sys.argv[1])
print(json.dumps({
    "names": [m.geom(i).name for i in range(m.ngeom)],
    "type": m.geom_type.tolist(),
    "size": m.geom_size.tolist(),
    "group": m.geom_group.tolist(),
    "contype": m.geom_contype.tolist(),
    "nmesh": m.nmesh,
    "mocap_pos": {m.body(b).name: m.body_pos[b].tolist()
                  for b in range(m.nbody) if m.body_mocapid[b] >= 0},
}))
"""


def _load_elsewhere(xml, cwd):
    run = subprocess.run(
        [sys.executable, "-c", _LOAD, str(xml)], capture_output=True, text=True, cwd=cwd
    )
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout)


def _same_geoms(loaded: dict, model: mujoco.MjModel) -> None:
    assert len(loaded["names"]) == model.ngeom
    assert loaded["names"] == [model.geom(i).name for i in range(model.ngeom)]
    assert loaded["type"] == model.geom_type.tolist()
    assert loaded["group"] == model.geom_group.tolist()
    assert loaded["contype"] == model.geom_contype.tolist()
    # MuJoCo writes numbers to MJCF with 7 significant digits: sizes agree to that.
    np.testing.assert_allclose(np.array(loaded["size"]), model.geom_size, rtol=1e-6, atol=1e-6)


def test_exported_point_scene_loads_elsewhere_with_the_simulators_geoms(tmp_path):
    out = tmp_path / "export"
    done = export_scene(SCENE, out, time=4.0, seed=0)
    assert done.xml == out / f"{SCENE}.xml" and done.people > 0
    assert len(list((out / "meshes").glob("*.obj"))) == done.meshes > 0
    loaded = _load_elsewhere(done.xml, tmp_path)  # another folder: paths are relative
    scan = load_scan(SCENE)
    crowd = scene_crowd(scan, 0)
    # Exports keep every texture whole; the simulator's world with whole textures is the same.
    built = build_world(scan, WorldOptions(texel_reach_m=None), crowd.shapes, crowd.skins).model
    _same_geoms(loaded, built)
    assert loaded["nmesh"] == built.nmesh
    # Meshes travel through OBJ files exactly: vertices, normals, texture coordinates, faces.
    model = mujoco.MjModel.from_xml_path(str(done.xml))
    for name in ("mesh_vert", "mesh_normal", "mesh_texcoord", "mesh_face", "mesh_facetexcoord"):
        np.testing.assert_array_equal(getattr(model, name), getattr(built, name), err_msg=name)
    np.testing.assert_array_equal(model.tex_data, built.tex_data)
    # People stand where the crowd puts them at t = 4 s, not parked below the building.
    positions, _ = crowd.pose(4.0)
    for k in range(len(crowd)):
        pelvis = loaded["mocap_pos"][body_name(k, 0)]
        np.testing.assert_allclose(pelvis, positions[k, 0], atol=1e-5)
        assert pelvis[2] > PARK_Z + 50
    # The camera rig stands at the first viewpoint.
    np.testing.assert_allclose(
        loaded["mocap_pos"]["agent"], scan.graph.position(scan.graph.nodes[0]), atol=1e-5
    )


@pytest.mark.parametrize("solid", [False, True])
def test_exported_go1_scene_has_the_legged_worlds_geoms(tmp_path, solid):
    done = export_scene(SCENE, tmp_path, time=1.0, body="go1", solid_people=solid)
    loaded = _load_elsewhere(done.xml, tmp_path.parent)
    scan = load_scan(SCENE)
    crowd = scene_crowd(scan, 0)
    legged = LeggedWorld(scan, WorldOptions(), crowd, LeggedOptions(physical_humans=solid))
    _same_geoms(loaded, legged.model)
    model = mujoco.MjModel.from_xml_path(str(done.xml))
    data = mujoco.MjData(model)
    mujoco.mj_step(model, data, 50)  # the robot's physics runs from the file
    assert np.isfinite(data.qpos).all() and data.qpos[2] > 0.0


def _view_of_a_person(stage, scan, crowd, t):
    """The viewpoint and heading whose view shows most of a person at ``t``, and how much."""
    settings = ViewSettings(32, 24, VFOV, human_mask=True)
    pelvis = crowd.pose(t)[0][:, 0]
    best = (0.0, None)
    for vp in scan.graph.nodes:
        pos = scan.graph.position(vp)
        for x, y, _ in pelvis:
            heading = math.atan2(x - pos[0], y - pos[1]) % (2 * math.pi)
            shown = stage.render((pos, heading, 0.0), settings, t).human_mask.mean()
            best = max(best, (shown, (vp, heading)), key=lambda b: b[0])
    assert best[0] > 0.02, "no view of a person"
    return (*best[1], best[0])


def _render(model, data):
    with mujoco.Renderer(model, 96, 128) as renderer:  # made after posing: skinned meshes too
        renderer.update_scene(data, camera="agent_cam")
        return renderer.render()


@pytest.mark.parametrize("style", ["pieces", "skinned"])
def test_exported_scene_looks_as_the_simulator_draws_it(tmp_path, style):
    """Posed people (rigid pieces, or a skinned mesh baked in its pose) and the building."""
    t = 3.0
    scan = load_scan(SCENE)
    crowd = scene_crowd(scan, 0)
    stage = Stage(scan, WorldOptions(people_style=style), crowd)
    vp, heading, person = _view_of_a_person(stage, scan, crowd, t)
    stage.render((scan.graph.position(vp), heading, 0.0), ViewSettings(32, 24, VFOV), t)
    ours = _render(stage.world.model, stage.data)  # the simulator's world, posed by it
    stage.close()
    done = export_scene(SCENE, tmp_path, time=t, viewpoint=vp, people_style=style)
    model = mujoco.MjModel.from_xml_path(str(done.xml))
    data = mujoco.MjData(model)
    data.mocap_quat[model.body("agent").mocapid[0]] = camera_quat(heading, 0.0)
    mujoco.mj_forward(model, data)
    theirs = _render(model, data)
    # Only stray edge pixels may differ (MJCF keeps 7 significant digits of each number): far
    # fewer than a person misplaced or missing would change.
    differ = np.abs(ours.astype(int) - theirs.astype(int)).max(axis=-1) > 10
    assert differ.mean() < min(0.01, person / 4)


def test_textured_meshes_and_textures_round_trip_through_files(tmp_path):
    image = np.zeros((8, 16, 3), np.uint8)
    image[:, :8] = (255, 0, 0)
    image[:4, 8:] = (0, 255, 0)
    square = MeshPart(
        name="wall",
        vertices=np.array([[0, 0, 0], [1.25, 0, 0], [1.25, 0, 1.5], [0, 0, 1.5]], np.float32),
        faces=np.array([[0, 1, 2], [0, 2, 3]]),
        uv=np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32),
        texture=image,
        rgba=(1.0, 1.0, 1.0, 1.0),
    )
    spec = mujoco.MjSpec()
    add_visual_parts(spec, [square])
    before = spec.compile()
    assert write_meshes(spec, tmp_path) == 1 and write_textures(spec, tmp_path) == 1
    spec.modelfiledir = str(tmp_path)
    (tmp_path / "m.xml").write_text(spec.to_xml())
    after = mujoco.MjModel.from_xml_path(str(tmp_path / "m.xml"))
    np.testing.assert_array_equal(after.tex_data, before.tex_data)
    np.testing.assert_array_equal(after.mesh_vert, before.mesh_vert)
    np.testing.assert_allclose(after.mesh_texcoord, before.mesh_texcoord, atol=1e-6)


def test_bad_export_arguments_name_what_is_valid(tmp_path):
    with pytest.raises(UnknownViewpointError, match="viewpoints"):
        export_scene(SCENE, tmp_path, viewpoint="nowhere")
    with pytest.raises(InvalidArgumentError, match="body 'wheels' unknown; valid: point, go1"):
        export_scene(SCENE, tmp_path, body="wheels")
    with pytest.raises(InvalidArgumentError, match="time"):
        export_scene(SCENE, tmp_path, time=float("nan"))


def test_scenes_export_command(tmp_path, capsys):
    out = tmp_path / "cli"
    assert cli_main(["scenes", "export", SCENE, "--out", str(out), "--time", "2",
                     "--no-people"]) == 0  # fmt: skip
    assert f"wrote {out / SCENE}.xml" in capsys.readouterr().out
    model = mujoco.MjModel.from_xml_path(str(out / f"{SCENE}.xml"))
    assert not any(model.body(b).name.startswith("human") for b in range(model.nbody))
    with pytest.raises(SystemExit) as bad:
        cli_main(["scenes", "export", SCENE, "--out", str(out), "--time", "-1"])
    assert bad.value.code == 2
    assert "--time must be at least 0 s, got -1" in capsys.readouterr().err
