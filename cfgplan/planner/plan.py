"""The planner's entry point: the cheapest admissible configurations, ranked.

A :class:`Run` puts the parts together: the grounding memo and the bounds of
the task (kept per task, so that planning the same task again, e.g. ``-k 1``
then ``--all``, grounds and summarises once), the strategy — best-first
search for the ``limit`` cheapest (:mod:`cfgplan.planner.search`), or, when
the goal's choices fall into independent parts, each part searched so and
the parts combined (:mod:`cfgplan.planner.combine`), windows of depth-first
walks to list them all in bounded memory (:mod:`cfgplan.planner.search`)
— the time limit, the greedy dive when a
search is stopped before it has proven anything, and, when nothing is
admissible, a search without the bounds to say why. Configurations come out
of a run as they are proven, so a caller may print them at once;
:func:`plan` collects them.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from functools import partial
from typing import TYPE_CHECKING

from cfgplan.configuration.model import Configuration
from cfgplan.planner import clock
from cfgplan.planner.bound import Bound
from cfgplan.planner.combine import Parts, divide, unroll
from cfgplan.planner.ground import Grounder
from cfgplan.planner.grow import Grower, ReplayKey, Replays
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.partial import Partial, root
from cfgplan.planner.partition import Partition, Split
from cfgplan.planner.pricer import Heuristic, Pricer, Splitter
from cfgplan.planner.report import Engine, Report, Stats, Status
from cfgplan.planner.search import BestFirst, Prefix, Progress, place
from cfgplan.planner.task import Ground, Task

if TYPE_CHECKING:  # each loaded where it is used: most runs use none (start-up)
    from cfgplan.planner.combine import Combined
    from cfgplan.planner.search import Windows


@dataclass(eq=False, repr=False)
class Analysis:
    """What the planner works out about a task once, for every search of it
    (:func:`analysis`): the grounding memo, the two bounds made on it, and what
    is made on demand and kept: the goals' independent parts and the replays'
    rules."""

    grounder: Grounder
    """The ground instances, made on demand and kept (:mod:`cfgplan.planner.ground`)."""
    bound: Bound
    """The first bound: what every expansion contains (:mod:`cfgplan.planner.bound`)."""
    partition: Partition
    """The second bound: passes over the graph of ground instances
    (:mod:`cfgplan.planner.partition`)."""
    components: dict[Ground, Parts | None] = field(default_factory=dict)
    """Each goal's independent parts (:func:`divided`)."""
    replays: dict[ReplayKey, Replays] = field(default_factory=dict)
    """The replays' rules (:attr:`cfgplan.planner.grow.Grower.kept`)."""


def analysis(task: Task, media: bool = True) -> Analysis:
    """The :class:`Analysis` of ``task``, made at its first search and kept on
    it (:attr:`Task.analyses`): it is freed with the task, as a run that
    reconfigures plans on one derived task after another. ``media``:
    :attr:`SearchOptions.media` (a partitioned bound each way)."""
    found: Analysis | None = task.analyses.get(media)
    if found is None:
        grounder = Grounder(task)
        partition = Partition(grounder, media)
        found = task.analyses[media] = Analysis(grounder, Bound(task, grounder, media), partition)
    return found


