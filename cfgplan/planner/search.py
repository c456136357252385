"""Best-first search for ranked admissible configurations (thesis 4.5).

The thesis's planner expands the goal depth-first, backtracking over method
versions and precondition bindings, and returns configurations cheapest
first. Here the same derivations are explored best-first: a node's priority is
the cost of its settled part (which never decreases as it grows) and then its
path of choices, so configurations come out ordered by cost and, at equal
cost, in the depth-first order of the thesis (domain order of method versions,
state order of facts, 6.3.2). Nothing is enumerated and then sorted.
"""

from __future__ import annotations

import heapq
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

from cfgplan.configuration.model import Configuration
from cfgplan.planner.bound import Bound
from cfgplan.planner.complete import finish, identity
from cfgplan.planner.match import Bindings, bind_name, bindings, why_not
from cfgplan.planner.partial import (
    Dead,
    Expansion,
    Item,
    Partial,
    canonical,
    describe_call,
    expand_method,
    instantiate,
    place_functionality,
    root,
)
from cfgplan.planner.task import FunctionalitySchema, Ground, MethodSchema, Task


@dataclass
class Stats:
    """What the search did: shown by ``--verbose`` and in JSON output."""

    nodes: int = 0
    expansions: int = 0
    derivations: int = 0
    duplicates: int = 0
    merged: int = 0  # partial configurations reached again by another order
    rejected: int = 0
    seconds: float = 0.0
    complete: bool = True  # False when a limit stopped the search early


@dataclass
class Report:
    """Dead ends met on the way, first occurrence kept, in the order met."""

    dead: dict[tuple[str, str], Dead] = field(default_factory=dict)
    rejected: list[tuple[str, str]] = field(default_factory=list)  # (condition, reason)

    def note(self, dead: Dead) -> None:
        self.dead.setdefault((dead.where, dead.condition), dead)


Progress = Callable[[Stats, float], None]


