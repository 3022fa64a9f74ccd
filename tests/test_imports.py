"""A lean process: heavy libraries load only when the feature that needs them runs."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from havln_mj.scene.scan import load_scan

HEAVY = ("scipy", "trimesh", "cv2", "coacd", "matplotlib", "networkx", "PIL", "shapely")


def _loaded_after(code: str) -> list[str]:
    """The heavy modules a fresh interpreter holds after running ``code``."""
    report = f"print(json.dumps(sorted(set({HEAVY!r}) & set(sys.modules))))"
    probe = f"import json, sys\n{code}\n{report}"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module", autouse=True)
def _built_house():
    load_scan("proc-0")  # built here: building a house is a feature that needs heavy libraries


def test_importing_the_simulator_loads_no_heavy_library():
    assert _loaded_after("import havln_mj\nhavln_mj.Simulator, havln_mj.SimState") == []


def test_a_simulator_without_rendering_steps_without_heavy_libraries():
    code = (
        "import havln_mj\n"
        "sim = havln_mj.Simulator()\n"
        "sim.setRenderingEnabled(False)\n"
        "sim.newRandomEpisode(['proc-0'])\n"
        "for _ in range(20):\n"
        "    sim.makeAction([len(sim.getState()[0].navigableLocations) - 1], [0.5], [0.0])\n"
    )
    assert _loaded_after(code) == []


def test_geodesic_distances_load_scipy_when_asked():
    code = (
        "import havln_mj\n"
        "sim = havln_mj.Simulator()\n"
        "sim.setRenderingEnabled(False)\n"
        "sim.newRandomEpisode(['proc-0'])\n"
        "sim.getGeodesicDistance([sim.graph('proc-0').nodes[-1]])\n"
    )
    assert _loaded_after(code) == ["scipy"]


def test_people_without_rendering_need_no_heavy_library():
    code = (
        "import havln_mj\n"
        "sim = havln_mj.Simulator(humans=True)\n"
        "sim.setRenderingEnabled(False)\n"
        "sim.newRandomEpisode(['proc-0'])\n"
        "for _ in range(20):\n"
        "    sim.makeAction([len(sim.getState()[0].navigableLocations) - 1], [0.5], [0.0])\n"
        "assert sim.getHumanState()[0]\n"
    )
    assert _loaded_after(code) == []
