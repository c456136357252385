"""Listing every configuration in bounded memory: depth first, by cost windows.

Best-first search (:mod:`cfgplan.planner.search`) proves configurations in
order but keeps every open node: listing *all* of a large instance that way
holds the whole frontier. Here ``--all`` instead walks the derivations depth
first, in the thesis's order (4.5), keeping only the path, and collects the
admissible configurations whose cost falls in a window ``[low, high)``;
nodes whose bound reaches ``high`` are cut. At the end of a pass the window
is sorted by cost, then depth-first order (6.3.2; the place of
:mod:`cfgplan.planner.ranking`, a derivation's path stood for by its rank in
the walk, which orders alike and holds less) — exactly the order the
best-first search gives — and listed; when costs have a unit
(:mod:`cfgplan.planner.levels`), the cheapest cost of a window is listed as
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

import math
import time
from collections.abc import Iterator
from dataclasses import dataclass, field

from cfgplan.configuration.model import Assignment, Configuration
from cfgplan.planner import clock
from cfgplan.planner.canonical import canonical
from cfgplan.planner.finish import Pieces, admissible, build, fingerprint
from cfgplan.planner.grow import Grower
from cfgplan.planner.partial import Partial, root
from cfgplan.planner.pricer import Heuristic, Pricer
from cfgplan.planner.report import DeadEnd, Report, Stats, Status
from cfgplan.planner.search import Progress
from cfgplan.planner.task import Ground


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