def divided(task: Task, goal: Ground, media: bool = True) -> Parts | None:
    """The goal's independent parts (:mod:`cfgplan.planner.combine`), made
    once per task and goal; None when there are not two, or when costs have
    no unit (:mod:`cfgplan.planner.costs`: then sums of parts may not rank
    as whole configurations do). ``media``: as :func:`analysis`."""
    analysed = analysis(task, media)
    made = analysed.components
    if goal not in made:
        found = None
        if task.levels.unit is not None:
            unrolled = unroll(analysed.grounder, goal)
            if unrolled is not None:
                found = divide(analysed.grounder, analysed.partition, *unrolled)
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
    (:mod:`cfgplan.planner.partition`)."""

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
    (:func:`analysis`), children priced from splits (unless ``splits`` is
    False, or :attr:`SearchOptions.splits` is); ``given``:
    :attr:`Grower.given`. Every strategy's grower and pricer are made here."""
    analysed = analysis(task, options.media)
    grounder, bound, partition = analysed.grounder, analysed.bound, analysed.partition
    made = Grower(
        grounder,
        distinct,
        given,
        options=options,
        replays=replays and options.replays,
        kept=analysed.replays,
    )
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
    listed) to say whether more exist (:attr:`status`), with bounded work
    (:mod:`cfgplan.planner.search`): ``-k 1`` never runs to the end of a
    search to prove there is no second configuration."""
    options: SearchOptions = field(default_factory=SearchOptions)
    """The strategies' settings and switches (parts apart, the look-ahead's
    least work, ...), given to every grower of the run."""
    status: Status = field(init=False, default=Status.COMPLETE)
    """How the run ended: stopped (the time limit, the user), or as the
    prefix it listed (:attr:`cfgplan.planner.search.Prefix.status`); UNKNOWN
    when the solver answered (it finds the first configuration and looks no
    further)."""
    engine: Engine = field(init=False, default=Engine.SEARCH)
    """Which engine found the configurations."""
    raced: bool = field(init=False, default=False)
    """The solver's process was started beside the search
    (:attr:`SearchOptions.race`): whoever answered, the first configuration is
    all the run looks for (:attr:`status` is UNKNOWN)."""
    answered: Stats | None = field(init=False, default=None)
    """The work of the solver's process, when it answered the race."""
    inadmissible: bool = field(init=False, default=False)
    """The solver's process proved that nothing is admissible (its relaxation
    has no model) before the search could."""
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
            from cfgplan.planner.search import Windows

            bound = analysis(self.task, self.options.media).bound
            self.strategy = Windows(made, pricer, self.goal, bound.feasible, self.progress)
        else:
            self.strategy = BestFirst(made, pricer, self.goal, self.progress)

    def _search(self) -> Iterator[Configuration]:
        """The configurations, cheapest first: the goal's parts apart, if it
        has some; for ``-k 1`` by the solver (:attr:`SearchOptions.solver`),
        or with the solver's process racing the search (:attr:`SearchOptions.race`)."""
        first_only = self.limit == 1 and isinstance(self.strategy, BestFirst)
        if self.options.solver and first_only:
            solved = self._solved()
            if solved is not None:
                yield solved
                return
        if self.options.race is not None and first_only and self.task.levels.unit is not None:
            # (costs without a unit have no bracket: nothing to race)
            from cfgplan.planner import solver  # loaded when asked for (start-up)

            if solver.FORKS:
                yield from self._race(self.options.race)
                return
        self._divide()
        yield from self.strategy

    def _race(self, after: int) -> Iterator[Configuration]:
        """The first configuration, by the search or by the solver's process
        started beside it after ``after`` steps (:mod:`cfgplan.planner.solver`),
        whichever ends first. Nothing is yielded while the child runs: the
        caller's own clock steps are not the race's."""
        from cfgplan.planner import solver

        found: Configuration | None = None
        try:
            with solver.racing(self._in_child, after) as rival:
                self._divide()
                searched = iter(self.strategy)
                found = next(searched, None)
        except solver.Overtaken as won:
            self.raced = True
            self.engine = Engine.SOLVER
            config, self.answered = won.answer
            if config is None:
                self.inadmissible = True  # why: :meth:`_explain`
                return
            yield config
            return
        self.raced = rival.started
        if found is None:
            return
        yield found
        if not self.raced:  # alone all along: as without the race
            yield from searched

    def _in_child(self) -> Callable[[], tuple[Configuration | None, Stats] | None]:
        """The solver in the racing child: its program grounded at once (while
        the search works), and its answer and work once the race starts: the
        first cheapest configuration, or None where it proved that nothing is
        admissible (the search may take long to find that out)."""
        from cfgplan.planner import solver

        grower = growing(self.task, self.options, self.distinct)[0]
        grounded = solver.relaxation(grower, self.goal)

        def answer() -> tuple[Configuration | None, Stats] | None:
            try:
                config = solver.cheapest(grower, self.goal, clock.remaining(), grounded)
            except solver.Inadmissible:
                return None, grower.stats  # an answer too: nothing is admissible
            return None if config is None else (config, grower.stats)

        return answer

    def _by_solver(self, grower: Grower) -> Configuration | None:
        """The first cheapest configuration by the solver's bracket (in at most
        half the time left) and walk; None when the bracket does not close or
        nothing is admissible. Raises :class:`solver.Unsupported` (costs without
        a unit) and :class:`clock.OutOfTime`."""
        from cfgplan.planner import solver

        left = clock.remaining()
        found = solver.bracket(grower.grounder, self.goal, None if left is None else left / 2)
        if not found.exact or found.upper is None:
            return None  # open, or nothing admissible: the search says why (its dead ends)
        return solver.first(grower, self.goal, found.lower)

    def _solved(self) -> Configuration | None:
        """:attr:`SearchOptions.solver`: the first cheapest configuration by the
        solver (:meth:`_by_solver`), or None: the search goes on from the start
        (and stops at once when out of time). What comes after it is not looked
        for (:attr:`status` is UNKNOWN)."""
        from cfgplan.planner import solver

        try:
            config = self._by_solver(self.strategy.grower)
        except (solver.Unsupported, clock.OutOfTime):
            return None
        if config is not None:
            self.engine = Engine.SOLVER
        return config

    def _divide(self) -> None:
        """Search the goal's independent parts apart, if it has some (:func:`in_parts`)."""
        if isinstance(self.strategy, BestFirst):
            self.strategy = in_parts(self.strategy, self.task, self.options, self.progress)

    @property
    def stats(self) -> Stats:
        """The work of the engine that answered."""
        return self.strategy.stats if self.answered is None else self.answered

    @property
    def report(self) -> Report:
        return self.strategy.report if self.explained is None else self.explained

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
            self.status = self.strategy.status
            if not self.status.stopped:
                first_only = self.engine is Engine.SOLVER or self.raced
                self.status = Status.UNKNOWN if first_only and listed else prefix.status
        except KeyboardInterrupt:
            self.status = Status.INTERRUPTED
        if self.status.stopped and not listed:
            guess = self._dive(deadline)
            if guess is not None:
                yield guess
            else:  # nothing found, nothing proved
                self.report.status = self.status
            return
        if not listed and (self.inadmissible or (self.stats.pruned and self.status.exhausted)):
            self._explain(started, deadline)

    def _dive(self, deadline: float | None) -> Configuration | None:
        """Stopped before anything was proven: dive for any configuration
        (unless :attr:`SearchOptions.dive` is off)."""
        if not self.options.dive:
            return None
        from cfgplan.planner.search import dive

        grace = self.options.grace
        end = time.perf_counter() + grace if deadline is None else deadline + grace
        grower, pricer = self.strategy.grower, self.strategy.pricer
        try:
            with clock.limit(end):
                if isinstance(self.strategy, BestFirst):
                    frontier = self.strategy.frontier
                else:  # the windows keep no frontier: dive from the start
                    settled = grower.settle(root(self.goal), pricer)
                    frontier = sorted(settled, key=lambda entry: place(*entry))
                return dive(frontier, partial(grower.children, pricer=pricer), grower.finish)
        except (clock.OutOfTime, KeyboardInterrupt):
            return None

    def _explain(self, started: float, deadline: float | None) -> None:
        """The bounds cut branches before their dead ends were met, or the
        solver's process proved that nothing is admissible before the search
        met them: search without the bounds, so the report can say why."""
        grounder = analysis(self.task, self.options.media).grounder
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
        report.status, report.explaining = explaining.status, True
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
