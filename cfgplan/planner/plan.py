"""The planner's entry point: the cheapest admissible configurations, ranked.

A :class:`Run` puts the parts together: the grounding memo and the bounds of
the task (kept per task, so that planning the same task again, e.g. ``-k 1``
then ``--all``, grounds and summarises once), the strategy — best-first
search for the ``limit`` cheapest (:mod:`cfgplan.planner.search`), or, when
the goal's choices fall into independent parts, each part searched so and
the parts combined (:mod:`cfgplan.planner.combine`), windows of depth-first
walks to list them all in bounded memory (:mod:`cfgplan.planner.enumerate`)
— the time limit, the greedy dive when a
search is stopped before it has proven anything, and, when nothing is
admissible, a search without the bounds to say why. Configurations come out
of a run as they are proven, so a caller may print them at once;
:func:`plan` collects them.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from functools import partial
from typing import TYPE_CHECKING

from cfgplan.configuration.model import Configuration
from cfgplan.planner import clock
from cfgplan.planner.bound import Bound
from cfgplan.planner.components import Parts, divide, unroll
from cfgplan.planner.ground import Grounder
from cfgplan.planner.grow import Grower
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.partial import Partial, root
from cfgplan.planner.partition import Partition
from cfgplan.planner.prefix import Prefix
from cfgplan.planner.pricer import Heuristic, Pricer, Splitter
from cfgplan.planner.report import Report, Stats, StopReason
from cfgplan.planner.search import BestFirst, Progress
from cfgplan.planner.split import Split
from cfgplan.planner.task import Ground, Task

if TYPE_CHECKING:  # each loaded where it is used: most runs use none (start-up)
    from cfgplan.planner.combine import Combined
    from cfgplan.planner.enumerate import Windows


def parts(task: Task, media: bool = True) -> tuple[Grounder, Bound, Partition]:
    """The grounding memo and the bounds of ``task``, made once per task and
    kept on it (:attr:`Task.memo`): they are freed with the task, as a run that
    reconfigures plans on one derived task after another. ``media``:
    :attr:`SearchOptions.media` (a partitioned bound each way)."""
    key = "parts" if media else "parts-without-media"
    found: tuple[Grounder, Bound, Partition] | None = task.memo.get(key)
    if found is None:
        grounder = Grounder(task)
        partition = Partition(grounder, media)
        found = task.memo[key] = (grounder, Bound(task, grounder, media), partition)
    return found


def divided(task: Task, goal: Ground, media: bool = True) -> Parts | None:
    """The goal's independent parts (:mod:`cfgplan.planner.components`), made
    once per task and goal; None when there are not two, or when costs have
    no unit (:mod:`cfgplan.planner.levels`: then sums of parts may not rank
    as whole configurations do). ``media``: as :func:`parts`."""
    key = "components" if media else "components-without-media"
    made: dict[Ground, Parts | None] = task.memo.setdefault(key, {})
    if goal not in made:
        found = None
        if task.levels.unit is not None:
            grounder, _, partition = parts(task, media)
            unrolled = unroll(grounder, goal)
            if unrolled is not None:
                found = divide(grounder, partition, *unrolled)
        made[goal] = found if found is not None and len(found.parts) > 1 else None
    return made[goal]


def combined(bound: Bound, partition: Partition) -> Heuristic:
    """The larger of the two admissible bounds (a maximum of lower bounds is one)."""

    def estimate(node: Partial) -> float | None:
        first = bound.estimate(node)
        if first is None:
            return None
        second = partition.estimate(node, bound.certain_agents(node))
        return None if second is None else max(first, second)

    return estimate


def partitioned(bound: Bound, partition: Partition) -> Heuristic:
    """The partitioned bound, with the agents ``bound`` knows to be certain:
    the strategies refine their priorities with it, lazily."""

    def estimate(node: Partial) -> float | None:
        return partition.estimate(node, bound.certain_agents(node))

    return estimate


def splitting(bound: Bound, partition: Partition) -> Splitter:
    """:func:`partitioned`, taken apart at the top item for the children
    (:mod:`cfgplan.planner.split`)."""

    def split(node: Partial) -> tuple[float | None, Split | None]:
        return partition.split(node, bound.certain_agents(node))

    return split


def growing(
    task: Task,
    options: SearchOptions,
    distinct: bool = True,
    given: frozenset[int] = frozenset(),
    splits: bool = True,
    replays: bool = False,
) -> tuple[Grower, Pricer]:
    """A grower for ``task`` and a pricer with the task's bounds
    (:func:`parts`), children priced from splits (unless ``splits`` is
    False, or :attr:`SearchOptions.splits` is); ``given``:
    :attr:`Grower.given`. Every strategy's grower and pricer are made here."""
    grounder, bound, partition = parts(task, options.media)
    made = Grower(grounder, distinct, given, options=options, replays=replays and options.replays)
    pricer = Pricer(
        task.levels,
        bound.estimator(options),
        partitioned(bound, partition),
        bound.feasible,
        splitting(bound, partition) if splits and options.splits else None,
        options,
        made.stats,
    )
    return made, pricer


