"""The search strategies over the grower (thesis 4.5) and the order they list in:
the tie order defined once, best-first search, --all by cost windows, the
anytime dive, and the first -k N results with whether one more exists.

The order in which configurations are listed, defined once (thesis 4.5, 6.3.2).

The thesis's planner returns configurations cheapest first; at equal cost,
in the order its depth-first expansion derives them (method versions in
domain order, precondition bindings in state order). A derivation's
:data:`Place` is that order's key: its cost, then its :data:`Path`, the
choices it made from the goal on (:attr:`cfgplan.planner.partial.Partial.path`).
Every strategy ranks by it:

- best-first search queues nodes by
  :func:`place`, a node's priority (cost so far plus a lower bound) for its cost;
- the greedy dive takes children by :func:`place`;
- ``--all`` sorts a cost window by place,
  each derivation's path stood for by its rank in the depth-first walk
  (the walk meets derivations in path order; an integer holds less);
- combinations of independent parts (:mod:`cfgplan.planner.combine`) and
  sequences of configurations (:mod:`cfgplan.planner.sequence`) are listed
  by :func:`merge`, each candidate carrying a place of its own kind: a
  combination's cost, then the choices below each choice item in the order
  the thesis meets them; a sequence's cost, then its steps' ranks, the first
  step first.

:func:`merge` is the one lazy k-best merge: a best-first listing of
candidates offered as it goes, where what a candidate offers never comes
before it.

The first ``-k N`` results of a search, and whether one more exists.

``cfgplan plan -k N`` says whether more configurations (or sequences) exist
than it lists. Searching for the (N+1)-th without a bound would, where
fewer exist, run the search to its end: ``-k 1`` would cost what ``--all``
does. So, once N are listed, the search goes on for one more with at most as
much work again as the first N took (at least :attr:`Prefix.least` steps of
:func:`cfgplan.planner.clock.check`, the same count on every machine): one
found, the status (:class:`cfgplan.planner.report.Status`) is ``MORE``; the
search ended, ``COMPLETE``; the work ran out, ``UNKNOWN``. One rule, used by
:class:`cfgplan.planner.plan.Run` and :class:`cfgplan.planner.sequence.SequenceSearch`.

An anytime answer: when a search is stopped (``--time-limit``, Ctrl-C)
before it has proven any configuration cheapest, dive depth-first from the
open nodes, cheapest child first (:func:`cfgplan.planner.search.place`), to
find *some* admissible configuration. It is marked as not proven optimal.

A plain function over the search's parts: the open nodes, how to expand one
and how to finish a complete one. Its own time is the caller's business
(:mod:`cfgplan.planner.clock`: expanding checks it).

Best-first search for ranked admissible configurations (thesis 4.5).

The thesis's planner expands the goal depth-first, backtracking over method
versions and precondition bindings, and returns configurations cheapest
first. Here the same derivations are explored best-first: a node's priority is
the cost of its settled part (which never decreases as it grows) plus a lower
bound on what it must still add (the heuristics, passed in: see
:mod:`cfgplan.planner.bound` and :mod:`cfgplan.planner.partition`), and then
its path of choices (:func:`cfgplan.planner.search.place`). So configurations
come out ordered by cost and, at equal cost, in the depth-first order of the
thesis (domain order of method versions, state order of facts, 6.3.2).
Nothing is enumerated and then sorted.

Nodes are grown by a :class:`cfgplan.planner.grow.Grower` and priced by a
:class:`cfgplan.planner.pricer.Pricer`; this module only orders them. The
time limit is the one :mod:`cfgplan.planner.clock` holds.

In distinct mode a partial configuration reached again (its canonical form)
is expanded once, by the node first in the thesis's order: its derivations
are the ones listed. Bounds of the node alone price both alike, so that is
the one taken first. A child priced from its parent's split
(:mod:`cfgplan.planner.partition`), or priced before the stronger bound was
given up and its twin after, may be priced above its twin, and so taken
after it although it comes first in depth-first order: it then *supersedes*
the twin (:meth:`BestFirst._supersede`). It is expanded too, and what the
twin's expansion left open is dropped as it is taken. Nothing the twin
derived was listed yet: the earlier node's priority bounds what both
complete at, and at that cost its path comes first. So the search never
starts over to repair its order (``tests/data/repros/
k-not-prefix-of-all``, where ``-k 5`` was once not a prefix of ``--all``).

Listing every configuration in bounded memory: depth first, by cost windows.

Best-first search proves configurations in
order but keeps every open node: listing *all* of a large instance that way
holds the whole frontier. Here ``--all`` instead walks the derivations depth
first, in the thesis's order (4.5), keeping only the path, and collects the
admissible configurations whose cost falls in a window ``[low, high)``;
nodes whose bound reaches ``high`` are cut. At the end of a pass the window
is sorted by cost, then depth-first order (6.3.2; the place of
:func:`place`, a derivation's path stood for by its rank in
the walk, which orders alike and holds less) — exactly the order the
best-first search gives — and listed; when costs have a unit
(:mod:`cfgplan.planner.costs`), the cheapest cost of a window is listed as
it is walked (depth-first order is then the listing order).
A configuration has one cost, so it falls in one window: distinct
configurations stay distinct across windows.

The first pass is one window over every cost, priced only by whether a node
can complete: most instances are listed in this one walk. Only when it has
taken :attr:`~cfgplan.planner.options.SearchOptions.one_pass` nodes without
meeting a configuration of the cheapest cost is it given up, for windows
pruned by the bounds — the cheapest cost first, the rest after — so that the
first configurations come soon.

When a window holds more than
:attr:`~cfgplan.planner.options.SearchOptions.most_held` configurations, its
upper edge is lowered to keep the cheaper half and the next window starts there,
so memory stays bounded whatever the instance; the configurations listed
are remembered (distinct mode) as 128-bit digests of their label-free form.
"""

