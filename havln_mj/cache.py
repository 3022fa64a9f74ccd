"""Atomic writes for caches: a reader sees the old file, the new file, or nothing.

Temporary files and staging folders carry the writing process's id in their names, so the
ones a killed process left behind are recognised and removed by the next write of the same
target (never those of a process still running: concurrent builders each keep their own).
Everything is created with the usual permissions (``0o666``/``0o777`` less the umask).
"""

from __future__ import annotations

import glob
import json
import os
import re
import shutil
import tempfile
from pathlib import Path
from typing import Any


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def pid_alive(pid: int) -> bool:
    """Whether a process with id ``pid`` is running (this one included; not a zombie)."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process
        return True
    try:  # a killed process not yet reaped still has an id (Linux: state Z in /proc)
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return True


def remove_orphans(target: Path) -> list[Path]:
    """Removes temporary files and folders of ``target`` left by processes no longer running.

    Returns:
        The paths removed.
    """
    # The names staging_dir, atomic_write_bytes (random part: 8 characters) and
    # atomic_replace_dir give.
    pattern = re.compile(rf"\.{re.escape(target.name)}\.(?:(\d+)\.[a-z0-9_]{{8}}\.tmp|old-(\d+))")
    removed = []
    try:
        siblings = list(target.parent.glob(f".{glob.escape(target.name)}.*"))
    except OSError:
        return removed
    for path in siblings:
        m = pattern.fullmatch(path.name)
        if m is None or pid_alive(int(m.group(1) or m.group(2))):
            continue
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path, ignore_errors=True)
        else:
            path.unlink(missing_ok=True)
        removed.append(path)
    return removed


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Writes ``data`` to ``path`` through a temporary file in the same folder and a rename."""
    path.parent.mkdir(parents=True, exist_ok=True)
    remove_orphans(path)
    fd, tmp = tempfile.mkstemp(
        dir=path.parent, prefix=f".{path.name}.{os.getpid()}.", suffix=".tmp"
    )
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp creates 0600; use the usual mode
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def atomic_write_json(path: Path, obj: Any, **dump_kwargs: Any) -> None:
    """Serialises ``obj`` as JSON and writes it atomically (see ``atomic_write_bytes``)."""
    atomic_write_bytes(path, json.dumps(obj, **dump_kwargs).encode("utf-8"))


def atomic_replace_dir(staging: Path, target: Path) -> None:
    """Moves a fully written ``staging`` folder to ``target``, replacing any old one.

    The old folder is first renamed aside, so ``target`` is never a half-written mix.
    """
    old = None
    if target.exists():
        old = target.with_name(f".{target.name}.old-{os.getpid()}")
        shutil.rmtree(old, ignore_errors=True)
        os.replace(target, old)
    os.replace(staging, target)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def staging_dir(target: Path) -> Path:
    """Creates an empty temporary folder beside ``target`` for ``atomic_replace_dir``.

    Staging folders of earlier builds of ``target`` whose process is gone are removed first.
    """
    target.parent.mkdir(parents=True, exist_ok=True)
    remove_orphans(target)
    path = Path(
        tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name}.{os.getpid()}.", suffix=".tmp")
    )
    os.chmod(path, 0o777 & ~_umask())  # mkdtemp creates 0700; use the usual mode
    return path
