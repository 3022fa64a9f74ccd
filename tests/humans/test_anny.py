import os

import mujoco
import numpy as np
import pytest

from havln_mj import groups
from havln_mj.humans import rotations as rot
from havln_mj.humans.anny_data import load_anny_catalog
from havln_mj.humans.anny_mujoco import AnnyLook, add_anny_pieces, add_anny_skinned
from havln_mj.humans.anny_rig import fit, rigid_pieces
from havln_mj.humans.body import BodyShape
from havln_mj.humans.catalog import load_catalog, make_clip
from havln_mj.humans.crowd import Crowd, Person
from havln_mj.humans.drawing import PeopleDrawing
from havln_mj.humans.outfits import BOTTOM, SKIN, TOP, paint, part_labels, random_outfit
from havln_mj.humans.skeleton import JOINT, PARENTS
from havln_mj.paths import asset_path
from havln_mj.render.texels import resolved_density

CATALOG = load_anny_catalog()


def test_catalog_spans_ages_sexes_and_builds():
    assert len(CATALOG) >= 24
    heights = np.array([b.height for b in CATALOG.bodies])
    assert (heights < 1.3).sum() >= 2 and (heights > 1.85).sum() >= 2
    assert sum(b.age < 0.5 for b in CATALOG.bodies) >= 4  # children
    assert sum(b.age > 0.86 for b in CATALOG.bodies) >= 4  # elders
    assert sum(b.female > 0.5 for b in CATALOG.bodies) >= 10
    assert sum(b.female < 0.5 for b in CATALOG.bodies) >= 10
    folder = asset_path("humans", "anny")
    assert sum(f.stat().st_size for f in folder.iterdir()) < 30e6
    assert (folder / "LICENSE.md").is_file()


@pytest.mark.parametrize("body", CATALOG.bodies, ids=CATALOG.ids)
def test_every_body_skins_to_reference_poses(body):
    rig = fit(body)
    v = body.vertices
    assert abs(np.ptp(v[:, 2]) - body.height) < 0.01 and abs(v[:, 2].min()) < 1e-3
    # Rest: joints at their Anny rest positions, turned back by the rest corrections.
    undo = rot.conj(rig.correction)
    np.testing.assert_allclose(rig.skin(rig.anchors, undo), v, atol=1e-3)
    # The whole body turned by 70° about z and moved: a rigid motion of every vertex.
    yaw = rot.from_axis((0.0, 0.0, 1.0), 1.2)
    shift = np.array([0.4, -2.0, 0.1])
    turned = rig.skin(rot.rotate(yaw, rig.anchors) + shift, rot.mul(yaw, undo))
    m = rot.to_matrix(yaw)
    np.testing.assert_allclose(turned, v @ m.T + shift, atol=1e-3)
    # The left forearm bent 90° at the elbow: its vertices turn about the elbow, the
    # vertices it does not weigh on stay.
    sub = [JOINT[n] for n in ("left_elbow", "left_wrist", "left_hand")]
    bend = rot.from_axis((1.0, 0.0, 0.0), np.pi / 2)
    quats, pos = undo.copy(), rig.anchors.copy()
    elbow = rig.anchors[JOINT["left_elbow"]]
    for j in sub:
        quats[j] = rot.mul(bend, undo[j])
        pos[j] = elbow + rot.rotate(bend, rig.anchors[j] - elbow)
    bent = rig.skin(pos, quats)
    w = body.topology.dense_weights()[:, sub].sum(axis=1)
    moved, still = w > 1 - 1e-6, w < 1e-6
    assert moved.sum() > 50 and still.sum() > 1000
    expect = elbow + (v[moved] - elbow) @ rot.to_matrix(bend).T
    np.testing.assert_allclose(bent[moved], expect, atol=1e-3)
    np.testing.assert_allclose(bent[still], v[still], atol=1e-3)


def test_offsets_keep_anny_bone_lengths_in_our_tpose():
    rig = fit(CATALOG.get("woman-average"))
    a = rig.anchors
    for j in range(1, 24):
        assert np.linalg.norm(rig.offsets[j]) == pytest.approx(np.linalg.norm(a[j] - a[PARENTS[j]]))
    # Arms point sideways in our T-pose: the left arm along −x.
    arm = rig.offsets[JOINT["left_elbow"]]
    assert arm[0] < -0.2 and abs(arm[2]) < 0.02


def test_rigid_pieces_cover_every_face():
    topo = CATALOG.topology
    pieces = rigid_pieces(topo.dense_weights(), topo.faces)
    covered = np.zeros(len(topo.faces), bool)
    for p in pieces:
        covered[p.faces] = True
    assert covered.all()


