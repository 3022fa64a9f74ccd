"""End to end: ``havln_mj annotate`` in headless Chromium, then the saved file in the simulator."""

from __future__ import annotations

import math
import signal
import subprocess
import sys
import threading

import numpy as np
import pytest

from havln_mj.errors import MissingDataError
from havln_mj.humans.population import read_ha3d_placements
from havln_mj.scene.scan import load_scan


@pytest.fixture
def browser():
    pytest.importorskip("selenium", reason="selenium comes with .[dev]")
    from havln_mj.annotator.browser import browser_paths, headless_chromium

    try:
        browser_paths()
    except MissingDataError as exc:
        pytest.skip(str(exc))
    with headless_chromium(1400, 1000) as driver:
        yield driver


@pytest.fixture
def annotate(tmp_path):
    """Runs ``havln_mj annotate`` on proc-0 (small views, any free port); yields its URL."""
    saved = tmp_path / "human_placements.json"
    proc = subprocess.Popen(
        [sys.executable, "-m", "havln_mj.cli", "annotate", "--scene", "proc-0", "--port", "0",
         "--width", "96", "--height", "72", "--placements", str(saved)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    timer = threading.Timer(180, proc.kill)  # a hung start fails the test, never the run
    timer.start()
    url = None
    for line in proc.stdout:
        if line.startswith("open http://"):
            url = line.split()[1]
            break
    timer.cancel()
    if url is None:
        proc.kill()
        pytest.fail(f"havln_mj annotate did not start: {proc.stderr.read()}")
    yield url, saved, proc
    if proc.poll() is None:
        proc.kill()
    proc.wait(timeout=30)
    proc.stdout.close()
    proc.stderr.close()


def _in_room(scan, code, n=1):
    vps = [v for v in scan.graph.nodes if (r := scan.regions.region_of(v)) and r.label == code]
    return vps[:n]


def test_place_move_delete_save_and_simulate(browser, annotate):
    from havln_mj import Simulator
    from havln_mj.annotator.browser import AnnotatorPage

    url, saved, proc = annotate
    scan = load_scan("proc-0")
    (kitchen,) = _in_room(scan, "k")
    (hallway,) = _in_room(scan, "h")
    other = next(v for v in scan.graph.nodes if v not in (kitchen, hallway))

    page = AnnotatorPage(browser, url)
    page.click_viewpoint(kitchen)
    page.choose("kitchen/stir-pot", model=2, facing_deg=135)
    page.place(kitchen)
    clip = page.preview()  # the person's motion, as an H.264 clip the browser plays
    assert clip["error"] is None and clip["duration"] > 1.0 and clip["width"] == 96
    page.wait_view()
    page.click_viewpoint(hallway)
    page.move(hallway)
    page.new_person()
    page.click_viewpoint(other)
    page.place(other)
    page.delete()
    assert page.save().startswith(f"saved 1 people to {saved}")

    proc.send_signal(signal.SIGINT)  # Ctrl+C stops the server cleanly
    assert proc.wait(timeout=30) == 0
    entries = read_ha3d_placements(saved)["proc-0"]
    assert entries == {hallway: ("kitchen:Someone stirring a pot on the stove.", 2, 45.0)}

    sim = Simulator(humans=True, human_placements=saved)
    sim.setRenderingEnabled(False)
    sim.initialize()
    sim.newEpisode(["proc-0"], [hallway], [0.0], [0.0])
    (person,) = sim.getHumanState()[0]
    assert person.activity == "kitchen/stir-pot"
    # Facing 135° as placed (the motion sways the body a little).
    assert person.heading == pytest.approx(math.radians(135), abs=0.15)
    xy = scan.graph.position(hallway)[:2]
    assert np.hypot(*(person.position[:2] - xy)) < 0.5
