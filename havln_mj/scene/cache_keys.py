"""What a cached scan was built from, and the check that it is whole.

A built scan folder holds a manifest (:data:`~havln_mj.scene.scanfolder.MANIFEST`, written
last) with two parts:

* ``inputs``: everything the folder was derived from, by content: the digests of the
  connectivity graph and the ``.house`` file, the licensed mesh's path, size and modification
  time (hashing a large mesh on every load would cost more than it protects), the generator
  and builder versions and the digest of their parameters. A cached scan is current only when
  the inputs it would be built from now are the same.
* ``files``: the size and SHA-256 of every file in the folder. A folder whose files do not
  match (one missing, truncated, edited or unreadable) is damaged.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from pathlib import Path
from typing import Any

from havln_mj.cache import atomic_write_json
from havln_mj.errors import MalformedDataError, MissingDataError
from havln_mj.scene.scanfolder import MANIFEST

# Bump when the manifest's layout changes: older folders are rebuilt.
MANIFEST_VERSION = 1
_CHUNK = 1 << 20


def file_digest(path: Path) -> str:
    """SHA-256 (hex) of a file's content.

    Raises:
        OSError: The file cannot be read.
    """
    h = hashlib.sha256()
    with open(path, "rb") as f:
        while chunk := f.read(_CHUNK):
            h.update(chunk)
    return h.hexdigest()


def stat_stamp(path: Path) -> dict[str, Any]:
    """A large input file named by its resolved path, size and modification time."""
    path = Path(path).resolve()
    st = path.stat()
    return {"path": str(path), "size": st.st_size, "mtime_ns": st.st_mtime_ns}


def params_digest(params: Any) -> str:
    """Digest of a parameter dataclass's fields (sorted JSON), for cache inputs."""
    fields = dataclasses.asdict(params)
    return hashlib.sha256(json.dumps(fields, sort_keys=True).encode()).hexdigest()[:16]


def write_manifest(folder: Path, inputs: dict[str, Any]) -> None:
    """Records ``inputs`` and every file of ``folder`` (call it once the folder is complete)."""
    files = {
        p.name: {"size": p.stat().st_size, "sha256": file_digest(p)}
        for p in sorted(folder.iterdir())
        if p.is_file() and p.name != MANIFEST and not p.name.startswith(".")
    }
    atomic_write_json(
        folder / MANIFEST,
        {"version": MANIFEST_VERSION, "inputs": inputs, "files": files},
        indent=1,
        sort_keys=True,
    )


def read_manifest(folder: Path) -> dict[str, Any]:
    """The inputs a scan folder was built from, after checking that it is whole.

    Raises:
        MissingDataError: The folder, its manifest or a file it lists is missing.
        MalformedDataError: The manifest is unreadable or of another version, or a file's size
            or content differs from what was written.
    """
    path = folder / MANIFEST
    if not path.is_file():
        raise MissingDataError(f"{path} is missing (an unfinished or older build)")
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
        files, inputs = manifest["files"], manifest["inputs"]
        version = manifest["version"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise MalformedDataError(f"{path} is unreadable ({exc})") from None
    if version != MANIFEST_VERSION or not isinstance(files, dict):
        raise MalformedDataError(f"{path} has version {version!r}, expected {MANIFEST_VERSION}")
    for name, want in files.items():
        file = folder / name
        if not file.is_file():
            raise MissingDataError(f"{file} is missing")
        try:
            size, digest = file.stat().st_size, None
            if size == want["size"]:
                digest = file_digest(file)
        except OSError as exc:
            raise MalformedDataError(f"{file} cannot be read ({exc.strerror or exc})") from None
        if size != want["size"]:
            raise MalformedDataError(f"{file} has {size} bytes, {want['size']} were written")
        if digest != want["sha256"]:
            raise MalformedDataError(f"{file} differs from the file written (content changed)")
    return inputs
