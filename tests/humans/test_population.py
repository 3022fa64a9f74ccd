"""Placing people: HA3D's rule in procedural houses and HA3D's own placements for real scans."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from havln_mj.errors import MalformedDataError, MissingDataError
from havln_mj.humans.catalog import load_catalog
from havln_mj.humans.loaders import haps_dir_name, load_haps_folder
from havln_mj.humans.population import (
    MIN_SEPARATION,
    Sources,
    ha3d_heading,
    people_count,
    populate,
    populate_ha3d,
    read_ha3d_placements,
)
from havln_mj.humans.skeleton import JOINT
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.scan import load_scan

TORSO = [JOINT[n] for n in ("pelvis", "spine1", "spine2", "spine3", "neck", "head")]


@pytest.fixture(scope="module", params=[0, 1, 2])
def scan(request):
    return load_scan(f"proc-{request.param}")


def test_head_count_spacing_and_rooms(scan):
    crowd = populate(scan, np.random.default_rng(0))
    assert 1 <= len(crowd) <= people_count(scan.regions)
    vps = [p.viewpoint for p in crowd.people]
    for i, a in enumerate(vps):
        for b in vps[i + 1 :]:
            d = np.linalg.norm(scan.graph.position(a) - scan.graph.position(b))
            assert d >= MIN_SEPARATION
    catalog = load_catalog()
    for p in crowd.people:
        assert p.region == scan.regions.region_of(p.viewpoint).label
        assert p.activity in {a.id for a in catalog.activities(p.region)}


def test_same_seed_same_crowd(scan):
    a = populate(scan, np.random.default_rng(5))
    b = populate(scan, np.random.default_rng(5))
    c = populate(scan, np.random.default_rng(6))
    times = np.linspace(0, 10, 7)
    np.testing.assert_array_equal(a.positions(times), b.positions(times))
    assert [p.activity for p in a.people] == [p.activity for p in b.people]
    assert [p.activity for p in a.people] != [p.activity for p in c.people] or not np.array_equal(
        a.positions(times), c.positions(times)
    )


def test_people_never_stand_inside_walls_or_furniture(scan):
    boxes = scan.boxes
    for seed in range(3):
        crowd = populate(scan, np.random.default_rng(seed))
        for k, person in enumerate(crowd.people):
            for t in np.linspace(0.0, person.clip.duration + 3.0, 24):
                pos, _ = crowd.pose(float(t))
                torso = pos[k, TORSO]
                inside = (
                    (boxes.lo[None] < torso[:, None] - 0.02)
                    & (boxes.hi[None] > torso[:, None] + 0.02)
                ).all(axis=-1)
                assert not inside.any(), f"{person.text} inside a box at t={t:.1f}"
                feet = pos[k, [JOINT["left_ankle"], JOINT["right_ankle"]], 2]
                assert feet.min() > person.anchor[2] - 0.01


def test_seated_people_sit_on_their_seat(scan):
    seats = [o for o in scan.regions.objects if o.seat_height is not None]
    for seed in range(6):
        crowd = populate(scan, np.random.default_rng(seed))
        for k, person in enumerate(crowd.people):
            if not load_catalog().get(person.activity).needs_seat:
                continue
            pelvis = crowd.pose(person.clip.duration)[0][k, JOINT["pelvis"]]
            under = [
                o
                for o in seats
                if (o.bbox[:2] - 0.05 <= pelvis[:2]).all()
                and (pelvis[:2] <= o.bbox[3:5] + 0.05).all()
            ]
            assert under, f"{person.text}: no seat under the pelvis"
            assert pelvis[2] - person.anchor[2] == pytest.approx(
                under[0].seat_height + 0.08 * person.shape.height, abs=0.1
            )


@pytest.fixture(scope="module")
def placements(shared_data):
    return read_ha3d_placements(shared_data / "ha3d" / "human_placements.json")


def test_ha3d_placements_for_real_scans(shared_data, placements):
    assert sum(len(v) for v in placements.values()) == 374
    catalog = load_catalog()
    for scan_id in ("17DRP5sb8fy", "1LXtFkjw3qL", "gTV8FGcVJC9"):
        graph = NavGraph.from_file(
            shared_data / "mp3d_connectivity" / f"{scan_id}_connectivity.json"
        )
        entries = placements[scan_id]
        crowd = populate_ha3d(graph, entries, np.random.default_rng(0))
        assert len(crowd) == len(entries)
        start = crowd.positions(np.array([0.0]))[0]
        for person, pelvis in zip(crowd.people, start, strict=True):
            text, _, degrees = entries[person.viewpoint]
            assert person.region == catalog.region_code(text.split(":")[0])
            if not catalog.get(person.activity).needs_path:
                assert np.hypot(*(pelvis[:2] - graph.position(person.viewpoint)[:2])) < 0.5
                assert person.heading == pytest.approx(ha3d_heading(degrees))


def test_ha3d_heading_faces_where_ha3d_turns_the_body():
    # HA3D: SMPL faces +z, turned θ about y, then (x, y, z) → (x, −z, y).
    for deg in (0, 45, 90, 180, 300):
        th = math.radians(deg)
        facing_smpl = np.array([math.sin(th), 0.0, math.cos(th)])
        x, y, z = facing_smpl
        world = np.array([x, -z, y])
        h = ha3d_heading(deg)
        np.testing.assert_allclose([math.sin(h), math.cos(h)], world[:2], atol=1e-12)


def test_placement_file_errors(tmp_path):
    with pytest.raises(MissingDataError, match=r"nowhere\.json"):
        read_ha3d_placements(tmp_path / "nowhere.json")
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"scan": {"vp": ["kitchen:x"]}}))
    with pytest.raises(MalformedDataError, match=r"bad\.json"):
        read_ha3d_placements(bad)


def _write_haps(folder, text: str, frames: int = 30) -> None:
    """A HAPS motion in its exact file layout: the rest pose drifting 1 cm per frame."""
    motion = np.zeros((25, 6, frames))
    motion[:24, 0, :] = 1.0  # rot6d rows of the identity: (1, 0, 0) and (0, 1, 0)
    motion[:24, 4, :] = 1.0
    motion[24, 0, :] = 0.01 * np.arange(frames)
    sub = folder / "human_motion_meshes" / haps_dir_name(text)
    sub.mkdir(parents=True)
    data = {"motion": motion, "thetas": motion[:24], "root_translation": motion[24, :3]}
    np.save(sub / "0_smpl_params.npy", {**data, "text": text, "length": frames})


def test_haps_motions_replace_ours(tmp_path, shared_data, placements):
    scan_id = "17DRP5sb8fy"
    vp, (text, _, _) = sorted(placements[scan_id].items())[0]
    _write_haps(tmp_path, text)
    sources = Sources(haps=load_haps_folder(tmp_path))
    graph = NavGraph.from_file(shared_data / "mp3d_connectivity" / f"{scan_id}_connectivity.json")
    crowd = populate_ha3d(
        graph, {vp: placements[scan_id][vp]}, np.random.default_rng(0), sources=sources
    )
    (person,) = crowd.people
    assert person.clip.fps == 20 and person.text == text.split(":", 1)[1]
    np.testing.assert_allclose(person.rest_offsets, person.clip.offsets)
    # In procedural houses, standing people of the motion's region play it too.
    region = load_catalog().region_code(text.split(":")[0])
    scan = next(
        s
        for s in (load_scan(f"proc-{k}") for k in range(8))
        if any(r.label == region for r in s.regions.regions)
    )
    crowds = [populate(scan, np.random.default_rng(k), sources=sources) for k in range(6)]
    played = [p for c in crowds for p in c.people if p.clip.fps == 20]
    assert played and all(p.region == region and p.text == text.split(":", 1)[1] for p in played)


def test_smpl_model_skins_everyone(blob_smpl):
    crowd = populate(load_scan("proc-0"), np.random.default_rng(0), sources=Sources(smpl=blob_smpl))
    assert crowd.people and all(s is not None for s in crowd.skins)
    betas = [p.skin.betas for p in crowd.people]
    assert not np.allclose(betas[0], betas[-1])
    verts = crowd.skin_vertices(1.0)
    assert set(verts) == set(range(len(crowd)))
    for k, person in enumerate(crowd.people):
        # The mesh stands on the person's floor: the lowest joint blob reaches it.
        assert verts[k][:, 2].min() == pytest.approx(person.anchor[2], abs=0.12)


def test_people_on_excluded_viewpoints_are_placed_too(shared_data, placements):
    # HA3D stands some people on excluded (duplicate) viewpoints; they stand there all the same.
    for scan_id in ("7y3sRwLe3Va", "PX4nDJXEHrG"):
        graph = NavGraph.from_file(
            shared_data / "mp3d_connectivity" / f"{scan_id}_connectivity.json"
        )
        entries = placements[scan_id]
        excluded = [vp for vp in entries if vp not in graph]
        assert excluded
        crowd = populate_ha3d(graph, entries, np.random.default_rng(0))
        assert len(crowd) == len(entries)
        for person in crowd.people:
            if person.viewpoint in excluded:
                assert np.hypot(*(person.anchor[:2] - graph.position(person.viewpoint)[:2])) < 1e-9