class Search:
    """An iterator over configurations, best first; see :func:`plan`."""

    def __init__(
        self,
        task: Task,
        goal: Ground,
        *,
        distinct: bool = True,
        time_limit: float | None = None,
        progress: Progress | None = None,
        bound: bool = True,
        estimate: bool = True,
    ) -> None:
        self.task = task
        self.bound = Bound(task) if bound else None
        self.pruned = 0  # nodes the bound proved to have no completion
        # Listing everything, a cost estimate cannot stop the search early:
        # then the bound only cuts nodes without completion.
        self.estimate = estimate
        self.goal = goal
        self.distinct = distinct
        self.time_limit = time_limit
        self.progress = progress
        self.stats = Stats()
        self.report = Report()
        self._seen: set[object] = set()
        self._closed: set[object] = set()
        self._expansions: dict[object, Expansion | Dead] = {}
        self._matches: dict[tuple[int, Ground], list[Bindings]] = {}
        self._heap: list[tuple[float, tuple[int, ...], Partial]] = []
        self._start = 0.0
        self.stopped = ""  # why the search stopped early: "time limit", "interrupted"

    def __iter__(self) -> Iterator[Configuration]:
        self._start = time.perf_counter()
        self._queue(self.settled(root(self.goal)))
        next_tick = 1.0
        while self._heap:
            elapsed = time.perf_counter() - self._start
            if self.time_limit is not None and elapsed > self.time_limit:
                self.stats.complete = False
                self.stopped = "time limit"
                break
            if self.progress is not None and elapsed > next_tick:
                self.progress(self.stats, elapsed)
                next_tick = elapsed + 0.5
            total, _, node = heapq.heappop(self._heap)
            self.stats.nodes += 1
            if node.done:
                ident = identity(node) if self.distinct else None
                if ident is not None and ident in self._seen:
                    self.stats.derivations += 1
                    self.stats.duplicates += 1
                    continue
                config = finish(node, self.task, total, self.report)
                self.stats.seconds = time.perf_counter() - self._start
                if config is None:
                    self.stats.rejected += 1
                    continue
                self.stats.derivations += 1
                config = config.model_copy(update={"derivation": self.stats.derivations})
                if ident is not None:
                    self._seen.add(ident)
                yield config
                continue
            if self.distinct:
                # The same partial configuration reached by another order of
                # choices has the same completions: only the first one counts.
                key = canonical(node)
                if key in self._closed:
                    self.stats.merged += 1
                    continue
                self._closed.add(key)
            self._queue(self.children(node))
        self.stats.seconds = time.perf_counter() - self._start

    def _queue(self, entries: Iterator[tuple[float, Partial]]) -> None:
        for priority, node in entries:
            heapq.heappush(self._heap, (priority, node.path, node))

    @property
    def frontier(self) -> list[tuple[float, Partial]]:
        """The open nodes, best first."""
        return [(priority, node) for priority, _, node in sorted(self._heap, key=lambda e: e[:2])]

    def finished(self, node: Partial, total: float) -> Configuration | None:
        """The admissible configuration of a node whose stack is empty, or None."""
        return finish(node, self.task, total, self.report)

    def children(self, node: Partial) -> Iterator[tuple[float, Partial]]:
        """Branch on the method on top of the stack: each version, each binding;
        yields the settled children with their priorities."""
        item = node.stack[0]
        versions = self.task.methods.get((item.call[0], len(item.call) - 1), ())
        self.stats.expansions += 1
        if item.call in item.ancestors:
            self.report.note(
                Dead(
                    describe_call(item.call),
                    "it recurs on its own expansion path",
                    condition="recursion",
                )
            )
            return
        choice = 0
        for method in versions:
            env = bind_name(method.params, item.call[1:])
            if env is None:
                self.report.note(
                    Dead(
                        f"{describe_call(item.call)}, version {method.version}",
                        f"its name ({method.name} {' '.join(method.params)}) does not match",
                        method.span,
                        condition="binding",
                    )
                )
                continue
            found = False
            where = f"{describe_call(item.call)}, version {method.version}"
            for env2 in self._bindings(method, item.call, env):
                found = True
                expansion = self._instantiated(method, env2, where)
                child = (
                    expansion
                    if isinstance(expansion, Dead)
                    else expand_method(node, item, expansion, where, method.span, choice)
                )
                choice += 1
                if isinstance(child, Dead):
                    self.report.note(child)
                    continue
                yield from self.settled(child)
            if not found:
                failure = why_not(self.task, method.tests, env, method.params)
                self.report.note(
                    Dead(
                        f"{describe_call(item.call)}, version {method.version}",
                        failure.describe(),
                        failure.span or method.span,
                    )
                )

    def _bindings(
        self, schema: MethodSchema | FunctionalitySchema, call: Ground, env: Bindings
    ) -> list[Bindings]:
        """The precondition bindings of a schema for a call: the state does not
        change during the search, so they are matched once per call."""
        key = (id(schema), call)
        found = self._matches.get(key)
        if found is None:
            found = self._matches[key] = list(bindings(self.task, schema.tests, env))
        return found

    def _instantiated(self, method: MethodSchema, env: Bindings, where: str) -> Expansion | Dead:
        key = (method.name, method.version, len(method.params), tuple(sorted(env.items())))
        found = self._expansions.get(key)
        if found is None:
            found = self._expansions[key] = instantiate(method, env, where)
        return found

    def settled(self, node: Partial) -> Iterator[tuple[float, Partial]]:
        """Place the functionalities on top of the stack; yield the node with its
        priority (one per precondition binding when a functionality has several)."""
        todo = [node]
        while todo:
            current = todo.pop()
            if current.done or _is_method(self.task, current.stack[0]):
                priority = current.cost
                if self.bound is not None and not current.done:
                    rest = self.bound.of(current, self.estimate)
                    if rest is None:
                        self.pruned += 1
                        continue
                    priority += rest
                yield priority, current
                continue
            item = current.stack[0]
            schema = self.task.functionalities.get((item.call[0], len(item.call) - 1))
            if schema is None:
                self.report.note(
                    Dead(
                        describe_call(item.call),
                        "is neither a method nor a functionality",
                        condition="domain",
                    )
                )
                continue
            if item.call in current.labels:
                child = place_functionality(current, item, schema, None, None, self.task)
                if isinstance(child, Dead):
                    self.report.note(child)
                else:
                    todo.append(child)
                continue
            env = bind_name(schema.params, item.call[1:])
            if env is None:
                self.report.note(
                    Dead(
                        describe_call(item.call),
                        f"does not match the functionality ({schema.name} "
                        f"{' '.join(schema.params)})",
                        schema.span,
                        condition="domain",
                    )
                )
                continue
            options = self._bindings(schema, item.call, env)
            if not options:
                failure = why_not(self.task, schema.tests, env, schema.params)
                self.report.note(Dead(describe_call(item.call), failure.describe(), schema.span))
                continue
            children: list[Partial] = []
            for index, env2 in enumerate(options):
                choice = index if len(options) > 1 else None
                child = place_functionality(current, item, schema, env2, choice, self.task)
                if isinstance(child, Dead):
                    self.report.note(child)
                else:
                    children.append(child)
            todo.extend(reversed(children))


def _is_method(task: Task, item: Item) -> bool:
    return (item.call[0], len(item.call) - 1) in task.methods


def plan(
    task: Task,
    goal: Ground,
    *,
    limit: int | None = 1,
    distinct: bool = True,
    time_limit: float | None = None,
    progress: Progress | None = None,
) -> tuple[list[Configuration], Search]:
    """The ``limit`` cheapest admissible configurations (all when None)."""
    search = Search(
        task,
        goal,
        distinct=distinct,
        time_limit=time_limit,
        progress=progress,
        estimate=limit is not None,
    )
    found: list[Configuration] = []
    try:
        for config in search:
            found.append(config)
            if limit is not None and len(found) >= limit:
                search.stats.complete = False
                break
    except KeyboardInterrupt:
        search.stats.complete = False
        search.stopped = "interrupted"
    if search.stopped and not found:
        # Stopped before the cheapest was proven: dive for any configuration.
        from cfgplan.planner.dive import dive

        guess = dive(search)
        if guess is not None:
            found.append(guess)
    if not found and search.pruned and search.stats.complete:
        # The bound cut branches without meeting their dead ends; search them
        # without it, so the report can say why nothing is admissible.
        explaining = Search(task, goal, distinct=distinct, bound=False)
        for _ in explaining:
            break
        search.report = explaining.report
    return found, search
