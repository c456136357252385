"""Growing nodes: what every search strategy does to a node it takes.

A :class:`Grower` expands the method on top of a node
(:func:`cfgplan.planner.successors.successors`), *settles* the children
(places the functionalities on top of their stacks, so every node it hands
back has a method on top or is complete), prices them with the bounds, and
finishes complete nodes (4.5 step 4). It keeps what the strategies share:
the statistics, the dead ends met (:class:`Report`), the configurations
already listed (distinct mode) and the result models.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from enum import Enum

from cfgplan.configuration.model import Assignment, Configuration
from cfgplan.planner import clock
from cfgplan.planner.finish import Models, admissible, build, fingerprint
from cfgplan.planner.ground import Grounder
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.partial import Partial
from cfgplan.planner.report import DeadEnd, Report
from cfgplan.planner.split import Split
from cfgplan.planner.successors import successors

Heuristic = Callable[[Partial], float | None]
"""A lower bound on what a node still costs; None when it has no completion."""

Splitter = Callable[[Partial], tuple[float | None, Split | None]]
"""The stronger bound, with the node's bound taken apart at its top item
(:mod:`cfgplan.planner.split`)."""


class Reprice(Enum):
    """Which open nodes a strategy must price again when the bounds change."""

    ALL = "all"
    REFINED = "refined"  # only those the stronger bound priced


@dataclass
class Stats:
    """What the search did: shown by ``--verbose`` and in JSON output."""

    nodes: int = 0  # nodes taken to be expanded or finished
    expansions: int = 0  # method instances expanded
    derivations: int = 0  # complete derivations met (duplicates included)
    duplicates: int = 0  # complete derivations whose configuration was listed already
    rejected: int = 0  # complete derivations found inadmissible (4.5 step 4)
    pruned: int = 0  # nodes the bounds proved to have no completion
    seconds: float = 0.0
    complete: bool = True  # False when a limit stopped the search early


@dataclass
class Grower:
    """Expands, settles, prices and finishes nodes for one search."""

    grounder: Grounder
    heuristic: Heuristic
    refine: Heuristic | None = None
    """A costlier, stronger bound; the strategy decides when to use it."""
    distinct: bool = True
    feasible: Heuristic | None = None
    """The cheapest test that a node can complete (0, or None: no completion),
    to price nodes with while :attr:`refine` dominates :attr:`heuristic`."""
    split: Splitter | None = None
    """:attr:`refine` taken apart at the top item: when given, a refined node's
    children are priced from its split (:mod:`cfgplan.planner.split`)."""
    given: frozenset[int] = frozenset()
    """Functionalities (labels) whose inputs may be fed from outside the
    search: the forced steps' ones in an independent part's search."""
    stats: Stats = field(default_factory=Stats)
    report: Report = field(default_factory=Report)
    seen: set[bytes] = field(default_factory=set)  # fingerprints listed (distinct)
    models: Models = field(default_factory=Models)
    options: SearchOptions = field(default_factory=SearchOptions)
    """When the stronger bound is tried, given up and relied on (and the
    strategies' settings)."""

    def __post_init__(self) -> None:
        self.levels = self.grounder.task.levels
        self.settled = 0  # nodes priced so far
        self.tried = 0  # refinements by the stronger bound so far
        self.raised = 0  # those that raised a priority (or pruned)
        self.dominated = 0  # those at least the first bound (or pruned)
        self.first = self.heuristic
        self.repriced: Reprice | None = None  # the bounds in use changed: what to re-price
        self.splits: dict[tuple[int, ...], Split] = {}  # refined nodes not yet expanded, by path
        self.lifted = 0  # children priced above their own bound by their parent's split

    @contextmanager
    def priced_by(self, heuristic: Heuristic, refine: Heuristic | None = None) -> Iterator[None]:
        """Price nodes with ``heuristic`` (and ``refine``) inside the block,
        with the bounds before it after: ``--all``'s walks, which need only
        whether a node can complete except where they look for the cheapest
        first (:mod:`cfgplan.planner.enumerate`)."""
        kept = self.heuristic, self.refine
        self.heuristic, self.refine = heuristic, refine
        try:
            yield
        finally:
            self.heuristic, self.refine = kept

    def start_over(self) -> None:
        """Forget the splits and what was met and listed, for a strategy that
        starts over with each child priced by its own bounds
        (:meth:`cfgplan.planner.search.BestFirst._again`): the statistics
        of the listing count again from nothing; nodes and expansions go on."""
        self.split = None
        self.splits.clear()
        self.lifted = 0
        self.seen.clear()
        self.report = Report()
        stats = self.stats
        stats.derivations = stats.duplicates = stats.rejected = 0

    def take_repriced(self) -> Reprice | None:
        """Which open nodes the strategy must price again since the bounds in
        use changed (:meth:`refined`), once: None when they did not."""
        which, self.repriced = self.repriced, None
        return which

    def children(self, node: Partial) -> Iterator[tuple[float, Partial]]:
        """Expand the method on top of ``node``; yield its settled children with
        their priorities (dead ends go to the report)."""
        self.stats.expansions += 1
        split = self.splits.pop(node.path, None)
        before = self.lifted
        for child in successors(self.grounder, node):
            clock.check()
            if isinstance(child, DeadEnd):
                self.report.note(child)
            elif split is None:
                yield from self.settle(child)
            else:
                yield from self._lift(node, split, self.settle(child))
        if split is not None and self.lifted > before:
            self.raised += 1  # the node's refinement paid: it priced its children

    def _lift(
        self, node: Partial, split: Split, settled: Iterator[tuple[float, Partial]]
    ) -> Iterator[tuple[float, Partial]]:
        """The settled children of one expansion of ``node``, priced at least
        by ``node``'s split (pruned where the media cannot carry it)."""
        depth = len(node.path)
        for priority, child in settled:
            if not child.done:
                price = split.prices.get(child.path[depth])
                if price == float("inf"):
                    self.stats.pruned += 1
                    continue
                if price is not None:
                    lifted = self.priority(node, split.rest + price)
                    if lifted > priority:
                        self.lifted += 1
                        priority = lifted
            yield priority, child

    def settle(self, node: Partial) -> Iterator[tuple[float, Partial]]:
        """Place the functionalities on top of the stack (one child per binding
        when one has several); yield each node that has a method on top, or is
        complete, with its priority: its cost, plus the bound unless complete."""
        task = self.grounder.task
        todo = [node]
        while todo:
            current = todo.pop()
            stack = current.stack
            if not stack or task.is_method(stack[0].call):
                if stack:
                    rest = self.heuristic(current)
                    if rest is None:
                        self.stats.pruned += 1
                        continue
                    priority = self.priority(current, rest)
                else:
                    priority = self.cost(current)
                self.settled += 1
                yield priority, current
                continue
            placed: list[Partial] = []
            for child in successors(self.grounder, current):
                if isinstance(child, DeadEnd):
                    self.report.note(child)
                else:
                    placed.append(child)
            todo.extend(reversed(placed))

    def priority(self, node: Partial, rest: float) -> float:
        """``cost + rest`` at its level as a lower bound, never above the level
        of a completion's cost (:meth:`cfgplan.planner.levels.Levels.bound`:
        rounded up to a multiple of the unit of costs, less a hair for the
        float sums of shared costs)."""
        return self.levels.bound(node.cost + rest)

    def cost(self, node: Partial) -> float:
        """A complete node's cost as configurations are ranked and reported
        (:meth:`cfgplan.planner.levels.Levels.cost`)."""
        return self.levels.cost(node.cost)

    def refined(self, node: Partial, priority: float, beaten: float | None = None) -> float | None:
        """The node's priority under the larger of both bounds; None: pruned.
        ``beaten``: the priority a raised node must pass for the raise to pay
        (best-first: the next node's; else any raise pays)."""
        if self.refine is None or self.settled < self.options.warm:
            return priority
        if self.split is not None:
            rest, split = self.split(node)
            if split is not None:
                self.splits[node.path] = split
        else:
            rest = self.refine(node)
        self.tried += 1
        if rest is None:
            self.raised += 1
            self.dominated += 1
            self.stats.pruned += 1
            return None
        raised = self.priority(node, rest)
        if raised >= priority:
            self.dominated += 1
        if raised > priority and (beaten is None or raised > beaten):
            self.raised += 1
        elif (
            self.tried >= self.options.trial
            and self.raised * self.options.pays < self.tried
            and self.dominated < self.tried
        ):
            self.refine = self.split = None  # it seldom helps here: give it up for this search
            self.splits.clear()
            # Nodes priced by the first bound stay right; the others are re-priced.
            refined_only = self.heuristic is self.first
            self.repriced = Reprice.REFINED if refined_only else Reprice.ALL
            self.heuristic = self.first
        rely = self.options.rely
        if self.tried == rely and self.dominated == rely and self.feasible is not None:
            # The stronger bound is all that counts here.
            self.heuristic, self.repriced = self.feasible, Reprice.ALL
        return max(priority, raised)

    def complete(self, node: Partial, total: float) -> Configuration | None:
        """Step 4 for a complete node, in the order configurations are listed:
        the configuration, or None (a repeat in distinct mode, or inadmissible)."""
        ident = fingerprint(node, self.grounder.numbering) if self.distinct else None
        if ident is not None and ident in self.seen:
            self.stats.derivations += 1
            self.stats.duplicates += 1
            return None
        config = self.finish(node, total, self.stats.derivations + 1)
        if config is None:
            return None
        self.stats.derivations += 1
        if ident is not None:
            self.seen.add(ident)
        return config

    def finish(self, node: Partial, total: float, derivation: int = 0) -> Configuration | None:
        """The admissible configuration of a complete node, or None (rejection reported)."""
        media = self.admissible(node)
        if media is None:
            return None
        return build(node, total, self.grounder.task, self.models, media, derivation)

    def admissible(self, node: Partial) -> tuple[Assignment, ...] | None:
        """Step 4's checks: the media assignment of a complete node, or None
        (rejection reported)."""
        result = admissible(node, self.grounder.task, self.given)
        if isinstance(result, DeadEnd):
            self.stats.rejected += 1
            self.report.reject(result)
            return None
        return result