from __future__ import annotations

import heapq
import math
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any, Generic, Protocol, TypeVar

from cfgplan.configuration.model import Assignment, Configuration
from cfgplan.planner import clock
from cfgplan.planner.finish import Pieces, admissible, build, fingerprint
from cfgplan.planner.grow import Completion, Grower
from cfgplan.planner.partial import Partial, canonical, root
from cfgplan.planner.pricer import Heuristic, Pricer, Reprice
from cfgplan.planner.report import DeadEnd, Report, Stats, Status
from cfgplan.planner.task import Ground

Path = tuple[int, ...]
"""The choices a derivation made, in the order it made them: the index of
each expansion taken among those of its item (4.5's backtracking order)."""

Place = tuple[float, Path]
"""Where a derivation is listed: cheaper first, then earlier in depth-first order."""


class _Ranked(Protocol):
    path: Path


def place(cost: float, node: _Ranked) -> Place:
    """The place of ``node`` (a derivation, complete or partial) at ``cost``:
    a partial node's at its priority is at most that of every derivation it
    completes to, as its path is a prefix of theirs."""
    return cost, node.path


class _Comparable(Protocol):
    def __lt__(self, other: Any, /) -> bool: ...


C = TypeVar("C", bound=_Comparable)


def merge(
    first: Iterable[C], offers: Callable[[C], Iterable[C]], listed: Callable[[C], bool]
) -> Iterator[C]:
    """The candidates reached from ``first`` through ``offers``, least first
    (a candidate compares by its place), those ``listed`` says are results.

    Requires that what a candidate offers never compares below it: then a
    candidate taken from the queue is the least of all still to come. Its
    offers are made only when the next one is asked for (after it is
    yielded, when it is a result), so ``-k 1`` makes no offer beyond the
    first result's. ``offers`` must offer a candidate once (an offer reached
    two ways is the caller's to drop)."""
    queue = list(first)
    heapq.heapify(queue)
    while queue:
        clock.check()
        candidate = heapq.heappop(queue)
        if listed(candidate):
            yield candidate
        for offered in offers(candidate):
            heapq.heappush(queue, offered)


T = TypeVar("T")


