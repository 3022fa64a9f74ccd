"""Training configs are checked section by section: a typo names the dotted key and the valid
keys, before anything is rendered; the resolved config reads back to the same run."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

torch = pytest.importorskip("torch")

from havln_mj.agents.train import TrainConfig, main, read_config, resolve_device  # noqa: E402
from havln_mj.errors import InvalidArgumentError  # noqa: E402


@pytest.mark.parametrize(
    ("config", "override", "key", "suggestion"),
    [
        ("vln_cm_smoke", "model.hiden=512", "model.hiden", "hidden"),
        ("vln_cm_smoke", "model.nonexistent=3", "model.nonexistent", None),
        ("vln_dt_smoke", "model.text.n_layer=2", "model.text.n_layer", "n_layers"),
        ("vln_cm_smoke", "features.view.widht=64", "features.view.widht", "width"),
        ("vln_cm_smoke", "features.encoder.width=[8]", "features.encoder.width", "widths"),
        ("vln_cm_smoke", "train.per_scen=2", "train.per_scen", "per_scene"),
        ("vln_dt_smoke", "itrations=5", "itrations", "iterations"),
    ],
)
def test_a_typo_in_any_section_names_the_key_and_the_valid_keys(config, override, key, suggestion):
    with pytest.raises(InvalidArgumentError) as info:
        read_config(Path(config), None, [override])
    message = str(info.value)
    assert f"unknown config key {key!r}" in message
    section = key.rpartition(".")[0] or "the top level"
    assert f"valid keys of {section}: " in message
    if suggestion:
        assert f"Did you mean {suggestion!r}?" in message


def test_valid_keys_listed_are_the_models_own():
    with pytest.raises(InvalidArgumentError) as info:
        read_config(Path("vln_cm_smoke"), None, ["model.hiden=512"])
    listed = str(info.value).split("valid keys of model: ")[1].split(".")[0].split(", ")
    assert listed == ["action_dim", "dropout", "hidden", "word_dim"]  # vocab/obs set by data


def test_bad_nested_values_fail_before_training(capsys):
    with pytest.raises(InvalidArgumentError, match=r"CMConfig\.hidden must be a positive int"):
        read_config(Path("vln_cm_smoke"), None, ["model.hidden=-4"])
    with pytest.raises(InvalidArgumentError, match="divisible"):
        read_config(Path("vln_dt_smoke"), None, ["model.d_model=15"])
    with pytest.raises(InvalidArgumentError, match="not a section"):
        read_config(Path("vln_cm_smoke"), None, ["iterations.x=1"])
    assert main(["--config", "vln_cm_smoke", "--set", "model.hiden=512"]) == 2
    assert "unknown config key 'model.hiden'" in capsys.readouterr().err


def test_resolved_config_fills_defaults_and_reads_back(tmp_path):
    cfg = read_config(Path("vln_cm_smoke"), None, [])
    resolved = cfg.resolved()
    assert resolved["model"] == {"word_dim": 8, "hidden": 16, "action_dim": 4, "dropout": 0.5}
    assert resolved["features"]["view"]["vfov"] == 0.8  # a ViewConfig default
    assert resolved["features"]["encoder"] == {
        "widths": [8, 16],
        "blocks": [1, 1],
        "out_dim": 16,
        "stem_stride": 2,
    }
    path = tmp_path / "config.json"
    path.write_text(json.dumps(resolved))
    again = read_config(path, None, [])
    assert again.resolved() == resolved
    assert isinstance(again, TrainConfig)


def test_devices_are_checked(capsys):
    assert resolve_device("cpu").type == "cpu"
    with pytest.raises(InvalidArgumentError, match="valid: cpu, cuda, cuda:N"):
        resolve_device("tpu")
    if not torch.cuda.is_available():
        with pytest.raises(InvalidArgumentError, match="sees no CUDA device"):
            resolve_device("cuda")
        assert main(["--config", "vln_cm_smoke", "--device", "cuda"]) == 2
        assert "sees no CUDA device" in capsys.readouterr().err