def in_parts(
    search: BestFirst, task: Task, options: SearchOptions, progress: Progress | None = None
) -> BestFirst | Combined:
    """``search``, or, when its goal has independent parts
    (:func:`divided`; :attr:`SearchOptions.components`), those parts searched
    apart and combined (:class:`~cfgplan.planner.combine.Combined`), handing over
    to ``search`` if the parts do not combine as assumed.
    Found under the time limit: should it pass, ``search`` is kept, and stops
    at once. Every ranked listing (a run's ``-k``, a sequence's steps) is
    assembled so."""
    if not options.components:
        return search
    try:
        found = divided(task, search.goal, options.media)
    except clock.OutOfTime:
        return search
    if found is None:
        return search
    from cfgplan.planner.combine import Combined

    distinct = search.grower.distinct

    def make(given: frozenset[int]) -> tuple[Grower, Pricer]:
        return growing(task, options, distinct, given)

    return Combined(search.grower, search.pricer, search.goal, found, make, progress)


def _no_bound(node: Partial) -> float:
    return 0.0


def _order(entry: tuple[float, Partial]) -> tuple[float, tuple[int, ...]]:
    return entry[0], entry[1].path


@dataclass(eq=False, repr=False)
class Run:
    """One planning run; iterate it for the configurations, best first."""

    task: Task
    goal: Ground
    limit: int | None = 1
    distinct: bool = True
    time_limit: float | None = None
    progress: Progress | None = None
    started: float | None = None
    """When the time limit started counting (perf_counter; default: now)."""
    ahead: bool = False
    """Once ``limit`` configurations are listed, look for one more (not
    listed) to say whether more exist (:attr:`more`), with bounded work
    (:mod:`cfgplan.planner.prefix`): ``-k 1`` never runs to the end of a
    search to prove there is no second configuration."""
    options: SearchOptions = field(default_factory=SearchOptions)
    """The strategies' settings and switches (parts apart, the look-ahead's
    least work, ...), given to every grower of the run."""
    more: bool | None = field(init=False, default=False)
    solved: bool = field(init=False, default=False)
    """The solver's bracket closed (:attr:`SearchOptions.solver`)."""
    """With :attr:`ahead`: :attr:`cfgplan.planner.prefix.Prefix.more`."""
    strategy: BestFirst | Combined | Windows = field(init=False)
    explained: Report | None = field(init=False, default=None)
    """Why nothing was found, when the bounds cut the dead ends before the
    search met them (:meth:`_explain`): the report of a search without them."""

    def __post_init__(self) -> None:
        ranked = self.limit is not None
        made, pricer = growing(
            self.task, self.options, self.distinct, splits=ranked, replays=ranked
        )
        if self.limit is None:
            from cfgplan.planner.enumerate import Windows

            bound = parts(self.task, self.options.media)[1]
            self.strategy = Windows(made, pricer, self.goal, bound.feasible, self.progress)
        else:
            self.strategy = BestFirst(made, pricer, self.goal, self.progress)

    def _search(self) -> Iterator[Configuration]:
        """The configurations, cheapest first: the goal's parts apart, if it has some."""
        if self.options.solver and self.limit == 1 and isinstance(self.strategy, BestFirst):
            solved = self._solved()
            if solved is not None:
                yield solved
                return
        self._divide()
        yield from self.strategy

    def _solved(self) -> Configuration | None:
        """:attr:`SearchOptions.solver`: the first cheapest configuration by the
        solver's bracket and walk, or None (the bracket did not close within
        half the time limit, or nothing is admissible: the search goes on from
        the start, and says why nothing is). What comes after it is not looked
        for (:attr:`more` is None)."""
        from cfgplan.planner import solver

        grower = self.strategy.grower
        left = clock.remaining()
        try:  # the bracket takes at most half of a time limit, the search has the rest
            found = solver.bracket(grower.grounder, self.goal, None if left is None else left / 2)
            if not found.exact or found.upper is None:
                # Open, or nothing admissible: the search says why (its dead ends).
                return None
            config = solver.first(grower, self.goal, found.lower)
        except (solver.Unsupported, clock.OutOfTime):
            return None  # the search goes on (and stops at once when out of time)
        self.solved = config is not None
        return config

    def _divide(self) -> None:
        """Search the goal's independent parts apart, if it has some (:func:`in_parts`)."""
        if isinstance(self.strategy, BestFirst):
            self.strategy = in_parts(self.strategy, self.task, self.options, self.progress)

    @property
    def stats(self) -> Stats:
        return self.strategy.stats

    @property
    def report(self) -> Report:
        return self.strategy.report if self.explained is None else self.explained

    @property
    def stopped(self) -> StopReason | None:
        return self.strategy.stopped

    def __iter__(self) -> Iterator[Configuration]:
        started = time.perf_counter() if self.started is None else self.started
        deadline = None if self.time_limit is None else started + self.time_limit
        prefix: Prefix[Configuration] = Prefix(self.limit, self.ahead, self.options.ahead_least)
        listed = 0
        try:
            with clock.limit(deadline):
                for config in prefix.take(self._search()):
                    listed += 1
                    yield config
            self.more = None if self.solved and listed else prefix.more
            if prefix.cut:
                self.stats.complete = False
        except KeyboardInterrupt:
            self.stats.complete = False
            self.strategy.stopped = StopReason.INTERRUPTED
        if self.stopped is not None and not listed:
            guess = self._dive(deadline)
            if guess is not None:
                yield guess
            else:  # nothing found, nothing proved
                self.report.unfinished = self.report.undecided = True
            return
        if not listed and self.stats.pruned and self.stats.complete:
            self._explain(started, deadline)

    def _dive(self, deadline: float | None) -> Configuration | None:
        """Stopped before anything was proven: dive for any configuration
        (unless :attr:`SearchOptions.dive` is off)."""
        if not self.options.dive:
            return None
        from cfgplan.planner.dive import dive

        grace = self.options.grace
        end = time.perf_counter() + grace if deadline is None else deadline + grace
        grower, pricer = self.strategy.grower, self.strategy.pricer
        try:
            with clock.limit(end):
                if isinstance(self.strategy, BestFirst):
                    frontier = self.strategy.frontier
                else:  # the windows keep no frontier: dive from the start
                    frontier = sorted(grower.settle(root(self.goal), pricer), key=_order)
                return dive(frontier, partial(grower.children, pricer=pricer), grower.finish)
        except (clock.OutOfTime, KeyboardInterrupt):
            return None

    def _explain(self, started: float, deadline: float | None) -> None:
        """The bounds cut branches before their dead ends were met: search them
        without the bounds, so the report can say why nothing is admissible."""
        grounder = parts(self.task, self.options.media)[0]
        unbounded = Grower(grounder, self.distinct)
        explaining = BestFirst(
            unbounded, Pricer(self.task.levels, _no_bound, stats=unbounded.stats), self.goal
        )
        spent = time.perf_counter() - started
        end = time.perf_counter() + max(self.options.explain_seconds, 2 * spent)
        if deadline is not None:
            end = min(end, deadline + self.options.grace)
        with clock.limit(end):
            for _ in explaining:
                break
        report = explaining.report
        if explaining.stopped is not None:
            report.unfinished = True
        self.explained = report


def plan(
    task: Task,
    goal: Ground,
    *,
    limit: int | None = 1,
    distinct: bool = True,
    time_limit: float | None = None,
    progress: Progress | None = None,
    options: SearchOptions | None = None,
) -> tuple[list[Configuration], Run]:
    """The ``limit`` cheapest admissible configurations (all when None), and
    the run that found them (its stats, report and stop reason)."""
    run = Run(task, goal, limit, distinct, time_limit, progress, options=options or SearchOptions())
    return list(run), run