@dataclass(eq=False, repr=False)
class Prefix(Generic[T]):
    """Take the first :attr:`limit` of a search (None: all), looking ahead for one more."""

    limit: int | None
    ahead: bool = False
    """Once :attr:`limit` are listed, look for one more (not listed)."""
    least: int = 10_000
    """The least work the look-ahead may do, whatever the first ones took."""
    status: Status = field(init=False, default=Status.COMPLETE)
    """COMPLETE, the search ended; with :attr:`ahead`, MORE, one more exists,
    or UNKNOWN, the look-ahead's work ran out; without, CUT once :attr:`limit`
    are listed."""

    def take(self, found: Iterable[T]) -> Iterator[T]:
        """The first :attr:`limit` of ``found``; the work of making them (the
        first step of ``found`` included) is counted, and bounds the look-ahead."""
        listed = 0
        try:
            with clock.counting() as work:
                for item in found:
                    if self.limit is not None and listed >= self.limit:  # the look-ahead's
                        self.status = Status.MORE
                        return
                    listed += 1
                    yield item
                    if self.limit is not None and listed >= self.limit:
                        if not self.ahead:
                            self.status = Status.CUT
                            return
                        work.most = work.done + max(self.least, work.done)
        except clock.OutOfWork:
            self.status = Status.UNKNOWN


Expand = Callable[[Partial], Iterable[tuple[float, Partial]]]
Finish = Callable[[Partial, float], Configuration | None]


def dive(
    frontier: list[tuple[float, Partial]],
    expand: Expand,
    finish: Finish,
    *,
    budget: int = 50_000,
) -> Configuration | None:
    """The first admissible configuration met by a greedy depth-first dive from
    ``frontier`` (best first), within ``budget`` nodes; None when none is met."""
    stack = list(reversed(frontier))  # the best open node on top
    spent = 0
    try:
        while stack and spent < budget:
            total, node = stack.pop()
            spent += 1
            if node.done:
                config = finish(node, total)
                if config is not None:
                    return config.model_copy(update={"proven": False, "derivation": 0})
                continue
            children = sorted(expand(node), key=lambda entry: place(*entry))
            stack.extend(reversed(children))
    except KeyboardInterrupt:
        return None
    return None


Progress = Callable[[Stats, float], None]


