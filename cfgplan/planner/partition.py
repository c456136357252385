"""A second admissible bound: every pending item's cheapest expansion, with
shared costs partitioned among the items that may share them.

:mod:`cfgplan.planner.bound` stays admissible under sharing by *grouping*:
pending items that may reach a common functionality name count once (the
largest). On a convoy, where every member's pose may come from the same
camera, everything can share, so that bound counts one member's cost for the
whole convoy. Here, instead, every cost that can be shared is *divided*
(uniform cost partitioning, as in classical planning heuristics):

- a functionality instance not in C costs ``w / S``, where S is how many
  times it can occur in the pending items' derivations together (each item
  counts the most times it can occur in one of its derivations);
- a robot or device not in C, and not certain to be used, is charged once
  per expansion that places something on it directly, ``w / S``, S counted
  likewise over expansions;
- a channel costs ``w / S`` over the channels it might turn out identical
  to (merged, 4.5): of its kind and data, with the same ends where its ends
  are known functionality instances. An end at a method is not known until
  that method is expanded (the channel is re-wired then), so a channel with
  both ends known may merge with those that have the same sender or the
  same receiver and the other end open, or both ends open; a channel with
  only its receiver known, with every channel of that receiver, every one
  with only its sender known, and every open one; and so on. A channel
  costs nothing when C already holds one it might merge with. So the
  channels that end up as one channel are charged ``w`` at most, together:
  each of them counts all the others among its S.

Where the media let a functionality instance, robot or device serve only
so many of the expansions that bring it (each sends a view of its own over
one link), S is that many at most (:mod:`cfgplan.planner.capacity`).

Then the cost of each pending item is a plain minimum over its expansions,
leaving out those whose own global channels the media cannot carry on top
of the node's (:mod:`cfgplan.planner.room`), computed bottom-up over the
graph of ground instances (:mod:`cfgplan.planner.graph`; this bound is a
pass over it, as the capacity's and the parts' are), and the items' costs
add up: in
any completion, a shared cost is charged at most as often as it can occur,
each time ``w / S``, so never more than ``w`` in all. The search takes the
larger of the two bounds (:func:`cfgplan.planner.plan.combined`).

Items whose expansions can recur into themselves (a ground instance below
itself) have no finite occurrence count: for such tasks this bound is off.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from cfgplan.planner.capacity import Capacity
from cfgplan.planner.graph import graph_of
from cfgplan.planner.ground import Grounder
from cfgplan.planner.least import Least
from cfgplan.planner.numbering import Numbering
from cfgplan.planner.occurrences import Kept, Occurrences
from cfgplan.planner.partial import Partial
from cfgplan.planner.prices import Prices, Wire
from cfgplan.planner.split import Split, split_at
from cfgplan.planner.task import Ground


@dataclass(eq=False, repr=False)
class Partition:
    """The partitioned bound for one task; :meth:`estimate` on each node."""

    grounder: Grounder
    media: bool = True
    """Whether expansions the media cannot carry are priced as impossible
    (:attr:`cfgplan.planner.options.SearchOptions.media`)."""
    number: Numbering = field(init=False)
    """The small integers that stand for keys in counts and totals: the
    task's one numbering (:attr:`cfgplan.planner.ground.Grounder.numbering`),
    which canonical forms and fingerprints number their values by too."""

    def __post_init__(self) -> None:
        task, self.number = self.grounder.task, self.grounder.numbering
        self.graph = graph = graph_of(self.grounder, self.media)
        """The AND/OR graph of ground instances this bound is a pass over (the grounder's)."""
        self.room = graph.room
        self.occurrences = Occurrences(task, graph, self.number)
        """How often each key can occur below the pending items (the S of the rules)."""
        self.capacity = Capacity(task, self.room, self.number, graph.instances, graph.order)
        self.least = Least(self.room, self.number, graph.made)

    # -- the bound of a node ----------------------------------------------------
    def estimate(self, node: Partial, certain: frozenset[str]) -> float | None:
        """A lower bound on the cost still to come (0 when off), or None when
        some pending item has no derivation; ``certain`` are agents every
        completion uses: they are counted in full, once."""
        return self.split(node, certain, apart=False)[0]

    def split(
        self, node: Partial, certain: frozenset[str], apart: bool = True
    ) -> tuple[float | None, Split | None]:
        """:meth:`estimate`, and (``apart``) the bound taken apart at the top
        item, which the node expands next (:mod:`cfgplan.planner.split`; None
        when the bound is off)."""
        occurrences = self.occurrences
        if occurrences.cyclic:
            return 0.0, None
        task = self.grounder.task
        calls = tuple(item.call for item in node.stack)
        kept = occurrences.stack(calls)
        if kept.pending is None:
            return 0.0, None
        present, future = self._channels(node, kept)
        totals, shared = kept.waiting(future)
        load = self.room.load(node.channels)
        lowered = self.capacity.lower(totals, calls, load)
        if lowered:
            totals, shared = {**totals, **lowered}, {}
        prices = Prices(task, node, certain, totals, present, self.number, load, shared=shared)
        memo, costs = self._evaluate(kept, calls, prices, lowered)
        total = sum(map(prices.channel, future))
        total += sum(task.costs.agent(agent) for agent in certain - node.robots)
        agent = prices.agent
        for key, on in kept.items:
            total += memo[key]
            if on is not None:  # a pending functionality, on agent ``on``
                total += agent(on)
        if total == float("inf"):
            return None, None
        if not apart:
            return total, None
        top = self.graph.instances[node.stack[0].call]
        if top.functionality:
            return total, None
        found = costs.get(top.key) if costs is not None else None
        priced = self.least.priced(top, memo, prices) if found is None else found
        return total, split_at(top, total - memo[top.key], priced)

    def _evaluate(
        self, kept: Kept, calls: tuple[Ground, ...], prices: Prices, lowered: dict[int, int]
    ) -> tuple[dict[int, float], dict[int, tuple[float, ...]] | None]:
        """The cheapest derivation of each instance below the pending items
        ``calls`` at ``prices`` (and each expansion's price, when kept): from
        the last node with these pending items evaluated, when there is one
        and it pays; recorded for the next from the third node on (a stack
        met once or twice, as on a chain, is priced as cheaply as can be).
        ``lowered``: the totals the media lowered (:meth:`Kept.touched`)."""
        least = self.least
        orders = (self.graph.order(call) for call in dict.fromkeys(calls))
        if not kept.reuse or kept.evaluated < 2:
            kept.evaluated += 1
            memo = least.full(orders, prices)
            kept.reuse = len(memo) >= least.smallest
            return memo, None
        touched = kept.touched(lowered)
        if kept.last is None:
            kept.last = least.record(orders, prices, touched)
        else:
            evaluation = least.again(kept.last, prices, touched)
            if evaluation is None:  # too much changes between these nodes
                kept.last, kept.reuse = None, False
                return least.full(orders, prices), None
            kept.last = evaluation
        return kept.last.memo, kept.last.costs

    def _channels(self, node: Partial, kept: Kept) -> tuple[set[int], list[Wire]]:
        """The keys of the channels already in C (resolved), and the wires of
        those waiting for an end (each will be one channel of the
        configuration); ``kept``: the node's pending items
        (:meth:`cfgplan.planner.occurrences.Occurrences.stack`)."""
        present: set[int] = set()
        future: list[Wire] = []
        # The calls of the pending functionalities: an end at a method is not known.
        pending = {
            item.label: item.call
            for item, (_, on) in zip(node.stack, kept.items, strict=True)
            if on is not None
        }
        located, graph = node.located.get, self.graph
        for ch in node.channels:
            src, dst = located(ch.source), located(ch.target)
            if src is not None and dst is not None:
                present.update(graph.between(ch, src, dst).counted)
                continue
            sender = src.call if src is not None else pending.get(ch.source)
            receiver = dst.call if dst is not None else pending.get(ch.target)
            future.append(graph.wire(ch.kind, ch.data, sender, receiver))
        return present, future
