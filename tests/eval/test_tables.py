"""Result tables in the paper's layout from evaluation folders."""

from __future__ import annotations

import json

from havln_mj.eval.tables import main


def _summary(folder, rows):
    folder.mkdir(parents=True)
    (folder / "summary.json").write_text(json.dumps(rows))


def test_rows_average_over_seeds_and_the_paper_follows(tmp_path, capsys):
    for k, sr in enumerate((0.4, 0.6)):
        _summary(
            tmp_path / f"s{k}",
            [
                {"split": "val_seen", "ne": 4.0 + k, "tcr": 1.0, "cr": 0.5, "sr": sr},
                {"split": "val_unseen", "ne": 5.0, "tcr": 2.0, "cr": 0.25, "sr": sr / 2},
            ],
        )
    out = tmp_path / "t.md"
    row = f"agent={tmp_path / 's0'},{tmp_path / 's1'}"
    assert main(["--row", row, "--paper", "--out", str(out)]) == 0
    lines = out.read_text().splitlines()
    assert lines[0].startswith("| agent | val_seen NE | TCR | CR | SR | val_unseen NE")
    assert lines[2] == (
        "| agent | 4.50 ± 0.50 | 1.00 ± 0.00 | 0.50 ± 0.00 | 0.50 ± 0.10 | 5.00 ± 0.00 | "
        "2.00 ± 0.00 | 0.25 ± 0.00 | 0.25 ± 0.05 |"
    )
    assert any(line.startswith("| paper: VLN-DT (100 % random data) | 8.51") for line in lines)
    data = json.loads(out.with_suffix(".json").read_text())
    assert data["agent"]["val_seen"]["sr"] == [0.4, 0.6]


def test_missing_folders_and_bad_rows(tmp_path, capsys):
    assert main(["--row", f"x={tmp_path / 'none'}", "--out", str(tmp_path / "t.md")]) == 2
    assert "summary.json does not exist" in capsys.readouterr().err
    assert main(["--row", "no-equals", "--out", str(tmp_path / "t.md")]) == 2
    assert "NAME=DIR" in capsys.readouterr().err