@dataclass(eq=False, repr=False)
class BestFirst:
    """An iterator over configurations, best first."""

    grower: Grower
    """Expands, settles and finishes the nodes."""
    pricer: Pricer
    """Prices them: the bounds, and when the stronger one is used."""
    goal: Ground
    progress: Progress | None = None
    origin: Partial | None = None
    """Where to search from (default: the goal alone on the stack)."""
    status: Status = Status.COMPLETE
    last: Partial | None = None
    """The complete node listed last (:meth:`completions`)."""
    _heap: list[tuple[float, tuple[int, ...], bool, Partial]] = field(default_factory=list)
    _closed: dict[bytes, tuple[int, ...]] = field(default_factory=dict)
    """The canonical forms of the partial nodes expanded (distinct), each with
    the path of the node that was expanded."""
    _superseded: set[tuple[int, ...]] = field(default_factory=set)
    """The paths of expanded nodes an earlier twin superseded (:meth:`_supersede`)."""
    _depths: set[int] = field(default_factory=set)
    """Their lengths: a node is below one when its path's prefix of such a length is one."""

    @property
    def stats(self) -> Stats:
        return self.grower.stats

    @property
    def superseded(self) -> int:
        """How many expanded nodes an earlier twin superseded (:meth:`_supersede`)."""
        return len(self._superseded)

    @property
    def report(self) -> Report:
        return self.grower.report

    def __iter__(self) -> Iterator[Configuration]:
        start = time.perf_counter()
        for admitted in self.completions():
            config = self.grower.build(admitted)
            self.stats.seconds = time.perf_counter() - start  # the caller may stop here
            yield config

    def completions(self) -> Iterator[Completion]:
        """The complete nodes step 4 admits, best first: what the
        configurations are built from (:meth:`__iter__`). An independent
        part's search lists these, not configurations: only its choices are
        combined (:mod:`cfgplan.planner.combine`)."""
        start = time.perf_counter()
        try:
            yield from self._search(start)
        except clock.OutOfTime:
            self.status = Status.TIME_LIMIT
        self.stats.seconds = time.perf_counter() - start

    def _search(self, start: float) -> Iterator[Completion]:
        grower, pricer = self.grower, self.pricer
        self._queue(grower.settle(root(self.goal) if self.origin is None else self.origin, pricer))
        next_tick = 1.0
        while self._heap:
            clock.check()
            elapsed = time.perf_counter() - start
            if self.progress is not None and elapsed > next_tick:
                self.progress(self.stats, elapsed)
                next_tick = elapsed + 0.5
            # The heap holds (place, refined, node), the place (priority, path)
            # flattened (ranking.place, :meth:`_queue`): two queued nodes
            # never have the same path (paths are unique choice sequences, and no
            # queued node is an ancestor of another), so tuples never compare
            # further than the path.
            total, _, refined, node = heapq.heappop(self._heap)
            if self._superseded and self._below_superseded(node.path):
                pricer.discard(node)  # its twin's own derivations stand for it
                continue
            if not refined:
                # Every other queued priority is at most its node's refined one,
                # so a node taken with its refined priority is the least in the
                # order of refined priorities (then paths): refining lazily
                # changes no order, only how many nodes are refined.
                beaten = self._heap[0][0] if self._heap else None
                raised = pricer.refined(node, total, beaten)
                repriced = pricer.take_repriced()
                if repriced is not None:
                    self._reprice(node, raised is None, repriced)
                    continue
                if raised is None:
                    continue
                if raised > total:
                    heapq.heappush(self._heap, (*place(raised, node), True, node))
                    continue
            self.stats.nodes += 1
            if node.done:
                admitted = grower.admit(node, total)
                if admitted is not None:
                    self.last = node
                    self.stats.seconds = time.perf_counter() - start
                    yield admitted
                continue
            if grower.distinct and not node.forbidden:
                # The same partial configuration reached by another order of
                # choices has the same completions: only the first one counts.
                # (A node that must not follow a replay's choices, grow.py,
                # has fewer: it neither closes a form nor is closed by one.)
                key = canonical(node, grower.grounder)
                first = self._closed.get(key)
                if first is not None and not self._below_superseded(first):
                    if node.path > first:
                        pricer.discard(node)  # it is not expanded
                        continue
                    self._supersede(first)
                self._closed[key] = node.path
            self._queue(grower.children(node, pricer))

    def _supersede(self, later: tuple[int, ...]) -> None:
        """The node at path ``later`` was expanded, and a node before it in
        depth-first order (a smaller path) has just been taken with the same
        canonical form: it was priced above its twin (by its parent's split,
        by the stronger bound given up between the two, or by the first bound
        no longer computed for the later one,
        :attr:`~cfgplan.planner.options.SearchOptions.rely`). The earlier
        node's derivations are the ones to list, so it is expanded, and every
        open node below ``later`` is dropped when taken (the twin's
        derivations are the earlier node's, again).

        None of them was listed: the earlier node was taken at a priority that
        bounds what any of its completions costs, and so what any of the
        twin's costs (they complete alike); at that cost the earlier path
        comes first. (Before the earlier node was made, an ancestor of it
        stood in the queue for it: its priority bounds the same completions,
        and its path, a prefix of the earlier one's, comes first too.) Nor
        counted: the twin's complete derivations are taken after it, and
        dropped. Forms the twin's expansion closed are open again
        (:meth:`_below_superseded`), for whichever node reaches them first in
        the thesis's order."""
        self._superseded.add(later)
        self._depths.add(len(later))

    def _below_superseded(self, path: tuple[int, ...]) -> bool:
        """Whether ``path`` is a superseded node's, or extends one."""
        superseded = self._superseded
        return any(path[:depth] in superseded for depth in self._depths)

    def _reprice(self, taken: Partial, pruned: bool, which: Reprice) -> None:
        """The stronger bound was given up: price the open nodes ``which``
        says, and ``taken`` unless it was ``pruned``, by the bounds now in
        use. Two nodes with one canonical form should have one priority, or
        the later of them in depth-first order could be expanded first and
        close the form to the earlier one (:meth:`_supersede` then repairs
        the order of equal-cost configurations, the thesis's, at a cost)."""
        nodes = []
        kept = []
        for entry in self._heap:
            if which is Reprice.REFINED and not entry[2]:
                kept.append(entry)  # priced by the bound still in use
            else:
                nodes.append(entry[3])
        if not pruned:
            nodes.append(taken)
        self._heap = kept
        heapq.heapify(self._heap)
        priced: list[tuple[float, Partial]] = []
        for node in nodes:
            priority = self.pricer.again(node)
            if priority is not None:
                priced.append((priority, node))
        self._queue(iter(priced))

    def _queue(self, entries: Iterator[tuple[float, Partial]]) -> None:
        lazy = self.pricer.lazy
        for priority, node in entries:
            heapq.heappush(self._heap, (*place(priority, node), not lazy or node.done, node))

    @property
    def frontier(self) -> list[tuple[float, Partial]]:
        """The open nodes, best first."""
        ordered = sorted(self._heap, key=lambda e: e[:2])
        return [(priority, node) for priority, _, _, node in ordered]


