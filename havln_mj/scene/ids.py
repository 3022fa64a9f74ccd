"""Scene ids: ``proc-<seed>`` for procedural houses, Matterport scan ids for real buildings."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from havln_mj.errors import UnknownSceneError, did_you_mean

_PROC = re.compile(r"proc-(0|[1-9][0-9]*)")
_MP3D = re.compile(r"[A-Za-z0-9]{11}")
VALID_FORMS = (
    "'proc-<seed>' with a non-negative integer seed (e.g. 'proc-0'), "
    "an 11-character Matterport3D scan id (e.g. '17DRP5sb8fy'), "
    "or the path of a scan folder"
)


@dataclass(frozen=True)
class SceneId:
    """A parsed scene id.

    Attributes:
        text: The id as given (for folders, the folder's resolved path).
        kind: ``"procedural"``, ``"matterport"`` or ``"folder"``.
        seed: The procedural seed (procedural ids only).
        path: The scan folder (folder ids only).
    """

    text: str
    kind: str
    seed: int | None = None
    path: Path | None = None


def _suggestion(text: str, known: list[str]) -> str:
    digits = re.findall(r"\d+", text)
    candidates = list(known)
    if digits:
        candidates.append(f"proc-{int(digits[0])}")
    if "proc" in text.lower() and not digits:
        candidates.append("proc-0")
    hint = did_you_mean(text, candidates)
    if not hint and digits and text.lower().startswith(("pro", "prc", "poc")):
        hint = f" Did you mean 'proc-{int(digits[0])}'?"
    return hint


def parse_scene_id(text: str, known: list[str] | None = None) -> SceneId:
    """Parses and validates a scene id, failing at once with the valid forms.

    Args:
        text: ``proc-<seed>``, a Matterport scan id, or an existing scan folder path.
        known: Scene ids known locally (cached scans), used to suggest the nearest match.

    Raises:
        UnknownSceneError: ``text`` has none of the valid forms.
    """
    if not isinstance(text, str) or not text:
        raise UnknownSceneError(
            f"scene id must be a non-empty string, got {text!r}; valid forms are {VALID_FORMS}"
        )
    m = _PROC.fullmatch(text)
    if m:
        return SceneId(text, "procedural", seed=int(m.group(1)))
    if _MP3D.fullmatch(text) and not text.startswith("proc"):
        return SceneId(text, "matterport")
    path = Path(text).expanduser()
    if path.is_dir():
        return SceneId(str(path.resolve()), "folder", path=path.resolve())
    raise UnknownSceneError(
        f"unknown scene id {text!r}: valid forms are {VALID_FORMS}.{_suggestion(text, known or [])}"
    )


_PROC_RANGE = re.compile(r"proc-(\d+):(\d+)")


def expand_scene_ranges(scenes: list[str] | tuple[str, ...]) -> list[str]:
    """Scene ids with ``proc-A:B`` written out as ``proc-A`` … ``proc-(B-1)``.

    Raises:
        UnknownSceneError: An empty range.
    """
    out: list[str] = []
    for s in scenes:
        m = _PROC_RANGE.fullmatch(s)
        if m is None:
            out.append(s)
            continue
        a, b = int(m[1]), int(m[2])
        if b <= a:
            raise UnknownSceneError(f"scene range {s!r} is empty; write proc-A:B with A < B")
        out += [f"proc-{k}" for k in range(a, b)]
    return out
