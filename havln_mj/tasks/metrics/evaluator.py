"""Runs measures over episodes in dependency order and summarises the results."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field

from havln_mj.errors import InvalidArgumentError, UnknownScanError, did_you_mean
from havln_mj.scene.navgraph import NavGraph
from havln_mj.tasks.metrics.config import MetricConfig
from havln_mj.tasks.metrics.episode import EvalEpisode
from havln_mj.tasks.metrics.measures import EpisodeContext, Measure, default_measures

GraphSource = NavGraph | Mapping[str, NavGraph] | Callable[[str], NavGraph]


def resolve_order(wanted: Iterable[str], available: Mapping[str, Measure]) -> list[Measure]:
    """Returns the wanted measures and everything they need, dependencies first.

    Args:
        wanted: Names of the measures to compute.
        available: Every measure that may be pulled in, by name.

    Raises:
        InvalidArgumentError: A name (wanted or required) is not available, or the
            ``requires`` links form a cycle (the message shows it).
    """
    order: list[Measure] = []
    done: set[str] = set()
    stack: list[str] = []  # the chain being resolved, to report cycles

    def visit(name: str, needed_by: str | None) -> None:
        if name in done:
            return
        if name in stack:
            cycle = [*stack[stack.index(name) :], name]
            raise InvalidArgumentError(f"measures depend on each other: {' -> '.join(cycle)}")
        if name not in available:
            who = f"required by {needed_by!r}" if needed_by else "requested"
            raise InvalidArgumentError(
                f"unknown measure {name!r} ({who}); available: {sorted(available)}"
                f"{did_you_mean(name, available)}"
            )
        stack.append(name)
        for dep in available[name].requires:
            visit(dep, name)
        stack.pop()
        done.add(name)
        order.append(available[name])

    for name in wanted:
        visit(name, None)
    return order


@dataclass(frozen=True)
class EvaluationResult:
    """Scores of a list of episodes.

    Attributes:
        per_episode: One dict per episode, in input order: ``episode_id`` and every measure.
        summary: Each measure aggregated over episodes (means), plus ``episodes`` (count).
    """

    per_episode: list[dict[str, float | str]] = field(default_factory=list)
    summary: dict[str, float] = field(default_factory=dict)


class Evaluator:
    """Scores episodes with a set of measures.

    Example:
        >>> ev = Evaluator()                                       # doctest: +SKIP
        >>> result = ev.evaluate(episodes, {"17DRP5sb8fy": graph})  # doctest: +SKIP
        >>> result.summary["sr"], result.per_episode[0]["tcr"]      # doctest: +SKIP
    """

    def __init__(
        self,
        measures: Iterable[str | Measure] | None = None,
        config: MetricConfig | None = None,
    ) -> None:
        """Chooses what to compute.

        Args:
            measures: Measure names (from the defaults) and/or ``Measure`` objects (which add
                to, or replace same-named, defaults). None computes all default measures.
                Dependencies are pulled in automatically.
            config: Thresholds and collision rule; defaults to ``MetricConfig()``.

        Raises:
            InvalidArgumentError: An unknown measure, a cycle, or an item that is neither a
                name nor a ``Measure``.
        """
        self.config = config if config is not None else MetricConfig()
        if not isinstance(self.config, MetricConfig):
            raise InvalidArgumentError(f"config must be a MetricConfig, got {config!r}")
        available = default_measures()
        wanted: list[str] = []
        for item in available.values() if measures is None else measures:
            if isinstance(item, Measure):
                available[item.name] = item
                wanted.append(item.name)
            elif isinstance(item, str):
                wanted.append(item)
            else:
                raise InvalidArgumentError(
                    f"measures must hold names or Measure objects, got {item!r}"
                )
        self.measures: list[Measure] = resolve_order(wanted, available)

    @property
    def names(self) -> list[str]:
        """Names of the measures computed, in computation order."""
        return [m.name for m in self.measures]

    def score(self, episode: EvalEpisode, graph: NavGraph) -> dict[str, float]:
        """Computes every measure for one episode.

        Raises:
            UnknownViewpointError: A viewpoint of the episode is not in ``graph``.
            InvalidArgumentError: The goal cannot be reached from the start.
        """
        ctx = EpisodeContext(episode, graph, self.config)
        for measure in self.measures:
            ctx._allowed, ctx._reader = frozenset(measure.requires), measure.name
            ctx.values[measure.name] = float(measure.compute(ctx))
        return dict(ctx.values)

    def evaluate(self, episodes: Iterable[EvalEpisode], graphs: GraphSource) -> EvaluationResult:
        """Scores episodes and summarises them.

        Args:
            episodes: The episodes to score.
            graphs: One ``NavGraph`` for all episodes, a mapping scan id -> graph, or a
                function scan id -> graph (e.g. a cached loader).

        Raises:
            InvalidArgumentError: No episodes, or an item is not an ``EvalEpisode``.
            UnknownScanError: ``graphs`` is a mapping without an episode's scan.
        """
        rows: list[dict[str, float | str]] = []
        columns: dict[str, list[float]] = {m.name: [] for m in self.measures}
        for i, ep in enumerate(episodes):
            if not isinstance(ep, EvalEpisode):
                raise InvalidArgumentError(f"episode {i} is not an EvalEpisode: {ep!r}")
            values = self.score(ep, _graph_for(ep.scan, graphs))
            for name, value in values.items():
                columns[name].append(value)
            rows.append({"episode_id": ep.episode_id, **values})
        if not rows:
            raise InvalidArgumentError("no episodes to evaluate")
        summary = {m.name: m.aggregate(columns[m.name]) for m in self.measures}
        summary["episodes"] = float(len(rows))
        return EvaluationResult(rows, summary)


def evaluate(
    episodes: Sequence[EvalEpisode],
    graphs: GraphSource,
    config: MetricConfig | None = None,
) -> EvaluationResult:
    """Scores episodes with all default measures (shorthand for ``Evaluator``)."""
    return Evaluator(config=config).evaluate(episodes, graphs)


def _graph_for(scan: str, graphs: GraphSource) -> NavGraph:
    if isinstance(graphs, NavGraph):
        return graphs
    if isinstance(graphs, Mapping):
        if scan not in graphs:
            raise UnknownScanError(
                f"no navigation graph for scan {scan!r}; graphs given for {sorted(graphs)}"
                f"{did_you_mean(scan, graphs)}"
            )
        return graphs[scan]
    if callable(graphs):
        return graphs(scan)
    raise InvalidArgumentError(
        f"graphs must be a NavGraph, a mapping scan -> NavGraph or a callable, got {graphs!r}"
    )