class _TooBig(Exception):
    """The first walk took its
    :attr:`~cfgplan.planner.options.SearchOptions.one_pass` nodes and listed
    nothing yet."""


@dataclass
class Found:
    """A complete derivation met in a window, in depth-first order ``index``:
    admissible with its media assignment, or not listed (``parts`` None:
    inadmissible, or a repeat). It is built into a configuration when it is
    listed, numbered then."""

    cost: float
    index: int
    parts: Pieces | None
    media: tuple[Assignment, ...] = ()
    repeat: bool = False  # its configuration was met before in this window
    dead: DeadEnd | None = None  # why it is inadmissible (reported when listed)


@dataclass
class Window:
    """The costs a pass lists, ``[low, high)``, and the least bound it cut."""

    low: float
    high: float
    beyond: float | None = None

    def cut(self, priority: float) -> bool:
        """Is a node of this priority beyond the window? (Noted if so.)"""
        if priority < self.high:
            return False
        self.beyond = priority if self.beyond is None else min(self.beyond, priority)
        return True


@dataclass(eq=False, repr=False)
class Windows:
    """An iterator over every configuration, cheapest first, window by window."""

    grower: Grower
    pricer: Pricer
    """The bounds, for the windows pruned by them."""
    goal: Ground
    feasible: Heuristic
    """Decides only whether a node can complete: all a window without an upper
    edge needs, and cheaper than a bound (the first walk's pricer)."""
    progress: Progress | None = None
    status: Status = Status.COMPLETE
    _start: float = field(default=0.0)

    @property
    def stats(self) -> Stats:
        return self.grower.stats

    @property
    def report(self) -> Report:
        return self.grower.report

    def __iter__(self) -> Iterator[Configuration]:
        self._start = time.perf_counter()
        try:
            yield from self._windows()
        except clock.OutOfTime:
            self.status = Status.TIME_LIMIT
        self.stats.seconds = time.perf_counter() - self._start

    def _windows(self) -> Iterator[Configuration]:
        grower, bounded = self.grower, self.pricer
        start = [(p, n) for p, n in grower.settle(root(self.goal), bounded)]
        if not start:
            return
        low = min(p for p, _ in start)
        plain = Pricer(grower.levels, self.feasible, stats=self.stats)
        window = Window(low, float("inf"))
        try:
            yield from self._walk(start, window, plain, budget=self.grower.options.one_pass)
        except _TooBig:
            # The cheapest lie deep: look for them first, pruned by the bounds.
            bounded.warmed(plain.settled)
            window = Window(low, grower.levels.above(low))
            yield from self._walk(start, window, bounded)
        while window.beyond is not None:  # something was cut: the costs above
            window = Window(max(window.high, window.beyond), float("inf"))
            yield from self._walk(start, window, plain)

    def _walk(
        self,
        start: list[tuple[float, Partial]],
        window: Window,
        pricer: Pricer,
        budget: int | None = None,
    ) -> Iterator[Configuration]:
        """One depth-first pass over the derivations costing from ``window.low``
        up to ``window.high`` (which may come down), listing them in order.
        When costs have a unit, the cheapest is listed as it is walked
        (depth-first order is then the listing order). Raises
        :class:`_TooBig` on the node after ``budget`` if none of them was met
        yet; the nodes, expansions and prunings of a walk given up stay
        counted."""
        grower, stats = self.grower, self.stats
        levels = grower.levels
        streamed = window.low if levels.unit is None else levels.above(window.low)
        listed: set[bytes] = set()
        held: set[bytes] = set()
        found: list[Found] = []
        closed: set[bytes] = set()
        stack = list(reversed(start))
        index = taken = 0
        next_tick = 1.0
        while stack:
            clock.check()
            priority, node = stack.pop()
            if window.cut(priority):
                continue
            if not node.done:
                raised = pricer.refined(node, priority)
                if raised is None or window.cut(raised):
                    continue
            stats.nodes += 1
            taken += 1
            if budget is not None and taken > budget:
                raise _TooBig
            elapsed = time.perf_counter() - self._start
            if self.progress is not None and elapsed > next_tick:
                self.progress(stats, elapsed)
                next_tick = elapsed + 0.5
            if node.done:
                index += 1
                if priority < window.low:
                    continue  # listed in an earlier window
                if priority < streamed:
                    budget = None  # something to list: this walk goes on to the end
                    yield from self._list([self._found(node, priority, index, listed)])
                    continue
                found.append(self._found(node, priority, index, held))
                if len(found) > self.grower.options.most_held:
                    found, window.high = _halve(found)
                    window.cut(window.high)  # what it dropped, a later window lists
                continue
            if grower.distinct:
                key = canonical(node, grower.grounder)
                if key in closed:
                    continue
                closed.add(key)
            children = list(grower.children(node, pricer))
            stack.extend(reversed(children))
        found.sort(key=lambda f: (f.cost, f.index))  # ranking.place, by rank in the walk
        yield from self._list(found)

    def _found(self, node: Partial, cost: float, index: int, admitted: set[bytes]) -> Found:
        """A complete derivation met: checked, unless (distinct mode) its
        configuration was admitted before in this window. Both have one cost,
        and the walk meets derivations in depth-first order, so the first met
        is the one listed, as in the best-first search."""
        grower = self.grower
        ident = fingerprint(node, grower.grounder.numbering) if grower.distinct else None
        if ident is not None and ident in admitted:
            return Found(cost, index, None, repeat=True)
        media = admissible(node, grower.grounder.task)
        if isinstance(media, DeadEnd):
            return Found(cost, index, None, dead=media)
        if ident is not None:
            admitted.add(ident)
        return Found(cost, index, Pieces(node.placed, node.channels, node.effects), media)

    def _list(self, found: list[Found]) -> Iterator[Configuration]:
        """Sorted derivations of a window, numbered as :meth:`Grower.admit`
        numbers them (repeats counted, inadmissible ones not)."""
        stats = self.stats
        task, models = self.grower.grounder.task, self.grower.models
        for f in found:
            if f.dead is not None:
                stats.rejected += 1
                self.report.reject(f.dead)
            elif f.repeat:
                stats.derivations += 1
                stats.duplicates += 1
            elif f.parts is not None:
                stats.derivations += 1
                yield build(f.parts, f.cost, task, models, f.media, stats.derivations)


def _halve(found: list[Found]) -> tuple[list[Found], float]:
    """Keep the cheaper half of a window (whole cost levels): the new upper edge."""
    costs = sorted({f.cost for f in found})
    if len(costs) == 1:
        return found, math.nextafter(costs[0], math.inf)  # one cost level: it cannot be split
    high = costs[len(costs) // 2]
    return [f for f in found if f.cost < high], high
