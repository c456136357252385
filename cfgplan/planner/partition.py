"""The second admissible bound, the partitioned one: what each key costs at a
node, the cheapest derivation of every instance at those prices, how often
each key can occur (the divisors of shared costs), their caps where the media
limit them, and children priced from their parent's bound.

What each key of the partitioned bound costs at one node
(the module's docstring gives the rules): the
keys counted, channels as the bound prices them (:class:`Wire`), the
prices of one node (:class:`Prices`), and the price of a method instance's
expansions at those prices (:func:`price_options`). The cheapest derivation
of each ground instance at them is this module's.

The cheapest derivation of every ground instance below a node's pending
items at its prices, for the partitioned
bound: :class:`Least`.

It evaluates a node's instances bottom-up. A node whose pending items are
those of a node evaluated before (siblings: the children of one expansion
whose body is all functionalities) starts from that evaluation and prices
again only the expansions that read a price that differs between the two
nodes, then the instances above them whose cheapest changed. Every value is
the one a fresh evaluation finds, float for float (each expansion's price is
added up in one order, :func:`~cfgplan.planner.partition.price_options`): the
search, its node counts and its answers do not depend on which nodes were
evaluated before.

How many times each key can occur in one derivation below a ground
instance, and in all of a stack of pending items: the counts S by which the
partitioned bound divides what may be shared (the module's docstring gives the rules).

The counts of an instance are a pass over the graph of ground instances
(:mod:`cfgplan.planner.graph`), children before parents: the most of each
key over its expansions, each expansion's the sum of its children's plus its
own channels and agents. A stack's sum is made from the sum of a stack met
before (its parent's, or a suffix's) a few keys at a time, and kept a while
(:class:`Kept`), with the last evaluation of a node with those items.

An instance that can recur into itself (below itself) has no finite count:
then every count is None and the bound is off.

How often a shared cost can occur where the media limit the expansions
that bring it (4.6): a cap on the divisors of the partitioned bound.

The partitioned bound divides a shared cost ``w`` (a functionality instance,
a robot or device) among the S times it can occur in the pending items'
derivations. When every expansion that brings it (its *carriers*) also sends
a global channel of its own between one pair of robots, it can occur only as
often as that pair's media carry such channels: N robots that may each crop
their view from one ceiling camera, each view 30 over the camera's link of
40, use that camera once among them, not N times. Dividing ``w`` by the
smaller number is as admissible as dividing by S: in every admissible
completion the cost is charged at most as often as it occurs. It is what
tells the bound that each robot pays for a camera of its own; without it the
search tries the partial assignments of robots to cameras (factorial in N)
before it accepts its first configuration.

A key (functionality instance or agent) is capped on a pair P when, over the
ground instances made so far:

- every carrier expansion brings it once and needs P (bandwidth above 0,
  :class:`cfgplan.planner.partial.Need`);
- the groups (pair, kind, data) it needs on P are not needed on P by a
  carrier of another ground instance, so no two carriers' channels merge;

and, at a node, no carrier instance occurs twice in one derivation of the
pending items together. The carriers a completion uses then each add a group
of their own to P: those whose group the node already loads, plus at most
``room / b`` more (``room``: what P's media carry beyond the node's load,
``b``: the least a carrier adds). The pending items that are the
functionality itself (or run on the agent) occur besides.

What the argument rests on: the load of a pair counts each group once, at
its largest bandwidth, so what matters is that the carriers' groups are
distinct (a carrier's channel merging with one that is not a carrier's
does no harm); a global channel keeps its two robots, a bandwidth written
in a method is never lowered (a merge keeps the larger, one left unset is
filled from ``:out``) (:mod:`cfgplan.planner.partial`); and every instance
below the pending items exists when :meth:`Capacity.lower` runs (the
partitioned bound counts them first), so no carrier is missed.

The partitioned bound of a node taken apart at its top item, to price the
node's children before they are refined.

A node expands its top item next (4.5 step 3), one child per expansion. The
partitioned bound of the node is the
node's cost plus the sum, over its pending items, of each item's cheapest
derivation at the node's prices. Any completion in which the top item takes
expansion ``k`` pays for that item at least expansion ``k``'s price at those
same prices (its own channels and agents, and its children's cheapest), so
the partition argument bounds it by the node's cost plus ``rest`` (the sum
without the top item) plus that price: a bound for child ``k`` and all it
settles into, got from the node's own refinement, without pricing the child.

A child whose expansion costs more than the cheapest is so priced above its
parent, and taken only when the search gets that far: most are never
refined. The bound depends on the parent, not on the child alone, so two
nodes reached by different choices with one canonical form may be priced
apart; :class:`cfgplan.planner.search.BestFirst` watches for that.

A second admissible bound: every pending item's cheapest expansion, with
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
one link), S is that many at most.

Then the cost of each pending item is a plain minimum over its expansions,
leaving out those whose own global channels the media cannot carry on top
of the node's (:mod:`cfgplan.planner.partial`), computed bottom-up over the
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

import heapq
from collections import Counter
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from math import inf as INF
from typing import NamedTuple, Protocol

from cfgplan.planner.graph import (
    Counts,
    Graph,
    Instance,
    Option,
    PriceKey,
    Wire,
    add,
    graph_of,
    most,
)
from cfgplan.planner.ground import Grounder, Numbering
from cfgplan.planner.partial import Load, Need, Partial, Room
from cfgplan.planner.task import Ground, Task

Fits = Callable[[tuple[Need, ...], Load], bool]
"""Whether the media carry an expansion's needs on top of a node's load
(:meth:`cfgplan.planner.partial.Room.fits`)."""


@dataclass(eq=False, repr=False)
class Prices:
    """What each key costs at one node: its weight, shared (the rules: the module's docstring)."""

    task: Task
    node: Partial
    certain: frozenset[str]
    totals: Counts
    present: set[int]
    number: Callable[[PriceKey], int]
    load: Load  # what the node's global channels load the media with (partial.py)
    agents: dict[str, float] = field(default_factory=dict)  # the agent prices found so far
    shared: dict[int, float] = field(default_factory=dict)
    """Each wire's ``weight / S`` found so far, by wire number: it reads
    ``totals`` only, so nodes given one ``totals`` (siblings,
    :class:`cfgplan.planner.partition.Kept`) share one of these."""

    def agent(self, agent: str) -> float:
        found = self.agents.get(agent)
        if found is None:
            found = 0.0
            if agent not in self.node.robots and agent not in self.certain:
                found = self.task.costs.agent(agent) / self.totals[self.number(("@", agent))]
            self.agents[agent] = found
        return found

    def channel(self, own: Wire) -> float:
        """A channel's price: nothing where C holds one it merges with, else
        its weight shared by the channels it may merge with (the sum of their
        counts, an int: the same in any order), found once per wire."""
        if own.free in self.present:
            return 0.0
        found = self.shared.get(own.number)
        if found is None:
            share = 0
            count = self.totals.get
            for key in own.shares:
                share += count(key, 0)
            found = self.shared[own.number] = own.weight / share
        return found

    def functionality(self, call: Ground, weight: float, key: int) -> float:
        """A functionality instance's price (key number ``key``): nothing
        where C holds it already, else its weight shared by the times it can
        occur (the rules: the module's docstring)."""
        return 0.0 if call in self.node.labels else weight / self.totals[key]


class PricedOption(Protocol):
    """What :func:`price_options` reads of an expansion
    (:class:`cfgplan.planner.graph.Option`)."""

    @property
    def needs(self) -> tuple[Need, ...]: ...
    @property
    def child_keys(self) -> tuple[int, ...]: ...
    @property
    def channels(self) -> tuple[Wire, ...]: ...
    @property
    def agents(self) -> tuple[str, ...]: ...


class Priced(Protocol):
    """What :func:`price_options` reads of a method instance
    (:class:`cfgplan.planner.graph.Instance`): its expansions."""

    @property
    def options(self) -> Sequence[PricedOption]: ...


def price_options(
    instance: Priced,
    positions: Iterable[int],
    priced: list[float],
    memo: dict[int, float],
    prices: Prices,
    fits: Fits,
) -> None:
    """Price the expansions of ``instance`` at ``positions`` into ``priced``,
    its children's cheapest in ``memo``: each one's children, then its own
    channels, then its agents, added in that order (one order, so one float);
    infinite where the media cannot carry its own global channels
    (:mod:`cfgplan.planner.partial`)."""
    agent_price, agent_prices = prices.agent, prices.agents
    channel, load = prices.channel, prices.load
    options = instance.options
    for position in positions:
        option = options[position]
        if option.needs and not fits(option.needs, load):
            priced[position] = float("inf")  # communication-inadmissible here
            continue
        cost = 0.0
        for child in option.child_keys:
            cost += memo[child]
        for own in option.channels:
            cost += channel(own)
        for agent in option.agents:
            price = agent_prices.get(agent)
            cost += agent_price(agent) if price is None else price
        priced[position] = cost


@dataclass(eq=False, repr=False, slots=True)
class Evaluation:
    """The cheapest derivation of every instance below one node's pending
    items at its ``prices`` (``memo``, by instance number), and each method
    instance's expansions priced (``costs``, in option order). ``touched``:
    the totals of the keys whose totals may differ from the summed counts of
    the pending items (channels waiting for an end, caps of
    :class:`Capacity`)."""

    prices: Prices
    touched: dict[int, int]
    memo: dict[int, float]
    costs: dict[int, tuple[float, ...]]


@dataclass(eq=False, repr=False)
class Least:
    """The cheapest derivations of ground instances at one node's prices:
    from scratch (:meth:`full`, :meth:`record`) or from another node's
    :class:`Evaluation` (:meth:`again`)."""

    room: Room
    """The media (its ``fits`` looked up at each use, so that it can be watched)."""
    number: Callable[[PriceKey], int]
    made: list[Instance]
    """The graph's instances in the order made (:attr:`cfgplan.planner.graph.Graph.made`):
    those after the first :attr:`indexed` are indexed when first needed (a
    search that never meets a stack twice never needs it)."""
    reuse: float = 0.75
    """Start from another node's evaluation only while fewer keys changed
    than this share of its instances (else pricing from scratch is cheaper)."""
    smallest: int = 64
    """Nor when fewer instances are below the pending items (pricing them
    from scratch costs less than comparing two nodes)."""
    readers: dict[int, list[tuple[int, Instance, tuple[int, ...]]]] = field(default_factory=dict)
    """For each key (of totals, of the channels in C, of an instance, of the
    media's load), the expansions whose price reads it: each method
    instance's number, the instance, and the positions of those options."""
    height: dict[int, int] = field(default_factory=dict)
    """An instance's height: 0 for a functionality, else one above its
    highest child (so children are priced before their parents)."""
    functionalities: dict[int, Instance] = field(default_factory=dict)
    reused: int = 0
    """How many evaluations :meth:`again` made (the others were from scratch)."""
    indexed: int = 0

    def _index(self) -> None:
        made = self.made
        for instance in made[self.indexed :]:
            self.index(instance)
        self.indexed = len(made)

    def index(self, instance: Instance) -> None:
        """Note what the expansions of ``instance`` read."""
        if instance.functionality:
            self.functionalities[instance.key] = instance
            return
        reading: dict[int, list[int]] = {}
        for position, option in enumerate(instance.options):
            keys: set[int] = {*option.child_keys, *option.agent_keys}
            for own in option.channels:
                keys.add(own.free)
                keys.update(own.shares)
            for need in option.needs:
                keys.add(need.group)
                keys.add(-1 - need.pair)
            for key in keys:
                reading.setdefault(key, []).append(position)
        readers = self.readers
        for key, positions in reading.items():
            readers.setdefault(key, []).append((instance.key, instance, tuple(positions)))

    def full(self, orders: Iterable[tuple[Instance, ...]], prices: Prices) -> dict[int, float]:
        """The cheapest derivation of every instance of ``orders`` (each
        children before parents), by instance number, from scratch."""
        memo: dict[int, float] = {}
        functionality, priced = prices.functionality, self.priced  # (the hot loop)
        for order in orders:
            for instance in order:
                key = instance.key
                if key not in memo:
                    memo[key] = (
                        functionality(instance.call, instance.weight, key)
                        if instance.functionality
                        else min(priced(instance, memo, prices), default=INF)
                    )
        return memo

    @staticmethod
    def _unpriced(
        orders: Iterable[tuple[Instance, ...]], memo: dict[int, float]
    ) -> Iterator[Instance]:
        """The instances of ``orders`` in order, each once (children before
        parents): those not in ``memo`` yet when their turn comes."""
        for order in orders:
            for instance in order:
                if instance.key not in memo:
                    yield instance

    def priced(self, instance: Instance, memo: dict[int, float], prices: Prices) -> list[float]:
        """Every expansion of ``instance`` priced, its children's cheapest in ``memo``."""
        found = [0.0] * len(instance.options)
        price_options(instance, range(len(found)), found, memo, prices, self.room.fits)
        return found

    def record(
        self, orders: Iterable[tuple[Instance, ...]], prices: Prices, touched: dict[int, int]
    ) -> Evaluation:
        """:meth:`full`, with every expansion's price kept, for :meth:`again`."""
        self._index()
        memo: dict[int, float] = {}
        costs: dict[int, tuple[float, ...]] = {}
        height = self.height
        for instance in self._unpriced(orders, memo):
            key = instance.key
            if instance.functionality:
                memo[key] = prices.functionality(instance.call, instance.weight, key)
                height[key] = 0
                continue
            priced = self.priced(instance, memo, prices)
            memo[key] = min(priced, default=INF)
            costs[key] = tuple(priced)  # no list: fewer objects for the collector
            if key not in height:
                height[key] = 1 + max(
                    (height[c] for o in instance.options for c in o.child_keys), default=0
                )
        return Evaluation(prices, touched, memo, costs)

    def again(
        self, before: Evaluation, prices: Prices, touched: dict[int, int]
    ) -> Evaluation | None:
        """The instances of ``before`` (a node with the same pending items)
        at ``prices``: only the expansions that read a price that differs
        are priced again, then the instances above them whose cheapest
        changed, children before parents. None when too much changed
        (:attr:`reuse`). The answer is made of ``before``'s maps, changed
        in place rather than copied: a caller keeps the answer only, as
        :class:`~cfgplan.planner.partition.Kept` does (``before`` is
        untouched when the answer is None)."""
        changed = self._changed(before, prices, touched)
        memo = before.memo
        if len(changed) > self.reuse * len(memo):
            return None
        costs = before.costs  # taken over, not copied: ``before`` is spent
        dirty: dict[int, tuple[Instance, set[int]]] = {}
        heap: list[tuple[int, int]] = []
        height, readers = self.height, self.readers

        def read(key: int) -> None:
            for number, instance, positions in readers.get(key, ()):
                if number not in memo:
                    continue  # not below these pending items
                found = dirty.get(number)
                if found is None:
                    dirty[number] = (instance, set(positions))
                    heapq.heappush(heap, (height[number], number))
                else:
                    found[1].update(positions)

        for key in changed:
            functionality = self.functionalities.get(key)
            if functionality is not None:
                if key not in memo:
                    continue
                value = prices.functionality(functionality.call, functionality.weight, key)
                if value == memo[key]:
                    continue
                memo[key] = value
            read(key)
        fits = self.room.fits
        while heap:
            _, key = heapq.heappop(heap)
            instance, positions = dirty.pop(key)
            priced = list(costs[key])
            price_options(instance, positions, priced, memo, prices, fits)
            costs[key] = tuple(priced)
            best = min(priced) if priced else INF
            if best != memo[key]:
                memo[key] = best
                read(key)
        self.reused += 1
        return Evaluation(prices, touched, memo, costs)

    def _changed(self, before: Evaluation, new: Prices, touched: dict[int, int]) -> set[int]:
        """The keys whose prices may differ between two nodes with the same
        pending items: totals changed (only touched keys can), functionalities
        placed in one only, channel keys in C in one only, agents free in one
        only, and the media's load (a few more do no harm: they are priced
        again, to the same)."""
        old = before.prices
        changed: set[int] = set()
        if before.touched is not touched and before.touched != touched:
            # (siblings: the same channels mostly wait, occurrences.Kept.waiting)
            changed.update(key for key, _ in before.touched.items() ^ touched.items())
        for call in old.node.labels.keys() ^ new.node.labels.keys():
            changed.add(self.number(("f", call)))
        changed.update(old.present ^ new.present)
        for agent in (old.node.robots | old.certain) ^ (new.node.robots | new.certain):
            changed.add(self.number(("@", agent)))
        if old.load != new.load:
            changed.update(key for key, _ in old.load.items() ^ new.load.items())
        return changed


STACKS = 64
"""Stacks of pending items whose summed counts (and last evaluation) are
kept, then forgotten all at once: siblings are refined soon after each other
(the search takes them at nearly the same priority), so a few suffice, and
memory stays bounded. As many stacks' capped keys are kept (:class:`Capacity`)."""

SUFFIXES = 4
"""How many of a stack's suffixes are looked up for a sum to start from
(a child's stack is its parent's with the top replaced by the top's body:
its suffix below the body was summed for the parent)."""


@dataclass(eq=False, repr=False, slots=True)
class Kept:
    """What is kept for one stack of pending items: their summed counts
    (None: the bound is off), and the last node with them evaluated
    (:class:`cfgplan.planner.partition.Least`: the next starts from it)."""

    pending: Counts | None
    items: tuple[tuple[int, str | None], ...] = ()
    """Each pending item's instance number, and the agent it runs on when
    it is a functionality (None: a method)."""
    last: Evaluation | None = None
    evaluated: int = 0  # nodes with them evaluated from scratch (the first two are)
    reuse: bool = True  # False: their nodes differ too much to start from another's
    _future: tuple[int, ...] = ()  # the wires :meth:`waiting` was given last (by id: made once)
    _totals: Counts | None = None  # and what it answered
    _shared: dict[int, float] = field(default_factory=dict)
    _raised: tuple[int, ...] = ()
    _touched: dict[int, int] | None = None

    def waiting(self, future: list[Wire]) -> tuple[Counts, dict[int, float]]:
        """The totals of a node with these pending items whose channels
        waiting for an end are ``future`` (each will be one channel of the
        configuration: its counted keys one more), and the wires' prices at
        those totals found so far (:attr:`cfgplan.planner.partition.Prices.shared`).
        Kept, as the last answer, from the second node with these items on
        (siblings' channels wait alike): the totals never to be changed, the
        prices only added to."""
        ident = tuple(map(id, future))
        if self._totals is None or ident != self._future:
            assert self.pending is not None  # the bound is on for these items
            totals = dict(self.pending)
            get = totals.get
            raised: list[int] = []
            for wire in future:
                raised.extend(wire.counted)
                for key in wire.counted:
                    totals[key] = get(key, 0) + 1
            if not self.evaluated:
                # The first node with these items: most stacks are met once
                # (a chain), and a copy of the totals kept for each of
                # them would add a tenth to the search's memory.
                return totals, {}
            self._future, self._totals, self._shared = ident, totals, {}
            self._raised, self._touched = tuple(raised), None
        return self._totals, self._shared

    def touched(self, lowered: dict[int, int]) -> dict[int, int]:
        """The totals of the keys whose totals differ from the pending items'
        counts at the node :meth:`waiting` answered last: those its waiting
        channels raised, and those the media ``lowered`` (never to be changed)."""
        if self._touched is None:
            assert self._totals is not None  # waiting() answered
            totals = self._totals
            self._touched = {key: totals[key] for key in self._raised}
        return {**self._touched, **lowered} if lowered else self._touched


@dataclass(eq=False, repr=False)
class Occurrences:
    """The counts of one task's ground instances and of the stacks of pending
    items met, over one graph."""

    task: Task
    graph: Graph
    number: Numbering
    """The small integers that stand for keys (the grounder's numbering)."""
    _counts: dict[Ground, Counts] = field(default_factory=dict)
    cyclic: bool = False
    """Some instance met can recur into itself: no counts (the bound is off)."""
    _stacks: dict[tuple[Ground, ...], Kept] = field(default_factory=dict)
    _sums: dict[tuple[Ground, ...], Counts] = field(default_factory=dict)
    """The summed counts of stacks and their suffixes (:meth:`_sum`)."""
    _extra: dict[Ground, tuple[Counter[Ground], Counts]] = field(default_factory=dict)
    """A method instance's counts taken apart (:meth:`_count`): the children
    every option has, and the most of the rest."""
    _over: dict[tuple[Ground, ...], tuple[Ground, Counts]] = field(default_factory=dict)
    """A stack's items below its top, and the top and the stack's summed
    counts: what a child's stack that ends with those items is summed from
    (:meth:`_derive`)."""

    def counts(self, call: Ground) -> Counts | None:
        """Most occurrences of each key in one derivation of ``call``; None
        when ``call`` can recur into itself."""
        if self.cyclic:
            return None
        found = self._counts.get(call)
        if found is not None:
            return found
        order = self.graph.below(call, self._counts)
        if order is None:
            self.cyclic = True
            return None
        for current in order:
            self._counts[current] = self._count(self.graph.instances[current])
        return self._counts[call]

    def _count(self, instance: Instance) -> Counts:
        """The most occurrences below ``instance``: over its options, the most
        of each option's. A child every option has is taken out first and
        added once, ``most(c + o for o) == c + most(o for o)`` key by key:
        the same integers, but a level of a deep chain, whose every version
        calls the level below, copies that level's counts once instead of
        walking them per version."""
        if instance.functionality:
            return {instance.key: 1}
        options = instance.options
        if not options:
            return {}
        shared = Counter(options[0].children)
        for option in options[1:]:
            shared &= Counter(option.children)
        total: Counts = {}
        for child in shared.elements():
            if total:
                add(total, self._counts[child])
            else:
                total = dict(self._counts[child])
        extra = most(self._option_count(option, shared) for option in options)
        self._extra[instance.call] = shared, extra
        add(total, extra)
        return total

    def _option_count(self, option: Option, shared: Counter[Ground]) -> Counts:
        """The occurrences in a derivation through ``option``, its children's
        most, less the ``shared`` children (counted by the caller)."""
        total: Counts = {}
        skip = shared.copy()
        for child in option.children:
            if skip[child] > 0:
                skip[child] -= 1
                continue
            add(total, self._counts[child])
        for own in option.channels:
            for key in own.counted:
                total[key] = total.get(key, 0) + 1
        for key in option.agent_keys:
            total[key] = total.get(key, 0) + 1
        return total

    def stack(self, calls: tuple[Ground, ...]) -> Kept:
        """The summed counts of the pending items ``calls`` (None: off, some
        can recur), made once per stack: the children of an expansion whose
        body is all functionalities share one (fusion: every sibling)."""
        found = self._stacks.get(calls)
        if found is None:
            if len(self._stacks) >= STACKS:
                self.forget()
            derived = self._derive(calls)
            if derived is not None:
                self._sums[calls] = derived
            found = self._stacks[calls] = Kept(self._sum(calls) if derived is None else derived)
            if found.pending is not None:
                method, instances = self.task.is_method, self.graph.instances
                found.items = tuple(
                    (instances[call].key, None if method(call) else call[1]) for call in calls
                )
                if calls and method(calls[0]):
                    self._over[calls[1:]] = calls[0], found.pending
        return found

    def forget(self) -> None:
        """Forget every stack's sums and evaluations (memory stays bounded:
        :data:`STACKS`)."""
        self._stacks.clear()
        self._sums.clear()
        self._over.clear()

    def _derive(self, calls: tuple[Ground, ...]) -> Counts | None:
        """The summed counts of ``calls`` made from those of a parent's stack,
        ``(top, *below)`` where ``calls`` ends with ``below`` (among the next
        :data:`SUFFIXES` suffixes): the top's counts are those of the children
        every option has plus the most of the rest (:meth:`_count`), so the
        sum is the parent's less that rest, less those children no longer
        pending (placed), plus the items that are not among them (and each
        pending functionality's agent). On a chain, a few keys a level
        instead of every level below (:meth:`_sum` adds up the level below
        the top). None when no such parent was summed. Integers: the same
        sums as made afresh (a key counted 0 times is left out, as there)."""
        for start in range(1, min(len(calls), SUFFIXES) + 1):
            found = self._over.get(calls[start:])
            if found is not None:
                break
        else:
            return None
        top, summed = found
        extra = self._extra.get(top)
        if extra is None:
            return None
        shared, rest = extra
        pending = Counter(calls[:start])
        totals = dict(summed)
        get, counts = totals.get, self.counts
        changed = list(rest)
        for key, n in rest.items():
            totals[key] = get(key, 0) - n
        for call in (shared - pending).elements():
            below = counts(call)
            assert below is not None  # below a top that does not recur
            changed.extend(below)
            for key, n in below.items():
                totals[key] = get(key, 0) - n
        for call in (pending - shared).elements():
            below = counts(call)
            if below is None:
                return None
            for key, n in below.items():
                totals[key] = get(key, 0) + n
        for call in calls[:start]:
            agent = self._agent(call)
            if agent is not None:
                totals[agent] = get(agent, 0) + 1
        for key in changed:
            if totals.get(key) == 0:
                del totals[key]
        return totals

    def _sum(self, calls: tuple[Ground, ...]) -> Counts | None:
        """The pending items' counts added up (None: some can recur). A
        node's stack is its parent's less the top, plus the top's body: so
        the sum of a stack is made from that of its longest suffix summed
        before (among the next :data:`SUFFIXES`), one item at a time, each
        step kept, and the next stack down the chain finds them. Integers:
        the same sums in any order."""
        sums = self._sums
        start = next(
            (i for i in range(1, min(len(calls), SUFFIXES) + 1) if calls[i:] in sums), None
        )
        if start is None:
            start = 1
            rest = self._add(calls[1:], {})
            if rest is None:
                return None
            sums[calls[1:]] = rest
        total = sums[calls[start:]]
        for i in range(start - 1, -1, -1):
            call = calls[i]
            counts = self.counts(call)
            if counts is None:
                return None
            # The larger copied, the smaller added to it: a level of a deep
            # chain counts every level below, the items below it few.
            small, total = (
                (total, dict(counts)) if len(counts) > len(total) else (counts, dict(total))
            )
            add(total, small)
            agent = self._agent(call)
            if agent is not None:
                total[agent] = total.get(agent, 0) + 1
            sums[calls[i:]] = total
        return total

    def _add(self, calls: tuple[Ground, ...], totals: Counts) -> Counts | None:
        """``totals`` with the counts of ``calls`` added (a pending
        functionality places itself on its agent too); None when one can recur."""
        get = totals.get
        for call in calls:
            counts = self.counts(call)
            if counts is None:
                return None
            for key, n in counts.items():
                totals[key] = get(key, 0) + n
            agent = self._agent(call)
            if agent is not None:
                totals[agent] = get(agent, 0) + 1
        return totals

    def _agent(self, call: Ground) -> int | None:
        """The key of the agent a pending item places itself on, counted once
        more in a stack's sum: a functionality's robot (None: a method)."""
        return None if self.task.is_method(call) else self.number(("@", call[1]))


UNLIMITED = 1 << 40
"""More carriers than any count of occurrences: what is not capped."""


class Limit(NamedTuple):
    """The carriers of one key on one pair: the least bandwidth one adds, and
    the groups each carrier instance may add (by instance number)."""

    pair: int
    bandwidth: float
    groups: tuple[tuple[int, frozenset[int]], ...]


class Capped(NamedTuple):
    """A key capped at one stack of pending items: its limits, and how many
    pending items are the functionality (or run on the agent) themselves."""

    key: int
    limits: tuple[Limit, ...]
    direct: int


@dataclass(eq=False, repr=False)
class Capacity:
    """The caps of one task, made from the AND/OR graph of its ground
    instances (``instances``, ``order``: :class:`cfgplan.planner.graph.Graph`)."""

    task: Task
    room: Room
    number: Callable[[object], int]
    instances: Mapping[Ground, Instance]
    order: Callable[[Ground], tuple[Instance, ...]]
    _made: int = -1  # how many instances the limits were made from
    _limits: dict[int, tuple[Limit, ...]] = field(default_factory=dict)
    _carriers: frozenset[int] = frozenset()
    _occurs: dict[int, Counts] = field(default_factory=dict)
    _stacks: dict[tuple[Ground, ...], tuple[Capped, ...]] = field(default_factory=dict)

    def lower(self, totals: Counts, calls: tuple[Ground, ...], load: Load) -> dict[int, int]:
        """What the occurrence counts ``totals`` of the pending items
        ``calls`` are lowered to by what the media let occur at a node that
        loads them with ``load``: the keys lowered, with their new totals
        (``totals`` itself is not changed)."""
        lowered: dict[int, int] = {}
        if not self.room.active:
            return lowered
        if len(self.instances) != self._made:
            self._make()
        for capped in self._capped(calls):
            now = totals.get(capped.key)
            if now is None or now <= 1:
                continue
            allowed = min(self._most(limit, load) for limit in capped.limits) + capped.direct
            if allowed < now:
                lowered[capped.key] = max(allowed, 1)
        return lowered

    def _most(self, limit: Limit, load: Load) -> int:
        """How many carriers of ``limit`` a completion of a node with ``load`` uses at most."""
        loaded = sum(1 for _, groups in limit.groups if any(g in load for g in groups))
        room = self.room.total.get(limit.pair, 0.0) - load.get(-1 - limit.pair, 0.0)
        fit = room / limit.bandwidth
        if not fit < UNLIMITED:  # a bandwidth of 1e-300, a capacity of 1e999: no cap
            return UNLIMITED
        return loaded + max(int(fit + 1e-9), 0)

    # -- what is capped at a stack of pending items -----------------------------
    def _capped(self, calls: tuple[Ground, ...]) -> tuple[Capped, ...]:
        found = self._stacks.get(calls)
        if found is None:
            if len(self._stacks) >= STACKS:
                self._stacks.clear()
            found = self._stacks[calls] = self._at(calls)
        return found

    def _at(self, calls: tuple[Ground, ...]) -> tuple[Capped, ...]:
        occurs: Counts = {}
        direct: Counts = {}
        for call in calls:
            if self.task.is_method(call):
                own = self.instances[call].key
                if own in self._carriers:
                    occurs[own] = occurs.get(own, 0) + 1
                for key, n in self._occurrences(call).items():
                    occurs[key] = occurs.get(key, 0) + n
            else:
                for key in (self.number(("f", call)), self.number(("@", call[1]))):
                    direct[key] = direct.get(key, 0) + 1
        capped = []
        for key, limits in self._limits.items():
            kept = tuple(
                limit
                for limit in limits
                if all(occurs.get(instance, 0) <= 1 for instance, _ in limit.groups)
            )
            if kept:
                capped.append(Capped(key, kept, direct.get(key, 0)))
        return tuple(capped)

    def _occurrences(self, call: Ground) -> Counts:
        """Most occurrences of each carrier instance in one derivation of ``call``."""
        for instance in self.order(call):
            if instance.key not in self._occurs:
                self._occurs[instance.key] = most(map(self._option_occurrences, instance.options))
        return self._occurs[self.instances[call].key]

    def _option_occurrences(self, option: Option) -> Counts:
        """The carrier occurrences in a derivation through ``option``."""
        total: Counts = {}
        for child, key in zip(option.children, option.child_keys, strict=True):
            if key in self._carriers:
                total[key] = total.get(key, 0) + 1
            add(total, self._occurs.get(self.instances[child].key, {}))
        return total

    # -- the limits, from the ground instances made so far ------------------------
    def _make(self) -> None:
        self._made = len(self.instances)
        self._occurs.clear()
        self._stacks.clear()
        functionalities = {i.key for i in self.instances.values() if i.functionality}
        carriers: dict[int, list[tuple[int, Option]]] = {}
        for instance in self.instances.values():
            for option in instance.options:
                brought = [k for k in option.child_keys if k in functionalities]
                for key in (*brought, *option.agent_keys):
                    carriers.setdefault(key, []).append((instance.key, option))
                for key in set(brought):
                    if brought.count(key) > 1:
                        carriers[key].append((-1, option))  # brought twice: never capped
        self._limits = {}
        for key, found in carriers.items():
            limits = _limits(found)
            if limits:
                self._limits[key] = limits
        self._carriers = frozenset(
            instance
            for limits in self._limits.values()
            for limit in limits
            for instance, _ in limit.groups
        )


def _limits(carriers: list[tuple[int, Option]]) -> tuple[Limit, ...]:
    """The limits of a key brought by ``carriers`` (instance number, option)."""
    if any(instance < 0 for instance, _ in carriers) or len({i for i, _ in carriers}) < 2:
        return ()
    pairs = set.intersection(
        *({need.pair for need in option.needs if need.bandwidth > 0} for _, option in carriers)
    )
    limits = []
    for pair in sorted(pairs):
        least = float("inf")
        groups: dict[int, set[int]] = {}
        for instance, option in carriers:
            on_pair = [need for need in option.needs if need.pair == pair]
            least = min(least, max(need.bandwidth for need in on_pair))
            groups.setdefault(instance, set()).update(need.group for need in on_pair)
        apart = sum(map(len, groups.values())) == len(set().union(*groups.values()))
        if apart:  # no group is needed by two carrier instances
            limits.append(
                Limit(pair, least, tuple((i, frozenset(g)) for i, g in sorted(groups.items())))
            )
    return tuple(limits)


class Split(NamedTuple):
    """A node's bound without its top item (``rest``), and the price of each
    of the top item's expansions by choice number, as
    :func:`cfgplan.planner.grow.successors` numbers them (infinite
    where the media cannot carry it, :mod:`cfgplan.planner.partial`)."""

    rest: float
    prices: dict[int, float]


def split_at(top: Instance, rest: float, priced: Sequence[float]) -> Split:
    """The split of a node whose top item is the method instance ``top``,
    its expansions ``priced`` in option order by its refinement
    (:class:`cfgplan.planner.partition.Least`: each price the one the
    refinement took the cheapest of, so that a child's bound is never above
    a completion's cost)."""
    return Split(rest, {option.choice: priced[n] for n, option in enumerate(top.options)})


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
        item, which the node expands next (None
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
        (:meth:`cfgplan.planner.partition.Occurrences.stack`)."""
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
