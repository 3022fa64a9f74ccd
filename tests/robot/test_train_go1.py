"""Training of the learned GO1 controller: curriculum, a tiny run, resume, export."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from havln_mj.errors import InvalidArgumentError, MalformedDataError
from havln_mj.train_go1.config import CurriculumConfig, EnvConfig, TrainConfig, config_from_json
from havln_mj.train_go1.curriculum import Curriculum
from havln_mj.train_go1.terrains import course_spec, ramp_degrees, riser

TINY = {
    "seed": 3,
    "iterations": 2,
    "checkpoint_every": 1,
    "env": {
        "num_envs": 2,
        "levels": 3,
        "max_init_level": 2,
        "treads": [0.3],
        "episode_seconds": 0.6,
        "flight_risers": 2,
    },
    "ppo": {"steps_per_env": 4, "hidden": [8], "epochs": 1, "minibatches": 2},
}


def test_curriculum_promotes_and_demotes_on_progress() -> None:
    rng = np.random.default_rng(0)
    cur = Curriculum(CurriculumConfig(promote=0.8, demote=0.4), 4, np.array([0, 2]), rng)
    # (progress, fell) -> level of robot 0, starting at level 0
    steps = [
        ((0.9, False), 1),  # far enough: up
        ((0.8, False), 2),  # exactly the threshold: up
        ((0.6, False), 2),  # in between: stays
        ((0.95, True), 1),  # a fall is a step down however far it got
        ((0.3, False), 0),  # too short: down
        ((0.1, False), 0),  # never below level 0
    ]
    for (progress, fell), level in steps:
        assert cur.update(0, progress, fell) == level
    assert cur.level[1] == 2  # the other robot did not move
    moved = set()
    for _ in range(200):
        cur.level[1] = 3
        moved.add(cur.update(1, 1.0, False))
    assert moved <= set(range(4)) and len(moved) > 1  # past the last level: a random one
    assert cur.mean == pytest.approx(np.mean(cur.level))


def test_curriculum_terrains_rise_as_configured() -> None:
    cfg = EnvConfig(levels=10, risers=(0.02, 0.19), max_ramp_deg=30.0)
    assert riser(cfg, 0) == 0.0
    assert riser(cfg, 1) == pytest.approx(0.02) and riser(cfg, 9) == pytest.approx(0.19)
    assert ramp_degrees(cfg, 9) == pytest.approx(30.0)
    spec, run, rise = course_spec(cfg, "stairs", 9, 0.3)
    assert run == pytest.approx(4 * 0.3) and rise == pytest.approx(5 * 0.19)
    names = {g.name for g in spec.worldbody.geoms}
    assert {"up1", "up4", "landing", "down1", "down4"} <= names


def test_config_rejects_unknown_keys_and_bad_values() -> None:
    with pytest.raises(MalformedDataError, match="unknown keys"):
        config_from_json({"env": {"num_robots": 3}})
    with pytest.raises(InvalidArgumentError, match="num_envs"):
        TrainConfig(env=EnvConfig(num_envs=0))
    cfg = config_from_json(TINY)
    assert config_from_json(json.loads(json.dumps(cfg.to_json()))) == cfg


def test_tiny_run_checkpoints_resumes_and_exports(tmp_path: Path) -> None:
    pytest.importorskip("torch")
    pytest.importorskip("matplotlib")
    from havln_mj.robot.go1.learned import load_policy
    from havln_mj.train_go1.__main__ import main

    cfg = tmp_path / "tiny.json"
    cfg.write_text(json.dumps(TINY))
    run = tmp_path / "run"
    assert main(["--config", str(cfg), "--out", str(run)]) == 0
    log = [json.loads(line) for line in (run / "log.jsonl").read_text().splitlines()]
    assert [r["iteration"] for r in log] == [1, 2]
    assert log[-1]["env_steps"] == 2 * 2 * 4
    for name in ("checkpoint.pt", "policy.npz", "config.json", "curriculum.png"):
        assert (run / name).is_file(), name
    assert not list(run.glob("*.tmp*"))
    # Asking again without --resume would overwrite the run: refused.
    assert main(["--config", str(cfg), "--out", str(run)]) == 2
    assert main(["--out", str(run), "--resume", "--iterations", "3"]) == 0
    log = [json.loads(line) for line in (run / "log.jsonl").read_text().splitlines()]
    assert [r["iteration"] for r in log] == [1, 2, 3]
    assert log[-1]["env_steps"] == 3 * 2 * 4
    assert main(["--out", str(run), "--export", str(tmp_path / "p.npz")]) == 0
    policy = load_policy(tmp_path / "p.npz")
    assert policy.train_config["seed"] == 3
    obs = np.zeros(policy.spec.obs_size)
    np.testing.assert_allclose(policy.act(obs), load_policy(run / "policy.npz").act(obs), atol=1e-6)
    assert main(["--out", str(tmp_path / "none"), "--resume"]) == 2


def test_resume_restores_levels_and_generators(tmp_path: Path) -> None:
    torch = pytest.importorskip("torch")
    from havln_mj.train_go1.trainer import Trainer

    first = Trainer(config_from_json(TINY), tmp_path / "run")
    first.train(2)
    ckpt = torch.load(tmp_path / "run" / "checkpoint.pt", weights_only=False)
    again = Trainer(config_from_json({}), tmp_path / "run", resume=True)
    assert again.cfg == first.cfg  # the run's own config, not the one passed
    assert again.iteration == 2
    np.testing.assert_array_equal(again.envs.curriculum.level, ckpt["levels"])
    state = again.gen.get_state()
    assert torch.equal(state, ckpt["torch_rng"])


def test_same_seed_same_run(tmp_path: Path) -> None:
    pytest.importorskip("torch")
    from havln_mj.train_go1.trainer import Trainer

    rows = []
    for k in range(2):
        Trainer(config_from_json(TINY), tmp_path / f"r{k}").train(1)
        row = json.loads((tmp_path / f"r{k}" / "log.jsonl").read_text())
        rows.append({key: v for key, v in row.items() if not key.endswith("_s")})
    assert rows[0] == rows[1]
