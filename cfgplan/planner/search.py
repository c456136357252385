"""Best-first search for ranked admissible configurations (thesis 4.5).

The thesis's planner expands the goal depth-first, backtracking over method
versions and precondition bindings, and returns configurations cheapest
first. Here the same derivations are explored best-first: a node's priority is
the cost of its settled part (which never decreases as it grows) plus a lower
bound on what it must still add (the heuristics, passed in: see
:mod:`cfgplan.planner.bound` and :mod:`cfgplan.planner.partition`), and then
its path of choices (:func:`cfgplan.planner.ranking.place`). So configurations
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
(:mod:`cfgplan.planner.split`), or priced before the stronger bound was
given up and its twin after, may be priced above its twin, and so taken
after it although it comes first in depth-first order: it then *supersedes*
the twin (:meth:`BestFirst._supersede`). It is expanded too, and what the
twin's expansion left open is dropped as it is taken. Nothing the twin
derived was listed yet: the earlier node's priority bounds what both
complete at, and at that cost its path comes first. So the search never
starts over to repair its order (``tests/data/repros/
k-not-prefix-of-all``, where ``-k 5`` was once not a prefix of ``--all``).
"""

from __future__ import annotations

import heapq
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

from cfgplan.configuration.model import Configuration
from cfgplan.planner import clock
from cfgplan.planner.canonical import canonical
from cfgplan.planner.grow import Completion, Grower
from cfgplan.planner.partial import Partial, root
from cfgplan.planner.pricer import Pricer, Reprice
from cfgplan.planner.ranking import place
from cfgplan.planner.report import Report, Stats, Status
from cfgplan.planner.task import Ground

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
                # (A node that must not follow a replay's choices, replay.py,
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