def test_outfits_dress_every_body():
    rng = np.random.default_rng(0)
    for body in CATALOG.bodies:
        outfit = random_outfit(rng, body)
        labels = part_labels(body.vertices, body.topology.joint_index[:, 0], body, outfit)
        chest = (np.abs(body.vertices[:, 0]) < 0.08) & (
            np.abs(body.vertices[:, 2] - body.joints[JOINT["spine2"], 2]) < 0.05
        )
        assert (labels[chest] == TOP).mean() > 0.9, body.id
        thigh = body.topology.joint_index[:, 0] == JOINT["left_hip"]
        thigh &= body.vertices[:, 2] > body.joints[JOINT["left_hip"], 2] - 0.08
        assert (labels[thigh] == BOTTOM).mean() > 0.9, body.id  # under a skirt: briefs
        assert (labels == SKIN).any()
    image = paint(CATALOG.get("man-average"), outfit)
    assert image.shape == (512, 512, 3) and image.dtype == np.uint8
    assert len(np.unique(image.reshape(-1, 3), axis=0)) > 5


def _one_person_world(style: str):
    catalog_talk = load_catalog().get("living-room/guest-chat")
    rig = fit(CATALOG.get("man-average"))
    rng = np.random.default_rng(1)
    shape = BodyShape(rig.clip_height, look=AnnyLook(rig, random_outfit(rng, rig.body)))
    clip = make_clip(catalog_talk, shape.height, rng)
    crowd = Crowd([Person(shape, clip, np.array([0.0, 3.0, 0.0]), np.pi, "talk")])
    spec = mujoco.MjSpec()
    spec.worldbody.add_light(dir=(0, 0.3, -1), diffuse=(0.6, 0.6, 0.6))
    spec.worldbody.add_camera(name="eye", pos=(0, 0, 1.0), xyaxes=(1, 0, 0, 0, 0, 1))
    drawing = PeopleDrawing.from_crowd(crowd, style)
    drawing.add_to(spec)
    model = spec.compile()
    return model, drawing.poser(model)


@pytest.mark.skipif(
    os.environ.get("MUJOCO_GL", "egl") not in ("egl", "osmesa"), reason="needs offscreen GL"
)
@pytest.mark.parametrize("style", ["pieces", "skinned", "capsules"])
def test_people_appear_in_rgb_depth_and_mask(style):
    from havln_mj.render.camera import Camera

    model, poser = _one_person_world(style)
    data = mujoco.MjData(model)
    with Camera(model, "eye", 64, 64, 60.0) as cam:
        for mesh in poser.pose(data, 1.0):
            cam.upload_mesh(mesh)
        mujoco.mj_forward(model, data)
        frame = cam.render(data)
        ids = cam.render_geom_ids(data)
    mask = (ids >= 0) & (model.geom_group[np.maximum(ids, 0)] == groups.HUMANS)
    assert mask.mean() > 0.02
    depth = frame.depth[mask]
    assert 2.6 < np.median(depth) < 3.3
    assert (frame.depth[~mask] == 0).all()  # nothing else in this world in view
    assert frame.rgb[mask].mean() > 20 and frame.rgb[~mask].max() == 0


def test_rigid_pieces_keep_no_mesh_on_the_look_and_fit_their_texture():
    # Pieces are made for the build and let go: a skinned body keeps its mesh to re-skin it.
    rig = fit(CATALOG.get("man-average"))
    look = AnnyLook(rig, random_outfit(np.random.default_rng(1), rig.body))

    def bodies(spec):
        return [spec.worldbody.add_body(mocap=True) for _ in range(len(JOINT))]

    spec = mujoco.MjSpec()
    add_anny_pieces(spec, "p", bodies(spec), look)
    assert "mesh" not in look.__dict__
    assert spec.compile().tex_width[0] == 512  # no limit: the painted size
    spec = mujoco.MjSpec()
    add_anny_pieces(spec, "p", bodies(spec), look, texel_limit=resolved_density(480, 60.0))
    assert spec.compile().tex_width[0] < 512
    spec = mujoco.MjSpec()
    add_anny_skinned(spec, "p", spec.worldbody.add_body(mocap=True), look, -100.0)
    assert "mesh" in look.__dict__


def test_the_catalog_keeps_its_texel_maps_as_stored():
    topology = CATALOG.topology
    assert topology.texel_face.dtype == np.int16 and topology.texel_bary.dtype == np.float16
