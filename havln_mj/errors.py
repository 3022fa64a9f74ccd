"""Every error havln_mj raises on bad input.

Each class also derives from the built-in exception a caller would expect (``ValueError``,
``KeyError``, ``FileNotFoundError``, ...), so code written against MatterSim or plain Python
keeps working. Messages name the bad value and what would be valid.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable


class HavlnError(Exception):
    """Base class of all havln_mj errors."""


class InvalidArgumentError(HavlnError, ValueError):
    """An argument has a value outside its valid range or set."""


class UnknownSceneError(HavlnError, ValueError):
    """A scene id that is neither a valid procedural id nor a known scan."""


class UnknownScanError(UnknownSceneError, IndexError):
    """A scan id the simulator has no navigation graph for (MatterSim raises IndexError)."""


class UnknownViewpointError(HavlnError, ValueError):
    """A viewpoint id that is not in the scan's navigation graph (or is excluded)."""


class BatchSizeError(InvalidArgumentError, IndexError):
    """A batched argument whose length is not the batch size (MatterSim raises IndexError)."""


class InvalidActionError(InvalidArgumentError):
    """An action index outside the current navigable locations, or a non-finite turn."""


class NotInitializedError(HavlnError, RuntimeError):
    """A simulator call that needs ``initialize``/``newEpisode`` first (MatterSim: RuntimeError)."""


class MalformedDataError(HavlnError, ValueError):
    """A data file (JSON, mesh, cache entry) does not follow its schema."""


class CorruptMeshError(MalformedDataError):
    """A mesh file cannot be read or holds no usable triangles."""


class FrameMismatchError(MalformedDataError):
    """A user's files disagree on the coordinate frame (viewpoints do not stand on the mesh)."""


class MissingDataError(HavlnError, FileNotFoundError):
    """A file the user must supply (or a built scan) is not where it was looked for."""


class RenderingUnavailableError(HavlnError, RuntimeError):
    """No OpenGL backend (EGL or OSMesa) could be started."""


class OutputError(HavlnError, OSError):
    """An output (a run folder, a video, a result file) cannot be written or finished."""


class ClosedError(HavlnError, RuntimeError):
    """A resource (a camera, a video writer) used after it was closed."""


class DependencyNotInstalledError(HavlnError, ImportError):
    """An optional extra (torch, ray, gymnasium, ...) is needed but not installed."""


def nearest(value: str, candidates: Iterable[str], n: int = 1) -> list[str]:
    """Returns up to ``n`` candidates closest to ``value`` (difflib ratio), best first."""
    return difflib.get_close_matches(value, list(candidates), n=n, cutoff=0.4)


def did_you_mean(value: str, candidates: Iterable[str]) -> str:
    """Returns a " Did you mean 'x'?" suffix, or an empty string when nothing is close."""
    match = nearest(value, candidates)
    return f" Did you mean {match[0]!r}?" if match else ""
