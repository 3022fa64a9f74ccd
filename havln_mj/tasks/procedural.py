"""R2R-like episodes for our own scans (procedural houses, graph proxies), in HA-R2R's schema.

Paths are shortest paths of 4–7 viewpoints and 5–20 m, as R2R's. People are the scan's crowd
exactly as :class:`havln_mj.sim.simulator.Simulator` with ``humans=True`` places them for the
same seed (``populate(scan, default_rng([seed, crc32(scan id)]))``), so the dataset's
``human`` entries name the viewpoints the simulator's people stand on. Their relative
positions and the crux points follow HA3D's rules (:mod:`havln_mj.tasks.annotate`), and each
path gets three instructions from :mod:`havln_mj.tasks.instructions`.

:func:`build_split` writes ``HA_<split>.json`` (read it with
:func:`havln_mj.tasks.datasets.load_dataset`) and ``vocab_<split>.txt``: one token per line,
``token<TAB>count``, most frequent first (ties alphabetical), counting :func:`tokenize` tokens
of every instruction.
"""

from __future__ import annotations

import dataclasses
import math
import re
import zlib
from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from tqdm import tqdm

from havln_mj.cache import atomic_write_bytes
from havln_mj.errors import InvalidArgumentError
from havln_mj.humans.catalog import Catalog, load_catalog
from havln_mj.humans.crowd import Crowd
from havln_mj.scene.navgraph import NavGraph
from havln_mj.scene.scan import Scan, load_scan
from havln_mj.tasks.annotate import crux_points
from havln_mj.tasks.datasets import SPLITS, write_dataset
from havln_mj.tasks.episodes import Episode
from havln_mj.tasks.instructions import generate_instructions, tokenize
from havln_mj.tasks.route_facts import describe_route

MIN_VIEWPOINTS, MAX_VIEWPOINTS = 4, 7  # R2R's path sizes
MIN_DISTANCE, MAX_DISTANCE = 5.0, 20.0  # metres
INSTRUCTIONS_PER_PATH = 3
PATH_ID_STRIDE = 1_000_000  # path ids of split k start at (k + 1) * stride; scenes 10_000 apart
SCENE_STRIDE = 10_000
_SPLIT_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_\-]*")


def scene_rng(seed: int, scan_id: str, *stream: int) -> np.random.Generator:
    """A scan's generator, independent of the order scans are visited in.

    With no ``stream`` this is the simulator's crowd generator for ``scan_id`` and ``seed``.
    """
    return np.random.default_rng([int(seed), zlib.crc32(scan_id.encode()), *stream])


def scene_crowd(scan: Scan, seed: int, catalog: Catalog | None = None) -> Crowd:
    """The people ``Simulator(humans=True)`` places in ``scan`` after ``setSeed(seed)``.

    A scan without regions (nothing says which rooms people belong in) has no people.
    """
    if scan.regions is None:
        return Crowd([])
    from havln_mj.humans.population import populate

    return populate(scan, scene_rng(seed, scan.scene_id), catalog=catalog)


def candidate_paths(graph: NavGraph) -> list[tuple[str, ...]]:
    """Every R2R-like shortest path of the graph: 4–7 viewpoints, 5–20 m (node order)."""
    dist = graph.distance_matrix()
    nodes = graph.nodes
    out = []
    for i, a in enumerate(nodes):
        for j, b in enumerate(nodes):
            if i != j and MIN_DISTANCE <= dist[i, j] <= MAX_DISTANCE:
                path = graph.shortest_path(a, b)
                if MIN_VIEWPOINTS <= len(path) <= MAX_VIEWPOINTS:
                    out.append(tuple(path))
    return out


def sample_paths(graph: NavGraph, n: int, rng: np.random.Generator) -> list[tuple[str, ...]]:
    """Up to ``n`` distinct R2R-like paths, drawn without replacement (fewer if fewer exist).

    Raises:
        InvalidArgumentError: The graph has no such path at all.
    """
    paths = candidate_paths(graph)
    if not paths:
        raise InvalidArgumentError(
            f"scan {graph.name!r} has no shortest paths of {MIN_VIEWPOINTS}–{MAX_VIEWPOINTS} "
            f"viewpoints and {MIN_DISTANCE:g}–{MAX_DISTANCE:g} m; use a larger scene"
        )
    return [paths[int(k)] for k in rng.permutation(len(paths))[:n]]


