"""Best-first search for ranked admissible configurations (thesis 4.5).

The thesis's planner expands the goal depth-first, backtracking over method
versions and precondition bindings, and returns configurations cheapest
first. Here the same derivations are explored best-first: a node's priority is
the cost of its settled part (which never decreases as it grows) plus a lower
bound on what it must still add (the *heuristic*, passed in: see
:mod:`cfgplan.planner.bound`), and then its path of choices. So configurations
come out ordered by cost and, at equal cost, in the depth-first order of the
thesis (domain order of method versions, state order of facts, 6.3.2).
Nothing is enumerated and then sorted.

Nodes are grown by :func:`cfgplan.planner.successors.successors`; the search
only *settles* them (places the functionalities on top of the stack, so every
queued node has a method on top or is complete), orders and finishes them.
"""

from __future__ import annotations

import heapq
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

from cfgplan.configuration.model import Configuration
from cfgplan.planner.finish import Models, finish, identity
from cfgplan.planner.ground import Grounder
from cfgplan.planner.partial import Partial, canonical, root
from cfgplan.planner.report import DeadEnd, Report, StopReason
from cfgplan.planner.successors import successors
from cfgplan.planner.task import Ground

Heuristic = Callable[[Partial], float | None]
"""A lower bound on what a node still costs; None when it has no completion."""


@dataclass
class Stats:
    """What the search did: shown by ``--verbose`` and in JSON output."""

    nodes: int = 0  # nodes taken from the queue
    expansions: int = 0  # method instances expanded
    derivations: int = 0  # complete derivations met (duplicates included)
    duplicates: int = 0  # complete derivations whose configuration was listed already
    rejected: int = 0  # complete derivations found inadmissible (4.5 step 4)
    pruned: int = 0  # nodes the heuristic proved to have no completion
    seconds: float = 0.0
    complete: bool = True  # False when a limit stopped the search early


Progress = Callable[[Stats, float], None]


@dataclass
class BestFirst:
    """An iterator over configurations, best first."""

    grounder: Grounder
    goal: Ground
    heuristic: Heuristic
    distinct: bool = True
    time_limit: float | None = None
    progress: Progress | None = None
    stats: Stats = field(default_factory=Stats)
    report: Report = field(default_factory=Report)
    stopped: StopReason | None = None
    _heap: list[tuple[float, tuple[int, ...], Partial]] = field(default_factory=list)
    _seen: set[object] = field(default_factory=set)  # configurations listed (distinct)
    _closed: set[object] = field(default_factory=set)  # partial nodes expanded (distinct)
    _models: Models = field(default_factory=Models)

    def __iter__(self) -> Iterator[Configuration]:
        start = time.perf_counter()
        self._queue(self._settle(root(self.goal)))
        next_tick = 1.0
        while self._heap:
            elapsed = time.perf_counter() - start
            self.stats.seconds = elapsed
            if self.time_limit is not None and elapsed > self.time_limit:
                self.stats.complete = False
                self.stopped = StopReason.TIME_LIMIT
                break
            if self.progress is not None and elapsed > next_tick:
                self.progress(self.stats, elapsed)
                next_tick = elapsed + 0.5
            # The heap holds (priority, path, node): two queued nodes never have
            # the same path (paths are unique choice sequences, and no queued node
            # is an ancestor of another), so tuples never compare two Partials.
            total, _, node = heapq.heappop(self._heap)
            self.stats.nodes += 1
            if node.done:
                config = self._complete(node, total)
                if config is not None:
                    self.stats.seconds = time.perf_counter() - start
                    yield config
                continue
            if self.distinct:
                # The same partial configuration reached by another order of
                # choices has the same completions: only the first one counts.
                key = canonical(node)
                if key in self._closed:
                    continue
                self._closed.add(key)
            self._queue(self.children(node))
        self.stats.seconds = time.perf_counter() - start

    def _complete(self, node: Partial, total: float) -> Configuration | None:
        """Step 4 for a node taken from the queue: the configuration to list, or
        None (a repeat in distinct mode, or inadmissible)."""
        ident = identity(node) if self.distinct else None
        if ident is not None and ident in self._seen:
            self.stats.derivations += 1
            self.stats.duplicates += 1
            return None
        config = self.finish(node, total)
        if config is None:
            return None
        self.stats.derivations += 1
        if ident is not None:
            self._seen.add(ident)
        return config.model_copy(update={"derivation": self.stats.derivations})

    def finish(self, node: Partial, total: float) -> Configuration | None:
        """The admissible configuration of a complete node, or None (rejection reported)."""
        result = finish(node, self.grounder.task, total, self._models)
        if isinstance(result, DeadEnd):
            self.stats.rejected += 1
            self.report.reject(result)
            return None
        return result

    def _queue(self, entries: Iterator[tuple[float, Partial]]) -> None:
        for priority, node in entries:
            heapq.heappush(self._heap, (priority, node.path, node))

    @property
    def frontier(self) -> list[tuple[float, Partial]]:
        """The open nodes, best first."""
        return [(priority, node) for priority, _, node in sorted(self._heap, key=lambda e: e[:2])]

    def children(self, node: Partial) -> Iterator[tuple[float, Partial]]:
        """Expand the method on top of ``node``; yield its settled children with
        their priorities (dead ends go to the report)."""
        self.stats.expansions += 1
        for child in successors(self.grounder, node):
            if isinstance(child, DeadEnd):
                self.report.note(child)
            else:
                yield from self._settle(child)

    def _settle(self, node: Partial) -> Iterator[tuple[float, Partial]]:
        """Place the functionalities on top of the stack (one child per binding
        when one has several); yield each node that has a method on top, or is
        complete, with its priority."""
        task = self.grounder.task
        todo = [node]
        while todo:
            current = todo.pop()
            if current.done or task.is_method(current.stack[0].call):
                priority = current.cost
                if not current.done:
                    rest = self.heuristic(current)
                    if rest is None:
                        self.stats.pruned += 1
                        continue
                    priority += rest
                yield priority, current
                continue
            placed: list[Partial] = []
            for child in successors(self.grounder, current):
                if isinstance(child, DeadEnd):
                    self.report.note(child)
                else:
                    placed.append(child)
            todo.extend(reversed(placed))
