"""The README's Simulator example runs as written (with the real graphs' folder filled in)."""

from __future__ import annotations

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_simulator_example_runs(shared_data):
    block = re.search(r"```python\n(.*?)```", README.read_text(), re.S)
    assert block, "README has no python example"
    code = block.group(1).replace("path/to/connectivity", str(shared_data / "mp3d_connectivity"))
    scope: dict = {}
    exec(compile(code, str(README), "exec"), scope)
    state = scope["sim"].getState()[0]
    assert state.step == 1
    assert state.location.viewpointId != "5b9b2794954e4694a45fc424a8643081"
