"""Pricing the nodes of one search: its bounds, and the rule for giving the
stronger one up (the strategies order nodes, the pricer prices them).

4.5 ranks configurations by cost; searched best-first, a node's priority is
the cost of its settled part plus a lower bound on what it must still add.
Two admissible bounds are at hand. The *first*
(:mod:`cfgplan.planner.bound`) is cheap: every node is priced by it as it
is settled (:meth:`Pricer.price`). The *stronger*
(:mod:`cfgplan.planner.partition`) is dear: a strategy applies it lazily,
to the node it takes (:meth:`Pricer.refined`); taken apart at that node's top
item (:mod:`cfgplan.planner.partition`) it also prices the node's children
(:meth:`Pricer.expanded`), most of which are then never refined themselves.

Whether the stronger bound pays for itself is decided here, and only here
(:class:`~cfgplan.planner.options.SearchOptions`: ``warm``, ``trial``,
``pays``, ``rely``): tried once a search has settled ``warm`` nodes, given up
when it seldom raises a priority, and relied on alone when it always
dominates the first. A strategy learns from :meth:`Pricer.take_repriced`
when the bound given up leaves open nodes to price again. Dropping or
adding an admissible bound never changes what is found nor its order, only
how many nodes are taken (tests/planner/test_pricer.py).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from enum import Enum

from cfgplan.planner.costs import Levels
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.partial import Partial
from cfgplan.planner.partition import Split
from cfgplan.planner.report import Stats

Heuristic = Callable[[Partial], float | None]
"""A lower bound on what a node still costs; None when it has no completion."""

Splitter = Callable[[Partial], tuple[float | None, Split | None]]
"""The stronger bound, with the node's bound taken apart at its top item
(:mod:`cfgplan.planner.partition`)."""

INFINITE = float("inf")


class Reprice(Enum):
    """Which open nodes a strategy must price again when the bounds change."""

    ALL = "all"
    REFINED = "refined"  # only those the stronger bound priced


@dataclass(eq=False, repr=False)
class Pricer:
    """The bounds of one search, which of them are in use, and why.

    Made with the bounds (``first``, and optionally ``stronger`` and its
    ``split``); the other slots are the rule's memory, changed only by the
    pricer's own methods."""

    levels: Levels
    """Rounds priorities and costs to the task's unit of cost (:mod:`cfgplan.planner.costs`)."""
    first: Heuristic
    """The first bound: every node settled is priced by it."""
    stronger: Heuristic | None = None
    """A costlier, stronger bound, applied to the nodes a strategy takes."""
    feasible: Heuristic | None = None
    """The cheapest test that a node can complete (0, or None: no completion):
    what prices settled nodes once the stronger bound is relied on alone."""
    split: Splitter | None = None
    """:attr:`stronger` taken apart at the top item: when given, a refined
    node's children are priced from its split."""
    options: SearchOptions = field(default_factory=SearchOptions)
    """When the stronger bound is tried, given up and relied on."""
    stats: Stats = field(default_factory=Stats)
    """The search's statistics: the pricer counts the nodes it prunes."""

    heuristic: Heuristic = field(init=False)
    """The bound settled nodes are priced by now: :attr:`first`, or
    :attr:`feasible` once the stronger bound is relied on."""
    refine: Heuristic | None = field(init=False)
    """The stronger bound while it is kept; None once given up."""
    settled: int = field(init=False, default=0)
    """Nodes priced so far (the stronger bound waits for ``warm`` of them)."""
    tried: int = field(init=False, default=0)
    """Refinements by the stronger bound so far."""
    raised: int = field(init=False, default=0)
    """Those that paid: pruned a node, raised its priority past the next
    node's, or priced some of its children above their own bound."""
    dominated: int = field(init=False, default=0)
    """Those at least the first bound (or pruned)."""
    lifted: int = field(init=False, default=0)
    """Children priced above their own bound by their parent's split."""
    repriced: Reprice | None = field(init=False, default=None)
    """The bounds in use changed: which open nodes to price again."""
    splits: dict[tuple[int, ...], Split] = field(init=False, default_factory=dict)
    """The splits of refined nodes not yet expanded, by path."""

    def __post_init__(self) -> None:
        self.heuristic = self.first
        self.refine = self.stronger

    # -- pricing settled nodes -----------------------------------------------------

    def price(self, node: Partial) -> float | None:
        """A node just settled priced (:meth:`again`), and counted towards
        ``warm`` unless pruned."""
        priority = self.again(node)
        if priority is not None:
            self.settled += 1
        return priority

    def priority(self, node: Partial, rest: float) -> float:
        """``cost + rest`` at its level as a lower bound, never above the level
        of a completion's cost (:meth:`cfgplan.planner.costs.Levels.bound`:
        rounded up to a multiple of the unit of costs, less a hair for the
        float sums of shared costs)."""
        return self.levels.bound(node.cost + rest)

    def cost(self, node: Partial) -> float:
        """A complete node's cost as configurations are ranked and reported
        (:meth:`cfgplan.planner.costs.Levels.cost`)."""
        return self.levels.cost(node.cost)

    def expanded(
        self, node: Partial, children: Iterator[Partial]
    ) -> Iterator[tuple[float, Partial]]:
        """The settled ``children`` of one expansion of ``node``, priced: by
        the bound in use, and at least by ``node``'s split when it was refined
        (pruned where the media cannot carry the child's expansion)."""
        split = self.splits.pop(node.path, None)
        before = self.lifted
        depth = len(node.path)
        for child in children:
            priority = self.price(child)
            if priority is None:
                continue
            if split is not None and not child.done and len(child.path) > depth:
                price = split.prices.get(child.path[depth])
                if price == INFINITE:
                    self.stats.pruned += 1
                    continue
                if price is not None:
                    lifted = self.priority(node, split.rest + price)
                    if lifted > priority:
                        self.lifted += 1
                        priority = lifted
            yield priority, child
        if split is not None and self.lifted > before:
            self.raised += 1  # the node's refinement paid: it priced its children

    def again(self, node: Partial) -> float | None:
        """A node's priority by the bound in use: a complete node's cost,
        else its cost plus that bound; None when the bound proves it has no
        completion (counted as pruned). Also an open node's, priced again
        when the bounds in use changed (:meth:`take_repriced`)."""
        if node.done:
            return self.cost(node)
        rest = self.heuristic(node)
        if rest is None:
            self.stats.pruned += 1
            return None
        priority = self.priority(node, rest)
        return node.floor if node.floor > priority else priority

    def floor(
        self, nodes: Iterable[Iterator[Partial]], beaten: float | None = None
    ) -> float | None:
        """The least priority of ``nodes`` (a replay's deviations, each settled,
        :func:`cfgplan.planner.grow.deviations`), by the bound in use: a
        lower bound on every derivation that deviates; None when none can
        complete. Once one is at most ``beaten``, that one's (the rest are
        not priced)."""
        least = None
        for settled in nodes:
            for node in settled:
                if node.done:
                    priority = self.cost(node)
                else:
                    rest = self.heuristic(node)
                    if rest is None:
                        continue  # no completion (not counted as pruned: never queued)
                    priority = self.priority(node, rest)
                if least is None or priority < least:
                    least = priority
                    if beaten is not None and least <= beaten:
                        return least
        return least

    # -- the stronger bound, lazily ------------------------------------------------

    @property
    def lazy(self) -> bool:
        """Whether nodes are refined when taken (the stronger bound is kept)."""
        return self.refine is not None

    def refined(self, node: Partial, priority: float, beaten: float | None = None) -> float | None:
        """The node's priority under the larger of both bounds; None: pruned.
        ``beaten``: the priority a raised node must pass for the raise to pay
        (best-first: the next node's; else any raise pays).

        Here is the rule for giving the stronger bound up, and for relying on
        it alone (:class:`~cfgplan.planner.options.SearchOptions`)."""
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
            # The stronger bound is all that counts here: nodes settled from
            # now on are priced by ``feasible``. The open nodes keep their
            # priorities, lower bounds still, and each is refined when taken,
            # as before; priced again by ``feasible`` they would only drop to
            # their cost, to be taken and refined anew at once (chain D=200:
            # 82 refinements of the deepest stacks for nothing). Twins priced
            # apart so are met as those priced apart by a split
            # (:meth:`cfgplan.planner.search.BestFirst._supersede`).
            self.heuristic = self.feasible
        return max(priority, raised)

    def take_repriced(self) -> Reprice | None:
        """Which open nodes the strategy must price again since the bounds in
        use changed (:meth:`refined`), once: None when they did not."""
        which, self.repriced = self.repriced, None
        return which

    def warmed(self, nodes: int) -> None:
        """Count ``nodes`` settled by another pricer of the same search
        towards ``warm``: ``--all``'s first walk, given up after
        :attr:`SearchOptions.one_pass` nodes, shows the search is no small one."""
        self.settled += nodes

    def discard(self, node: Partial) -> None:
        """``node`` will not be expanded (a twin of a node expanded before): forget its split."""
        self.splits.pop(node.path, None)