def scene_episodes(
    scan: Scan,
    n: int,
    seed: int,
    first_path_id: int = 0,
    catalog: Catalog | None = None,
    skip: int = 0,
) -> list[Episode]:
    """Up to ``n`` HA-R2R episodes in one scan.

    Episode ``k`` depends only on the scan, the seed and ``k``, so ``skip`` gives a split of
    other paths in the same houses with the same people (e.g. val_seen after train's first
    ``skip``).

    Args:
        scan: The building.
        n: Paths wanted (fewer when the scan has fewer R2R-like paths).
        seed: The dataset seed; the people are the simulator's for this seed.
        first_path_id: ``path_id`` of the first episode; the others follow.
        catalog: The activity catalog (default: the built-in one).
        skip: Leave out the scan's first ``skip`` episodes (they belong to another split).

    Raises:
        InvalidArgumentError: ``n`` is below 1, ``skip`` below 0, or the scan has no
            R2R-like path.
    """
    if n < 1:
        raise InvalidArgumentError(f"episodes per scene must be at least 1, got {n}")
    if skip < 0:
        raise InvalidArgumentError(f"episodes to skip must be at least 0, got {skip}")
    catalog = catalog or load_catalog()
    crowd = scene_crowd(scan, seed, catalog)
    rng = scene_rng(seed, scan.scene_id, 1)  # paths and wording: a stream apart from people
    out = []
    for k, path in enumerate(sample_paths(scan.graph, n + skip, rng)):
        heading = float(rng.uniform(0.0, 2 * math.pi))
        route = describe_route(scan, path, heading, crowd, catalog)
        instructions, about_people = generate_instructions(route, rng, INSTRUCTIONS_PER_PATH)
        if k < skip:
            continue
        out.append(
            Episode(
                path_id=first_path_id + k - skip,
                scan=scan.scene_id,
                path=path,
                heading=round(heading, 6),
                instructions=instructions,
                distance=round(route.distance, 2),
                humans=route.humans,
                crux_points=crux_points(path, scan.graph),
                rel_pos_descriptions=about_people if route.people else None,
            )
        )
    return out


def procedural_episodes(
    scenes: Sequence[str], per_scene: int, seed: int, skip: int = 0, first_id: int = SCENE_STRIDE
) -> list[Episode]:
    """Episodes of several procedural scenes (the evaluation harness's ``--scenes``).

    Scene ``s`` (in the given order) gets path ids from ``first_id + 10_000 * s``; ``skip``
    leaves out each scene's first paths (another split's: val_seen after train). Episodes name
    their scene as given (a scan folder by its path), so the simulator finds it again.
    """
    out: list[Episode] = []
    for s, scene in enumerate(scenes):
        first = first_id + SCENE_STRIDE * s
        scan = load_scan(scene)
        if scan.scene_id != scene:
            scan = dataclasses.replace(scan, scene_id=scene)
        out += scene_episodes(scan, per_scene, seed, first_path_id=first, skip=skip)
    return out


def split_path_id_base(split: str) -> int:
    """First ``path_id`` of a split: ``(k + 1) * PATH_ID_STRIDE`` for the k-th of ``SPLITS``.

    Other names get a base from their CRC-32 in 10..99 strides, so ids rarely collide.
    """
    if split in SPLITS:
        return (SPLITS.index(split) + 1) * PATH_ID_STRIDE
    return (10 + zlib.crc32(split.encode()) % 90) * PATH_ID_STRIDE


def vocabulary(episodes: Iterable[Episode]) -> Counter[str]:
    """Token counts over every instruction (:func:`~havln_mj.tasks.instructions.tokenize`)."""
    counts: Counter[str] = Counter()
    for e in episodes:
        for text in e.instructions:
            counts.update(tokenize(text))
    return counts


