"""An evaluation's output folder: checked before work starts, written as results come.

* ``run.json``: the settings that decide the results, written before the first instruction.
* ``instructions.jsonl``: one line per finished instruction (its trajectory with the
  per-step collision flags, and HA3D's clock counter before and after it), appended and
  flushed as each one finishes. An interrupted or failed evaluation keeps every finished
  line; ``--resume`` reads them back and runs only the rest (a torn last line is run again).
* ``episodes.json``, ``submission.json``, ``summary.md`` and, last, ``summary.json``: the
  scored results, written when every instruction has run (each file atomically).

Without ``--resume`` a folder's earlier results (these files and ``recordings/``) are
removed first, so a folder never mixes two evaluations; with it, the settings must match.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import IO, Any

from havln_mj.cache import atomic_write_bytes, atomic_write_json
from havln_mj.errors import InvalidArgumentError, OutputError

RUN = "run.json"
PROGRESS = "instructions.jsonl"
EPISODES = "episodes.json"
SUBMISSION = "submission.json"
SUMMARY_MD = "summary.md"
SUMMARY = "summary.json"
RECORDINGS = "recordings"
_FILES = (RUN, PROGRESS, EPISODES, SUBMISSION, SUMMARY_MD, SUMMARY)


class Outputs:
    """The output folder of one evaluation.

    Args:
        out: The folder (created if needed).
        settings: What decides the results (agent, protocol, data, seed, ...), JSON-able.
        resume: Continue the evaluation the folder holds instead of starting afresh.

    Raises:
        OutputError: The folder cannot be created or written.
        InvalidArgumentError: ``resume`` with nothing to resume, or with other settings.
    """

    def __init__(self, out: Path, settings: Mapping[str, Any], resume: bool) -> None:
        self.out = out
        self.settings = json.loads(json.dumps(dict(settings)))  # as read back from run.json
        _check_writable(out)
        self.done: dict[tuple[str, str], dict] = {}
        self.resume = resume
        if resume:
            self._resume()
        self._file: IO[str] | None = None

    def begin(self) -> None:
        """Starts writing: a fresh evaluation first removes the folder's earlier results."""
        if not self.resume:
            self._clear()
            atomic_write_json(self.out / RUN, {"settings": self.settings}, indent=1)

    def _clear(self) -> None:
        for name in _FILES:
            (self.out / name).unlink(missing_ok=True)
        shutil.rmtree(self.out / RECORDINGS, ignore_errors=True)

    def _resume(self) -> None:
        try:
            old = json.loads((self.out / RUN).read_text())["settings"]
        except (OSError, ValueError, KeyError, TypeError):
            raise InvalidArgumentError(
                f"--resume: {self.out} holds no evaluation to resume ({RUN} is missing or "
                "unreadable); run without --resume to start one"
            ) from None
        new = self.settings
        differ = sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k))
        if differ:
            changes = "; ".join(f"{k}: {old.get(k)!r} then, {new.get(k)!r} now" for k in differ)
            raise InvalidArgumentError(
                f"--resume: {self.out} holds an evaluation with other settings ({changes}); "
                "resume it with the same arguments, or choose another --out"
            )
        records = list(_read_lines(self.out / PROGRESS))
        for record in records:
            self.done[(record["split"], record["instr_id"])] = record
        # Drop a torn last line, so what is appended next starts on a line of its own.
        lines = "".join(json.dumps(r, separators=(",", ":")) + "\n" for r in records)
        atomic_write_bytes(self.out / PROGRESS, lines.encode())
        (self.out / SUMMARY).unlink(missing_ok=True)  # complete again only when rescored

    def add(self, record: Mapping[str, Any]) -> None:
        """Appends one finished instruction and flushes it to disk."""
        if self._file is None:
            try:
                self._file = open(self.out / PROGRESS, "a", encoding="utf-8")  # noqa: SIM115
            except OSError as exc:
                raise OutputError(f"cannot write {self.out / PROGRESS}: {exc.strerror}") from None
        self._file.write(json.dumps(record, separators=(",", ":")) + "\n")
        self._file.flush()
        self.done[(record["split"], record["instr_id"])] = dict(record)

    def close(self) -> None:
        """Closes the progress file."""
        if self._file is not None:
            self._file.close()
            self._file = None

    def finish(self, episodes: list, submission: list, summaries: list, table: str) -> None:
        """Writes the scored results, the summary last."""
        self.close()
        atomic_write_json(self.out / EPISODES, episodes)
        atomic_write_json(self.out / SUBMISSION, submission)
        atomic_write_bytes(self.out / SUMMARY_MD, (table + "\n").encode())
        atomic_write_json(self.out / SUMMARY, summaries, indent=1)


def _check_writable(out: Path) -> None:
    """Creates ``out`` and proves a file can be written in it."""
    try:
        out.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(dir=out, prefix=".havln-probe-")
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise OutputError(
            f"cannot write the output folder {out}: {exc.strerror or exc}; choose another --out"
        ) from None


def _read_lines(path: Path) -> Iterator[dict]:
    """The complete records of a progress file (a torn or unreadable line ends it)."""
    if not path.is_file():
        return
    with open(path, encoding="utf-8") as f:
        for line in f:
            if not line.endswith("\n"):
                return  # torn by an interruption: that instruction runs again
            try:
                record = json.loads(line)
            except ValueError:
                return
            if not isinstance(record, dict) or "split" not in record or "instr_id" not in record:
                return
            yield record
