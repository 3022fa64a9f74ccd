"""CoACD's settings for decomposing buildings, each checked, and the installed CoACD's version.

:class:`CoacdParams` is part of the hull cache key of :mod:`havln_mj.scene.collision`
(:meth:`CoacdParams.to_json`) and is turned into the keyword arguments the installed CoACD
accepts (:meth:`CoacdParams.coacd_kwargs`).
"""

from __future__ import annotations

import dataclasses
import importlib.metadata
import inspect
import json
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from havln_mj.errors import InvalidArgumentError


@dataclass(frozen=True)
class CoacdParams:
    """CoACD settings; the field names and meanings are those of ``coacd.run_coacd``.

    Defaults are tuned for buildings in metres: the concavity threshold is 0.1 m in real-metric
    mode instead of CoACD's normalised 0.05, which on a 10 x 8 m house is ~0.6 m of slack and
    lets hulls bridge door gaps and fill the space between furniture and walls. The rest are
    CoACD's published defaults (remesh resolution 50, MCTS 100 iterations / depth 3 / 20 nodes)
    with a fixed seed, so results are reproducible and cacheable. On a 10 x 8 m 4-room house
    (2 cores) this takes about a minute and gives ~140 hulls; ``mcts_iterations=40,
    mcts_max_depth=2, mcts_nodes=10`` gives a similar fit in about a third of the time. The
    non-manifold remesh inflates surfaces by about 1/180 of the mesh's size (~5 cm for a 10 m
    house) and raising ``preprocess_resolution`` reduces it at a cost in time.

    Attributes:
        threshold: Concavity at which a piece stops being split; lower gives more, tighter hulls.
            Metres when ``real_metric`` is true, else CoACD's normalised units in (0, 1].
        max_convex_hull: Cap on the number of hulls (only with ``merge``), -1 for no cap.
        preprocess_mode: Manifold remesh: "auto" (only for non-manifold input), "on", "off".
        preprocess_resolution: Voxel resolution of the manifold remesh; higher is tighter, slower.
        resolution: Surface samples for the Hausdorff distance.
        mcts_nodes: Child nodes per MCTS node.
        mcts_iterations: MCTS search iterations.
        mcts_max_depth: MCTS search depth.
        pca: Align the mesh with its principal axes before cutting.
        merge: Merge adjacent hulls whose union stays under the threshold.
        decimate: Limit each hull to ``max_ch_vertex`` vertices.
        max_ch_vertex: Vertex cap per hull (only with ``decimate``).
        extrude: Extrude neighbouring hulls along their shared faces.
        extrude_margin: Extrusion distance (only with ``extrude``).
        apx_mode: Shape of the pieces: "ch" (convex hulls) or "box".
        real_metric: Read ``threshold`` in metres (the mesh must be in metres); needs
            coacd >= 1.0.14.
        seed: Random seed of CoACD's sampling.
    """

    threshold: float = 0.1
    max_convex_hull: int = -1
    preprocess_mode: str = "auto"
    preprocess_resolution: int = 50
    resolution: int = 2000
    mcts_nodes: int = 20
    mcts_iterations: int = 100
    mcts_max_depth: int = 3
    pca: bool = False
    merge: bool = True
    decimate: bool = False
    max_ch_vertex: int = 256
    extrude: bool = False
    extrude_margin: float = 0.01
    apx_mode: str = "ch"
    real_metric: bool = True
    seed: int = 0

    def __post_init__(self) -> None:
        """Checks every field's type and range.

        Raises:
            InvalidArgumentError: A field is out of range; the message names field and value.
        """
        metres = isinstance(self.real_metric, bool | np.bool_) and bool(self.real_metric)
        thr_hi = math.inf if metres else 1.0
        _check_float("threshold", self.threshold, 0.0, thr_hi, "(0, 1]" if thr_hi == 1.0 else "> 0")
        _check_int("max_convex_hull", self.max_convex_hull, -1, 10**6, "-1 (no cap) or 1..1000000")
        if self.max_convex_hull == 0:
            _bad("max_convex_hull", 0, "-1 (no cap) or 1..1000000")
        _check_choice("preprocess_mode", self.preprocess_mode, ("auto", "on", "off"))
        _check_int("preprocess_resolution", self.preprocess_resolution, 5, 1000)
        _check_int("resolution", self.resolution, 100, 10**6)
        _check_int("mcts_nodes", self.mcts_nodes, 1, 1000)
        _check_int("mcts_iterations", self.mcts_iterations, 1, 10**6)
        _check_int("mcts_max_depth", self.mcts_max_depth, 1, 20)
        _check_int("max_ch_vertex", self.max_ch_vertex, 4, 10**6)
        _check_float("extrude_margin", self.extrude_margin, 0.0, math.inf, ">= 0", low_open=False)
        _check_choice("apx_mode", self.apx_mode, ("ch", "box"))
        _check_int("seed", self.seed, 0, 2**32 - 1)
        for name in ("pca", "merge", "decimate", "extrude", "real_metric"):
            value = getattr(self, name)
            if not isinstance(value, bool | np.bool_):
                _bad(name, value, "True or False")

    def to_json(self) -> str:
        """Returns a canonical JSON form (sorted keys, plain types), part of the cache key."""
        return json.dumps(self._plain(), sort_keys=True, separators=(",", ":"))

    def coacd_kwargs(self) -> dict[str, Any]:
        """Returns keyword arguments for the installed ``coacd.run_coacd``.

        Raises:
            InvalidArgumentError: A field is set away from its default but the installed CoACD
                does not accept it.
        """
        import coacd  # a large import: only when meshes are decomposed

        accepted = inspect.signature(coacd.run_coacd).parameters
        takes_any = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in accepted.values())
        kwargs = {}
        for name, value in self._plain().items():
            if takes_any or name in accepted:
                kwargs[name] = value
            elif value != _IMPLICIT.get(name, _FIELD_DEFAULTS[name]):
                neutral = _IMPLICIT.get(name, _FIELD_DEFAULTS[name])
                raise InvalidArgumentError(
                    f"CoacdParams.{name}={value!r} is not supported by the installed coacd "
                    f"{coacd_version()}; set it to {neutral!r} or upgrade coacd (>= 1.0.14)"
                )
        return kwargs

    def _plain(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if isinstance(value, bool | np.bool_):
                out[f.name] = bool(value)
            elif isinstance(value, float | np.floating):
                out[f.name] = float(value)
            elif isinstance(value, int | np.integer):
                out[f.name] = int(value)
            else:
                out[f.name] = value
        return out


_FIELD_DEFAULTS = {f.name: f.default for f in dataclasses.fields(CoacdParams)}
# What an older coacd that lacks a parameter does implicitly, where that is not our default.
_IMPLICIT: dict[str, Any] = {"real_metric": False}


def _bad(name: str, value: Any, valid: str) -> None:
    raise InvalidArgumentError(f"CoacdParams.{name}={value!r} is invalid; valid: {valid}")


def _check_int(name: str, value: Any, lo: int, hi: int, valid: str | None = None) -> None:
    valid = valid or f"an integer in {lo}..{hi}"
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | np.integer):
        _bad(name, value, valid)
    if not lo <= value <= hi:
        _bad(name, value, valid)


def _check_float(
    name: str, value: Any, lo: float, hi: float, valid: str, *, low_open: bool = True
) -> None:
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | float | np.number):
        _bad(name, value, f"a number {valid}")
    v = float(value)
    if not math.isfinite(v) or v > hi or v < lo or (low_open and v == lo):
        _bad(name, value, f"a finite number {valid}")


def _check_choice(name: str, value: Any, choices: tuple[str, ...]) -> None:
    if value not in choices:
        _bad(name, value, ", ".join(repr(c) for c in choices))


def coacd_version() -> str:
    """The installed CoACD's version ("unknown" when its metadata is missing)."""
    try:
        return importlib.metadata.version("coacd")
    except importlib.metadata.PackageNotFoundError:
        return "unknown"
