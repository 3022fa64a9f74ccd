"""``havln_mj scenes build``."""

from __future__ import annotations

from havln_mj.cli import main
from havln_mj.scene.scan import scans_dir


def test_scenes_build_prebuilds_and_reports_failures(capsys):
    assert main(["scenes", "build", "proc-31", "proc-32", "--workers", "2"]) == 0
    assert (scans_dir() / "proc-31" / "connectivity.json").is_file()
    assert (scans_dir() / "proc-32" / "mesh.glb").is_file()
    out = capsys.readouterr().out
    assert "built 2 of 2 scenes" in out
    assert main(["scenes", "build", "proc-31", "Abcdefghijk", "--workers", "1"]) == 1
    assert "Abcdefghijk: FAILED" in capsys.readouterr().out
    assert main(["scenes", "build"]) == 2
