"""Checkpoints by path or by shipped name, and released checkpoints (no resuming state)."""

from __future__ import annotations

import pytest

torch = pytest.importorskip("torch")

from havln_mj.agents.checkpoint import AgentBundle, build_model, resolve_checkpoint  # noqa: E402
from havln_mj.agents.featurize import FeatureSpec  # noqa: E402
from havln_mj.agents.release import main as release_main  # noqa: E402
from havln_mj.agents.vision import ViewEncoder  # noqa: E402
from havln_mj.errors import MissingDataError  # noqa: E402
from havln_mj.tasks.vocab import Vocabulary  # noqa: E402


def _bundle() -> AgentBundle:
    torch.manual_seed(0)
    config = {"vocab_size": 5, "obs_dim": 21, "word_dim": 4, "hidden": 8, "action_dim": 2}
    state = {
        "config": {"agent": "vln_cm"},
        "iteration": 7,
        "history": [{"iteration": 7, "loss": 1.0}],
        "best": 0.5,
        "optimizer": {"state": {0: torch.zeros(1000)}},
        "torch_rng": torch.get_rng_state(),
    }
    return AgentBundle(
        "vln_cm",
        build_model("vln_cm", config),
        config,
        Vocabulary(["walk", "stop", "left"]),
        ViewEncoder(4, (4,), (1,), 16),
        FeatureSpec(),
        state,
    )


@pytest.fixture
def home(tmp_path, monkeypatch):
    """A project home with one checkpoint in agents/."""
    (tmp_path / "scenes").mkdir()
    (tmp_path / "agents").mkdir()
    monkeypatch.setenv("HAVLN_HOME", str(tmp_path))
    _bundle().save(tmp_path / "agents" / "tiny.pt")
    return tmp_path


def test_shipped_checkpoints_resolve_by_name_from_any_folder(home, tmp_path_factory, monkeypatch):
    monkeypatch.chdir(tmp_path_factory.mktemp("elsewhere"))
    shipped = home / "agents" / "tiny.pt"
    assert resolve_checkpoint("agents/tiny.pt") == shipped
    assert resolve_checkpoint("tiny.pt") == shipped
    assert resolve_checkpoint(shipped) == shipped
    assert AgentBundle.load("agents/tiny.pt").agent == "vln_cm"
    with pytest.raises(MissingDataError, match=r"use a shipped one: agents/tiny\.pt"):
        resolve_checkpoint("agents/other.pt")


def test_release_keeps_what_evaluation_needs_and_drops_resuming_state(home, tmp_path, capsys):
    source = home / "agents" / "tiny.pt"
    target = tmp_path / "out" / "released.pt"
    assert release_main([str(source), str(target)]) == 0
    assert target.stat().st_size < source.stat().st_size
    released, full = AgentBundle.load(target), AgentBundle.load(source)
    assert set(released.state) == {"config", "iteration", "history", "best"}
    assert released.state["history"] == full.state["history"]
    for a, b in zip(released.model.state_dict().values(), full.model.state_dict().values(),
                    strict=True):  # fmt: skip
        torch.testing.assert_close(a, b)
    assert released.vocab.tokens == full.vocab.tokens
    assert release_main([str(tmp_path / "none.pt"), str(target)]) == 2
    assert "does not exist" in capsys.readouterr().err
