"""``havln_mj scenes build`` and ``havln_mj dataset build``."""

from __future__ import annotations

from havln_mj.cli import main
from havln_mj.scene.scan import scans_dir
from havln_mj.tasks.datasets import load_dataset
from havln_mj.tasks.procedural import read_vocab


def test_scenes_build_prebuilds_and_reports_failures(capsys):
    assert main(["scenes", "build", "proc-31", "proc-32", "--workers", "2"]) == 0
    assert (scans_dir() / "proc-31" / "connectivity.json").is_file()
    assert (scans_dir() / "proc-32" / "mesh.glb").is_file()
    out = capsys.readouterr().out
    assert "built 2 of 2 scenes" in out
    assert main(["scenes", "build", "proc-31", "Abcdefghijk", "--workers", "1"]) == 1
    assert "Abcdefghijk: FAILED" in capsys.readouterr().out
    assert main(["scenes", "build"]) == 2


def test_dataset_build_writes_a_split(tmp_path, capsys):
    args = ["dataset", "build", "--scenes", "proc-3", "proc-5", "--split", "train"]
    assert main([*args, "--episodes-per-scene", "4", "--seed", "1", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr()
    assert "wrote 8 paths, 24 instructions" in out.out and "words per instruction" in out.out
    assert "train" in out.err  # the progress bar
    data = load_dataset(tmp_path / "HA_train.json")
    assert len(data) == 8 and data.num_instructions == 24
    assert {e.scan for e in data} == {"proc-3", "proc-5"}
    assert read_vocab(tmp_path / "vocab_train.txt")
    bad = ["dataset", "build", "--scenes", "proc-3", "nope", "--split", "train"]
    assert main([*bad, "--out", str(tmp_path / "bad")]) == 2
    assert "unknown scene id 'nope'" in capsys.readouterr().err
    assert not (tmp_path / "bad").exists()
