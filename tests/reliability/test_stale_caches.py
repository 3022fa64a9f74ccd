"""Defect 1: a cached scan is keyed on the content of what it was built from, not its path."""

from __future__ import annotations

import json
import os

from havln_mj.scene import scan as scan_module
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.procedural import recipe as recipe_module
from havln_mj.scene.scan import load_scan
from havln_mj.sim.simulator import Simulator


def _drop_first_edge(path) -> None:
    data = json.loads(path.read_text())
    for i, entry in enumerate(data):
        for j, flag in enumerate(entry["unobstructed"]):
            if flag and i != j:
                data[i]["unobstructed"][j] = data[j]["unobstructed"][i] = False
                path.write_text(json.dumps(data))
                return
    raise AssertionError("the graph has no edge")


def test_a_graph_edited_in_place_rebuilds_its_proxy(fresh_cache, graph_dir, small_scan):
    first = load_scan(small_scan, connectivity_dir=graph_dir)
    path = graph_dir / f"{small_scan}_connectivity.json"
    _drop_first_edge(path)
    again = load_scan(small_scan, connectivity_dir=graph_dir)
    assert again.graph.num_edges == first.graph.num_edges - 1
    assert again.graph.edges() == NavGraph.from_file(path).edges()
    # Without a folder given, the folder the cached scan was built from is checked too.
    _drop_first_edge(path)
    assert load_scan(small_scan).graph.edges() == NavGraph.from_file(path).edges()


def test_both_rendering_modes_read_the_same_graph(fresh_cache, graph_dir, small_scan):
    load_scan(small_scan, connectivity_dir=graph_dir)  # a proxy cached from the old graph
    _drop_first_edge(graph_dir / f"{small_scan}_connectivity.json")
    sim = Simulator(humans=False)
    sim.setNavGraphPath(str(graph_dir))
    sim.setRenderingEnabled(False)
    sim.initialize()
    # The navigation table reads the file; run, scenes build and rendering read the scan.
    assert sim.scan(small_scan).graph.edges() == sim.graph(small_scan).edges()
    sim.close()


def test_touching_a_graph_without_changing_it_keeps_the_cache(fresh_cache, graph_dir, small_scan):
    first = load_scan(small_scan, connectivity_dir=graph_dir)
    stamp = (first.folder / "manifest.json").stat().st_mtime_ns
    os.utime(graph_dir / f"{small_scan}_connectivity.json")
    load_scan(small_scan, connectivity_dir=graph_dir)
    assert (first.folder / "manifest.json").stat().st_mtime_ns == stamp


def test_another_recipe_rebuilds_a_procedural_house(fresh_cache, monkeypatch):
    builds = []
    real_build = scan_module._build_procedural
    monkeypatch.setattr(
        scan_module, "_build_procedural", lambda s, t: (builds.append(s), real_build(s, t))
    )
    load_scan("proc-3")
    load_scan("proc-3")
    assert builds == [3]
    recipe = recipe_module.load_recipe()
    other = recipe_module.Recipe(recipe.raw, "0" * 16)
    monkeypatch.setattr(recipe_module, "load_recipe", lambda path=None: other)
    load_scan("proc-3")
    assert builds == [3, 3]
