"""``havln_mj scenes build`` and ``havln_mj dataset build``."""

from __future__ import annotations

import subprocess
import sys

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
    assert "proc-31: procedural" in out and "0 edges walked by route" in out
    assert main(["scenes", "build", "proc-31", "Abcdefghijk", "--workers", "1"]) == 1
    assert "Abcdefghijk: FAILED" in capsys.readouterr().out
    assert main(["scenes", "build"]) == 2


def test_scenes_build_says_how_many_edges_a_proxy_walks_by_route(shared_data, capsys):
    # 5LpN3gDmAk7's proxy walks one edge round the corridor it crosses (see test_realscan).
    conn = str(shared_data / "mp3d_connectivity")
    argv = ["scenes", "build", "5LpN3gDmAk7", "--connectivity-dir", conn, "--workers", "1"]
    assert main([*argv, "--collision", "boxes"]) == 0
    out = capsys.readouterr().out
    assert "5LpN3gDmAk7: graph proxy" in out
    assert "1 edge walked by route, 0 unwalkable" in out
    # D7G3Y4RVNrH's proxy draws a flight for a steep edge (see test_realscan).
    assert main(["scenes", "build", "D7G3Y4RVNrH", *argv[3:], "--collision", "boxes"]) == 0
    out = capsys.readouterr().out
    assert "1 edge walked by route (1 along a flight drawn for it), 0 unwalkable" in out


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


def _parsers(parser):
    """A parser and every subcommand parser under it."""
    import argparse

    yield parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                yield from _parsers(sub)


def test_every_command_documents_every_flag():
    import argparse

    from havln_mj.cli import COMMANDS, command_module

    for name in COMMANDS:
        parser = command_module(name).parser(f"havln_mj {name}")
        assert parser.prog == f"havln_mj {name}"
        for p in _parsers(parser):
            for action in p._actions:
                if isinstance(action, argparse._HelpAction | argparse._SubParsersAction):
                    continue
                label = "/".join(action.option_strings) or action.dest
                assert action.help and action.help.strip(), f"havln_mj {name}: {label}"


def test_the_command_dispatches_and_names_what_is_valid(capsys):
    assert main([]) == 2 and "commands:" in capsys.readouterr().out
    assert main(["evl"]) == 2
    assert "Did you mean 'eval'" in capsys.readouterr().err
    for name in ("run", "eval", "train", "tables"):
        try:
            main([name, "--help"])
        except SystemExit as exc:
            assert exc.code == 0
        assert f"usage: havln_mj {name}" in capsys.readouterr().out


def test_python_dash_m_runs_the_command():
    done = subprocess.run(
        [sys.executable, "-m", "havln_mj", "eval", "--help"], capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    assert "usage: havln_mj eval" in done.stdout
