"""Semantic and instance segmentation: labels agree with the geometry, people are people."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from havln_mj import groups
from havln_mj.frames import heading_to
from havln_mj.humans.mujoco_people import PeopleWriter
from havln_mj.humans.population import populate
from havln_mj.render.camera import Camera
from havln_mj.render.labels import (
    LABELS,
    PERSON_INSTANCE_BASE,
    colorize,
    geom_labels,
    render_labels,
    segmentation_groups,
)
from havln_mj.robot.point_body import CAMERA, PointBody
from havln_mj.scene.matterport.categories import PERSON, mpcat40_index
from havln_mj.scene.scan import load_scan
from havln_mj.sim.world import build_world

W, H, VFOV = 64, 48, 60.0


@pytest.fixture(scope="module")
def peopled():
    """proc-3 with its people, posed at t = 0, and a camera looking at each person."""
    scan = load_scan("proc-3")
    crowd = populate(scan, np.random.default_rng(0), count=4)
    world = build_world(scan, people=crowd.shapes)
    model = world.model
    data = mujoco.MjData(model)
    writer = PeopleWriter(model, len(crowd))
    return scan, crowd, model, data, writer


def _look_at_people(scan, crowd, model, data, writer, t):
    """Yields the eye after posing the camera 1.5-4 m from each person, looking at them
    (from viewpoints nobody stands on)."""
    writer.write(data, *crowd.pose(t))
    graph = scan.graph
    states = crowd.states(t)
    people = np.array([s.position[:2] for s in states])
    for state in states:
        target = state.position + np.array([0.0, 0.0, 0.9])
        near = [
            v
            for v in graph.nodes
            if 1.5 < np.linalg.norm(graph.position(v)[:2] - target[:2]) < 4
            and np.linalg.norm(people - graph.position(v)[:2], axis=1).min() > 0.8
        ]
        for vp in near[:2]:
            p = graph.position(vp)
            el = math.atan2(target[2] - p[2], np.linalg.norm(target[:2] - p[:2]))
            PointBody(p, heading=heading_to(p, target), elevation=el).write(model, data)
            yield p


def _pixel_ray(model, data, row, col):
    """Unit direction through a pixel centre of the agent camera (MuJoCo camera frame)."""
    t = math.tan(math.radians(VFOV) / 2)
    x = (2 * (col + 0.5) / W - 1) * t * W / H
    y = (1 - 2 * (row + 0.5) / H) * t
    mat = data.cam_xmat[model.camera(CAMERA).id].reshape(3, 3)
    d = mat @ np.array([x, y, -1.0])
    return d / np.linalg.norm(d)


def test_labels_agree_with_the_geometry(peopled):
    # A ray from the camera through a pixel hits a geom of the pixel's class and instance.
    scan, crowd, model, data, writer = peopled
    semantic, instance = geom_labels(model)
    mask = np.zeros(mujoco.mjNGROUP, np.uint8)
    mask[list(segmentation_groups(model))] = 1
    geom = np.zeros(1, np.int32)
    checked, classes = 0, set()
    with Camera(model, CAMERA, W, H, VFOV, geom_groups=groups.CAMERA_GROUPS) as cam:
        for eye in _look_at_people(scan, crowd, model, data, writer, 0.0):
            seg = render_labels(model, data, cam)
            for row in range(2, H - 2, 5):
                for col in range(2, W - 2, 5):
                    patch = seg.instance[row - 1 : row + 2, col - 1 : col + 2]
                    if np.any(patch != patch[1, 1]):
                        continue  # an edge: the ray may fall either side
                    dist = mujoco.mj_ray(
                        model, data, eye, _pixel_ray(model, data, row, col), mask, 1, -1, geom
                    )
                    assert dist > 0, (row, col)
                    assert semantic[geom[0]] == seg.semantic[row, col], (
                        row,
                        col,
                        model.geom(geom[0]).name,
                    )
                    assert instance[geom[0]] == seg.instance[row, col]
                    classes.add(int(seg.semantic[row, col]))
                    checked += 1
    assert checked > 300
    assert {mpcat40_index("wall"), PERSON} <= classes and len(classes) >= 5


def _person_of_geom(model) -> np.ndarray:
    """Per geom, the index k of the person whose body ``human<k>/...`` carries it, else -1."""
    out = np.full(model.ngeom, -1)
    for g in np.flatnonzero(model.geom_group == groups.HUMANS):
        out[g] = int(model.body(model.geom_bodyid[g]).name.split("/")[0].removeprefix("human"))
    return out


def test_people_carry_the_person_class_and_stable_instances(peopled):
    scan, crowd, model, data, writer = peopled
    semantic, instance = geom_labels(model)
    person = _person_of_geom(model)
    human = person >= 0
    assert human.sum() > 0 and np.all(semantic[human] == PERSON)
    building = model.geom_group == LABELS
    assert np.all(semantic[building] != PERSON) and np.all(
        instance[building] < PERSON_INSTANCE_BASE
    )
    # Frames at two times: every pixel that shows a person's geom reads person k's id at both.
    seen: dict[int, set] = {}
    with Camera(model, CAMERA, W, H, VFOV, geom_groups=groups.CAMERA_GROUPS) as cam:
        for t in (0.0, 3.0):
            for _ in _look_at_people(scan, crowd, model, data, writer, t):
                ids = cam.render_geom_ids(data, geom_groups=segmentation_groups(model))
                seg = render_labels(model, data, cam)
                who = np.where(ids >= 0, person[np.maximum(ids, 0)], -1)
                assert np.all((seg.semantic == PERSON) == (who >= 0))
                for k in np.unique(who[who >= 0]):
                    seen.setdefault(int(k), set()).update(
                        np.unique(seg.instance[who == k]).tolist()
                    )
    assert seen, "no person was in view"
    for k, ids in seen.items():
        assert ids == {PERSON_INSTANCE_BASE + k}, (k, ids)


def test_a_scan_without_people_shows_no_person_and_building_classes(peopled):
    scan = load_scan("proc-3")
    model = build_world(scan).model
    data = mujoco.MjData(model)
    graph = scan.graph
    with Camera(model, CAMERA, W, H, VFOV) as cam:
        PointBody(graph.position(graph.nodes[0]), heading=0.5).write(model, data)
        seg = render_labels(model, data, cam)
    assert not np.any(seg.semantic == PERSON)
    assert np.all(seg.instance > 0)  # a closed house: every pixel shows a labelled object
    assert colorize(seg.semantic).shape == (H, W, 3)