def write_vocab(counts: Counter[str], path: Path) -> None:
    """Writes ``token<TAB>count`` lines, most frequent first, ties alphabetical (atomically)."""
    rows = sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))
    atomic_write_bytes(path, "".join(f"{t}\t{c}\n" for t, c in rows).encode("utf-8"))


def read_vocab(path: str | Path) -> dict[str, int]:
    """Reads a vocabulary file written by :func:`write_vocab`: token → count."""
    out = {}
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        token, _, count = line.partition("\t")
        out[token] = int(count)
    return out


@dataclass(frozen=True)
class BuiltSplit:
    """What :func:`build_split` wrote.

    Attributes:
        dataset: The ``HA_<split>.json`` file.
        vocab: The ``vocab_<split>.txt`` file.
        episodes: The episodes, in file order.
    """

    dataset: Path
    vocab: Path
    episodes: tuple[Episode, ...]

    def word_counts(self) -> list[int]:
        """Words (whitespace-separated) of every instruction."""
        return [len(t.split()) for e in self.episodes for t in e.instructions]


def build_split(
    scenes: Sequence[str],
    split_name: str,
    episodes_per_scene: int,
    seed: int,
    out_dir: str | Path,
    *,
    progress: bool = True,
) -> BuiltSplit:
    """Generates a split over ``scenes`` and writes its dataset and vocabulary files.

    Scene ``i`` (in the given order) gets path ids from ``split_path_id_base(split_name) +
    i * SCENE_STRIDE``. Each scene's paths, wording and people depend only on ``seed`` and
    its id, so a scene's episodes are the same in any list of scenes.

    Args:
        scenes: Scene ids (``proc-<seed>``, scan ids, scan folders); no repeats.
        split_name: Names the files ``HA_<split>.json`` and ``vocab_<split>.txt``.
        episodes_per_scene: Paths per scene (fewer where a scene has fewer).
        seed: The seed; ``Simulator(humans=True)`` with ``setSeed(seed)`` has the same people.
        out_dir: Output folder (created).
        progress: Show a progress bar.

    Raises:
        InvalidArgumentError: No scenes, repeated scenes, a bad split name or count, or a
            scene without R2R-like paths.
        UnknownSceneError: A scene id is not valid (before anything is written).
    """
    scenes = list(scenes)
    if not scenes:
        raise InvalidArgumentError("no scenes given (e.g. proc-0 proc-1)")
    repeated = sorted({s for s in scenes if scenes.count(s) > 1})
    if repeated:
        raise InvalidArgumentError(f"scenes are listed more than once: {', '.join(repeated)}")
    if not _SPLIT_NAME.fullmatch(split_name):
        raise InvalidArgumentError(
            f"split name must be letters, digits, '_' or '-' (e.g. {', '.join(SPLITS)}), "
            f"got {split_name!r}"
        )
    if episodes_per_scene < 1 or episodes_per_scene > SCENE_STRIDE:
        raise InvalidArgumentError(
            f"episodes per scene must be in 1–{SCENE_STRIDE}, got {episodes_per_scene}"
        )
    if len(scenes) * SCENE_STRIDE > PATH_ID_STRIDE:
        raise InvalidArgumentError(
            f"at most {PATH_ID_STRIDE // SCENE_STRIDE} scenes per split, got {len(scenes)}"
        )
    scans = [load_scan(s) for s in scenes]  # every id checked before any work
    catalog = load_catalog()
    base = split_path_id_base(split_name)
    episodes: list[Episode] = []
    for i, scan in enumerate(tqdm(scans, desc=split_name, unit="scene", disable=not progress)):
        first = base + i * SCENE_STRIDE
        episodes += scene_episodes(scan, episodes_per_scene, seed, first, catalog)
    out = Path(out_dir)
    dataset, vocab = out / f"HA_{split_name}.json", out / f"vocab_{split_name}.txt"
    write_dataset(episodes, dataset)
    write_vocab(vocabulary(episodes), vocab)
    return BuiltSplit(dataset, vocab, tuple(episodes))
