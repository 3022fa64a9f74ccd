"""The training command end to end on tiny settings: files, determinism, resume, evaluation."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from havln_mj.agents.checkpoint import AgentBundle  # noqa: E402
from havln_mj.agents.featurize import feature_store  # noqa: E402
from havln_mj.agents.train import Trainer, main, read_config  # noqa: E402
from havln_mj.commands.evaluate import main as eval_main  # noqa: E402
from havln_mj.errors import InvalidArgumentError, MissingDataError  # noqa: E402

EventAccumulator = pytest.importorskip(
    "tensorboard.backend.event_processing.event_accumulator"
).EventAccumulator

CM = read_config(Path("vln_cm_smoke"), None, []).__dict__ | {"agent": "vln_cm"}
DT = read_config(Path("vln_dt_smoke"), None, []).__dict__ | {"agent": "vln_dt"}


def _config(tmp_path, d, name="c.json"):
    path = tmp_path / name
    path.write_text(json.dumps(d))
    return path


def _weights(path):
    return [t.clone() for t in AgentBundle.load(path).model.state_dict().values()]


def test_vln_cm_trains_writes_its_files_and_is_evaluated(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["--config", str(_config(tmp_path, CM)), "--out", str(out), "--no-progress"]) == 0
    for name in (
        "checkpoint.pt",
        "best.pt",
        "train.log",
        "history.json",
        "loss.png",
        "config.json",
    ):
        assert (out / name).is_file(), name
    history = json.loads((out / "history.json").read_text())
    assert [h["iteration"] for h in history] == [2, 4]
    assert all(np.isfinite(h["loss"]) and 0 <= h["val_sr"] <= 1 for h in history)
    # TensorBoard holds the same numbers as history.json.
    events = EventAccumulator(str(out / "tensorboard"))
    events.Reload()
    loss = events.Scalars("train/loss")
    assert [e.step for e in loss] == [2, 4]
    np.testing.assert_allclose([e.value for e in loss], [h["loss"] for h in history], rtol=1e-6)
    assert [e.value for e in events.Scalars("val/sr")] == pytest.approx(
        [h["val_sr"] for h in history]
    )
    # The resolved config reads back to the same run.
    assert (
        read_config(out / "config.json", None, []).resolved()
        == read_config(_config(tmp_path, CM), None, []).resolved()
    )
    log = (out / "train.log").read_text()
    assert "expert demos" in log and "random-walk demos" in log
    capsys.readouterr()
    # The evaluation harness runs the checkpoint (features of unseen proc-5 are rendered).
    ev = tmp_path / "eval"
    code = eval_main(["--scenes", "proc-5", "--per-scene", "2", "--agent", str(out / "best.pt"),
                      "--out", str(ev)])  # fmt: skip
    assert code == 0
    summary = json.loads((ev / "summary.json").read_text())[0]
    assert summary["instructions"] == 6 and 0.0 <= summary["sr"] <= 1.0
    episodes = json.loads((ev / "episodes.json").read_text())
    assert all(e["steps"] <= 30 for e in episodes)
    # Only the viewpoints the agent stood on were rendered, and the cache says it is partial.
    bundle = AgentBundle.load(out / "best.pt")
    cached = feature_store(bundle.encoder, replace(bundle.features, seed=0)).scan("proc-5")
    visited = {
        step[0]
        for s in json.loads((ev / "submission.json").read_text())
        for step in s["trajectory"]
    }
    assert cached.rows and set(cached.rows) <= visited and not cached.complete


def test_vln_dt_trains_on_random_walks_and_is_evaluated(tmp_path, capsys):
    out = tmp_path / "dt"
    assert main(["--config", str(_config(tmp_path, DT)), "--out", str(out), "--no-progress"]) == 0
    log = (out / "train.log").read_text()
    assert "30 random walks" in log
    bundle = AgentBundle.load(out / "best.pt")
    assert bundle.agent == "vln_dt" and bundle.model.cfg.context == 4
    capsys.readouterr()
    ev = tmp_path / "eval"
    code = eval_main(["--scenes", "proc-3", "--per-scene", "1", "--skip", "3", "--agent",
                      str(out / "best.pt"), "--out", str(ev)])  # fmt: skip
    assert code == 0 and json.loads((ev / "summary.json").read_text())[0]["instructions"] == 3


def test_same_seed_same_run_and_resume_continues_exactly(tmp_path):
    cfg = read_config(_config(tmp_path, CM), None, [])
    Trainer(cfg, tmp_path / "a", progress=False).run()
    short = read_config(_config(tmp_path, CM), None, ["iterations=2"])
    Trainer(short, tmp_path / "b", progress=False).run()
    resumed = Trainer(cfg, tmp_path / "b", progress=False)
    resumed.run(resume=True)
    assert "resumed at iteration 2" in (tmp_path / "b" / "train.log").read_text()
    for x, y in zip(_weights(tmp_path / "a" / "checkpoint.pt"),
                    _weights(tmp_path / "b" / "checkpoint.pt"), strict=True):  # fmt: skip
        torch.testing.assert_close(x, y)
    other = read_config(_config(tmp_path, CM), None, ["lr=0.5"])
    with pytest.raises(InvalidArgumentError, match="another config"):
        Trainer(other, tmp_path / "b", progress=False).run(resume=True)


def test_config_errors(tmp_path, capsys):
    assert read_config(Path("vln_cm_smoke"), "vln_cm", []).iterations == 4  # built-in by name
    with pytest.raises(MissingDataError, match="agents/configs"):
        read_config(tmp_path / "none.json", None, [])
    with pytest.raises(InvalidArgumentError, match="unknown config key 'epochs'"):
        read_config(_config(tmp_path, {**CM, "epochs": 3}), None, [])
    with pytest.raises(InvalidArgumentError, match="is for 'vln_cm'"):
        read_config(_config(tmp_path, CM), "vln_dt", [])
    with pytest.raises(InvalidArgumentError, match="random_fraction"):
        read_config(_config(tmp_path, CM), None, ["random_fraction=2"])
    assert main(["--config", str(_config(tmp_path, CM)), "--set", "feedback=beam"]) == 2
    assert "feedback 'beam' unknown" in capsys.readouterr().err


def test_resume_without_a_checkpoint_is_an_error(tmp_path, capsys):
    code = main(["--config", str(_config(tmp_path, CM)), "--out", str(tmp_path / "new"),
                 "--resume", "--no-progress"])  # fmt: skip
    assert code == 2
    assert "no checkpoint to resume from" in capsys.readouterr().err
    assert not (tmp_path / "new").exists()  # nothing was built or written
    cfg = read_config(_config(tmp_path, CM), None, [])
    with pytest.raises(MissingDataError, match="no checkpoint to resume from"):
        Trainer(cfg, tmp_path / "empty", progress=False).run(resume=True)
