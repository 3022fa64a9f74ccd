"""Checks the command-line tools run on their arguments before doing any work.

Each check returns None when the value is fine, else the message to show: it names the flag,
the value and what would be valid. :func:`add_data_flags` adds the flags that say where a
user's licensed data is, the same in every command.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from collections.abc import Iterable
from pathlib import Path

from havln_mj.errors import UnknownSceneError
from havln_mj.scene.ids import parse_scene_id

DATA_FLAGS = {
    "--human-placements": "HA3D placement file for real scans (default $HAVLN_HA3D_PLACEMENTS)",
    "--mp3d-dir": "Matterport3D data root (raw or habitat layout; default $HAVLN_MP3D_DIR)",
    "--connectivity-dir": (
        "folder of <scan>_connectivity.json graphs (default $HAVLN_CONNECTIVITY_DIR)"
    ),
    "--haps-dir": (
        "HAPS motion folder to play instead of built-in motions (default $HAVLN_HAPS_DIR)"
    ),
    "--smpl-model": (
        "SMPL model file to draw people as skinned meshes (default $HAVLN_SMPL_MODEL)"
    ),
}
"""The flags naming a user's data, with their help."""


def add_go1_controller_flag(p: argparse.ArgumentParser) -> None:
    """Adds ``--go1-controller``: the gait the simulated GO1 walks with."""
    from havln_mj.robot.go1.constants import CONTROLLERS  # the GO1 package, only for its CLIs

    p.add_argument(
        "--go1-controller",
        choices=CONTROLLERS,
        default="trot",
        help="the GO1's gait: trot (blind, flat floors; default), terrain (height scan), "
        "learned (a trained policy over the terrain gait), crawl (the slow stair crawl) or "
        "hybrid (the trot, and the crawl where a walk or turn meets a step)",
    )


def add_data_flags(p: argparse.ArgumentParser, *flags: str) -> None:
    """Adds ``flags`` (names in :data:`DATA_FLAGS`) to ``p``, as paths defaulting to None."""
    for flag in flags:
        p.add_argument(flag, type=Path, default=None, help=DATA_FLAGS[flag])


def in_range(
    flag: str, value: float, lo: float, hi: float | None = None, unit: str = ""
) -> str | None:
    """Whether ``lo <= value <= hi`` (``hi`` None: no upper bound)."""
    if lo <= value and (hi is None or value <= hi):
        return None
    valid = f"in [{lo:g}, {hi:g}]" if hi is not None else f"at least {lo:g}"
    return f"{flag} must be {valid}{unit}, got {value:g}"


def existing(flag: str, path: Path | None, kind: str = "folder") -> str | None:
    """Whether ``path`` (when given) is an existing ``kind``: ``"folder"`` or ``"file"``."""
    if path is None:
        return None
    path = Path(path).expanduser()
    ok = path.is_dir() if kind == "folder" else path.is_file()
    if ok:
        return None
    what = "does not exist" if not path.exists() else f"is not a {kind}"
    return f"{flag} {path} {what}; give an existing {kind}"


def writable_folder(flag: str, path: Path) -> str | None:
    """Whether ``path`` is a folder this process can write, or can be made one (not made here)."""
    path = Path(path).expanduser().absolute()
    if path.exists() and not path.is_dir():
        return f"{flag} {path} is a file; give a folder to write into"
    base = path
    while not base.exists():
        base = base.parent
    if not base.is_dir():
        return f"{flag} {path} cannot be made: {base} is a file"
    try:
        fd, probe = tempfile.mkstemp(dir=base, prefix=".write-test-")
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        return f"{flag} {path} cannot be written ({exc.strerror or exc}); give a writable folder"
    return None


def scene_ids(flag: str, ids: Iterable[str], known: list[str] | None = None) -> str | None:
    """Whether every id is a valid scene id (the message lists each bad one and the forms)."""
    bad = []
    for text in ids:
        try:
            parse_scene_id(text, known)
        except UnknownSceneError as exc:
            bad.append(str(exc))
    if not bad:
        return None
    return f"{flag}: " + "; ".join(bad)


def usable_cpus() -> int:
    """CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def worker_count(requested: int, jobs: int) -> tuple[int, str | None]:
    """Processes worth starting for ``jobs`` jobs: at most the jobs and the CPUs.

    Returns:
        The count and, when it is fewer than requested, a note saying why.
    """
    cpus = usable_cpus()
    n = max(1, min(requested, jobs, cpus))
    if n == requested:
        return n, None
    return n, (
        f"note: using {n} worker process{'' if n == 1 else 'es'}, not {requested}: "
        f"{jobs} scene{'' if jobs == 1 else 's'} to build on {cpus} CPU{'' if cpus == 1 else 's'}"
    )
