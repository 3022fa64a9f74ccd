"""The checkpoints shipped in agents/ load by name and reproduce their table's check row."""

from __future__ import annotations

import json

import pytest

torch = pytest.importorskip("torch")

from havln_mj.agents.checkpoint import AgentBundle, shipped_checkpoints  # noqa: E402
from havln_mj.commands.evaluate import main as eval_main  # noqa: E402
from havln_mj.paths import project_home  # noqa: E402

MANIFEST = json.loads((project_home() / "agents" / "checkpoints.json").read_text())
MAX_BYTES = 4 * 2**20  # shipped checkpoints stay small: the package carries them


def test_every_shipped_checkpoint_is_listed_small_and_released():
    assert sorted(p.name for p in shipped_checkpoints()) == sorted(MANIFEST)
    for path in shipped_checkpoints():
        assert path.stat().st_size < MAX_BYTES, path
        bundle = AgentBundle.load(path)
        assert bundle.agent == MANIFEST[path.name]["agent"]
        assert "optimizer" not in bundle.state and bundle.state["history"]


@pytest.mark.parametrize("name", sorted(MANIFEST))
def test_shipped_checkpoint_reproduces_its_check_row(name, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)  # the checkpoint is found by its shipped name, from anywhere
    entry = MANIFEST[name]
    code = eval_main(
        [*entry["check"], "--agent", f"agents/{name}", "--out", "ev", "--threads", "1"]
    )
    assert code == 0, capsys.readouterr().err
    summary = json.loads((tmp_path / "ev" / "summary.json").read_text())[0]
    row = entry["splits"]["check"]
    assert summary["instructions"] == row["instructions"]
    assert summary["sr"] == pytest.approx(row["sr"], abs=0.02)
    assert summary["ne"] == pytest.approx(row["ne"], abs=0.25)
