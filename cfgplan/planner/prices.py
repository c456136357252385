"""What each key of the partitioned bound costs at one node
(:mod:`cfgplan.planner.partition`, whose docstring gives the rules): the
keys counted, channels as the bound prices them (:class:`Wire`), the
prices of one node (:class:`Prices`), and the cheapest derivation of each
ground instance at those prices (:class:`Least`).

:class:`Least` evaluates a node's instances bottom-up. A node whose pending
items are those of a node evaluated before (siblings: the children of one
expansion whose body is all functionalities) starts from that evaluation and
prices again only the expansions that read a price that differs between the
two nodes, then the instances above them whose cheapest changed. Every value
is the one a fresh evaluation finds, float for float (each expansion's price
is added up in one order, :func:`price_options`): the search, its node counts
and its answers do not depend on which nodes were evaluated before.
"""

from __future__ import annotations

import heapq
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from cfgplan.planner.partial import Partial
from cfgplan.planner.room import Load, Need, Room
from cfgplan.planner.task import Ground, Task

if TYPE_CHECKING:
    from cfgplan.planner.graph import Instance

Fits = Callable[[tuple[Need, ...], Load], bool]
"""Whether the media carry an expansion's needs on top of a node's load
(:meth:`cfgplan.planner.room.Room.fits`)."""

Key = tuple[object, ...]
"""What costs, as counted: ``("f", call)`` for a functionality (so that no
call, a tuple of names, is ever mistaken for another key); ``("@", agent)``; for
channels of one kind and data: ``("=", kind, data, sender, receiver)`` (both
ends known), ``("?r", kind, data, receiver)`` (only the receiver known),
``("?s", kind, data, sender)`` (only the sender), ``("?", kind, data)`` (both
ends open), and the sums ``("*", kind, data)`` (every channel),
``("to", kind, data, receiver)`` and ``("from", kind, data, sender)`` (every
one with that end known), ``("?r*", kind, data)`` and ``("?s*", kind, data)``
(every one with only a receiver, only a sender known)."""

Counts = dict[int, int]
"""Most occurrences of each key in one derivation, keys by their numbers
(:attr:`cfgplan.planner.partition.Partition.number`: small integers hash
faster than nested tuples)."""


def add(total: Counts, counts: Counts) -> None:
    """Add ``counts`` to ``total`` (the occurrences of two parts of one derivation)."""
    get = total.get
    for key, n in counts.items():
        total[key] = get(key, 0) + n


def most(options: Iterable[Counts]) -> Counts:
    """The most occurrences of each key in any one of ``options`` (a method's
    expansions, each its occurrences: one derivation takes one expansion)."""
    found: Counts = {}
    for total in options:
        for key, n in total.items():
            if n > found.get(key, 0):
                found[key] = n
    return found


@dataclass(frozen=True, slots=True)
class Wire:
    """A channel as this bound prices it: ``weight / S``, S the sum of the
    counts of ``shares`` (the channels it might merge with, itself included);
    nothing when C holds a channel with key ``free``. Its occurrence counts
    towards ``counted``. Keys by their numbers."""

    weight: float
    counted: tuple[int, ...]
    shares: tuple[int, ...]
    free: int


def wire_keys(
    kind: str, data: object, sender: Ground | None, receiver: Ground | None
) -> tuple[tuple[Key, ...], tuple[Key, ...], Key]:
    """What a channel whose known ends (functionality calls) are given counts
    towards, what it shares with, and what makes it free (:class:`Wire`)."""
    every: Key = ("*", kind, data)
    opened: Key = ("?", kind, data)
    if sender is not None and receiver is not None:
        key: Key = ("=", kind, data, sender, receiver)
        to: Key = ("to", kind, data, receiver)
        by: Key = ("from", kind, data, sender)
        shares = (key, ("?r", kind, data, receiver), ("?s", kind, data, sender), opened)
        return (key, every, to, by), shares, key
    if receiver is not None:
        to = ("to", kind, data, receiver)
        counted = (("?r", kind, data, receiver), every, to, ("?r*", kind, data))
        return counted, (to, ("?s*", kind, data), opened), to
    if sender is not None:
        by = ("from", kind, data, sender)
        counted = (("?s", kind, data, sender), every, by, ("?s*", kind, data))
        return counted, (by, ("?r*", kind, data), opened), by
    return (opened, every), (every,), every


@dataclass
class Prices:
    """What each key costs at one node: its weight, shared (the rules:
    :mod:`cfgplan.planner.partition`)."""

    task: Task
    node: Partial
    certain: frozenset[str]
    totals: Counts
    present: set[int]
    number: Callable[[Key], int]
    load: Load  # what the node's global channels load the media with (room.py)
    agents: dict[str, float] = field(default_factory=dict)  # the agent prices found so far

    def agent(self, agent: str) -> float:
        found = self.agents.get(agent)
        if found is None:
            found = 0.0
            if agent not in self.node.robots and agent not in self.certain:
                found = self.task.agent_cost(agent) / self.totals[self.number(("@", agent))]
            self.agents[agent] = found
        return found

    def channel(self, own: Wire) -> float:
        if own.free in self.present:
            return 0.0
        share = 0  # an int: the same sum in any order
        count = self.totals.get
        for key in own.shares:
            share += count(key, 0)
        return own.weight / share


def price_options(
    instance: Instance,
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
    (:mod:`cfgplan.planner.room`)."""
    # Prices.channel and Prices.agent inlined (and all of this in Least.full).
    agent_price, agent_prices = prices.agent, prices.agents
    present, count, load = prices.present, prices.totals.get, prices.load
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
            if own.free not in present:
                share = 0
                for counted in own.shares:
                    share += count(counted, 0)
                cost += own.weight / share
        for agent in option.agents:
            price = agent_prices.get(agent)
            cost += agent_price(agent) if price is None else price
        priced[position] = cost


@dataclass(slots=True)
class Evaluation:
    """The cheapest derivation of every instance below one node's pending
    items at its ``prices`` (``memo``, by instance number), and each method
    instance's expansions priced (``costs``, in option order). ``touched``:
    the totals of the keys whose totals may differ from the summed counts of
    the pending items (channels waiting for an end, caps of
    :mod:`cfgplan.planner.capacity`)."""

    prices: Prices
    touched: dict[int, int]
    memo: dict[int, float]
    costs: dict[int, tuple[float, ...]]


@dataclass
class Least:
    """The cheapest derivations of ground instances at one node's prices:
    from scratch (:meth:`full`, :meth:`record`) or from another node's
    :class:`Evaluation` (:meth:`again`)."""

    room: Room
    """The media (its ``fits`` looked up at each use, so that it can be watched)."""
    number: Callable[[Key], int]
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
    readers: dict[int, list[tuple[Instance, int]]] = field(default_factory=dict)
    """For each key (of totals, of the channels in C, of an instance, of the
    media's load), the expansions (method instance, option position) whose
    price reads it."""
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
        readers = self.readers
        for position, option in enumerate(instance.options):
            keys: set[int] = {*option.child_keys, *option.agent_keys}
            for own in option.channels:
                keys.add(own.free)
                keys.update(own.shares)
            for need in option.needs:
                keys.add(need.group)
                keys.add(-1 - need.pair)
            for key in keys:
                readers.setdefault(key, []).append((instance, position))

    def full(self, orders: Iterable[tuple[Instance, ...]], prices: Prices) -> dict[int, float]:
        """The cheapest derivation of every instance of ``orders`` (each
        children before parents), by instance number, from scratch."""
        memo: dict[int, float] = {}
        # The hot loop of the search: price_options inlined, sums in its order.
        agent_price, agent_prices = prices.agent, prices.agents
        totals, present, placed = prices.totals, prices.present, prices.node.labels
        count = totals.get
        fits, load = self.room.fits, prices.load
        for order in orders:
            for instance in order:
                key = instance.key
                if key in memo:
                    continue
                if instance.functionality:
                    memo[key] = 0.0 if instance.call in placed else instance.weight / totals[key]
                    continue
                best = float("inf")
                for option in instance.options:
                    if option.needs and not fits(option.needs, load):
                        continue  # communication-inadmissible below this node
                    cost = 0.0
                    for child in option.child_keys:
                        cost += memo[child]
                    for own in option.channels:
                        if own.free not in present:
                            share = 0
                            for counted in own.shares:
                                share += count(counted, 0)
                            cost += own.weight / share
                    for agent in option.agents:
                        price = agent_prices.get(agent)
                        cost += agent_price(agent) if price is None else price
                    if cost < best:
                        best = cost
                memo[key] = best
        return memo

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
        totals, placed = prices.totals, prices.node.labels
        for order in orders:
            for instance in order:
                key = instance.key
                if key in memo:
                    continue
                if instance.functionality:
                    memo[key] = 0.0 if instance.call in placed else instance.weight / totals[key]
                    height[key] = 0
                    continue
                priced = self.priced(instance, memo, prices)
                memo[key] = min(priced, default=float("inf"))
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
        (:attr:`reuse`)."""
        changed = self._changed(before, prices, touched)
        memo = before.memo
        if len(changed) > self.reuse * len(memo):
            return None
        memo = dict(memo)
        costs = dict(before.costs)
        dirty: dict[int, tuple[Instance, set[int]]] = {}
        heap: list[tuple[int, int]] = []
        height, readers = self.height, self.readers

        def read(key: int) -> None:
            for instance, position in readers.get(key, ()):
                if instance.key not in memo:
                    continue  # not below these pending items
                found = dirty.get(instance.key)
                if found is None:
                    dirty[instance.key] = (instance, {position})
                    heapq.heappush(heap, (height[instance.key], instance.key))
                else:
                    found[1].add(position)

        placed, totals = prices.node.labels, prices.totals
        for key in changed:
            functionality = self.functionalities.get(key)
            if functionality is not None:
                if key not in memo:
                    continue
                value = 0.0 if functionality.call in placed else functionality.weight / totals[key]
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
            best = min(priced, default=float("inf"))
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
        changed = {key for key, _ in before.touched.items() ^ touched.items()}
        for call in old.node.labels.keys() ^ new.node.labels.keys():
            changed.add(self.number(("f", call)))
        changed.update(old.present ^ new.present)
        for agent in (old.node.robots | old.certain) ^ (new.node.robots | new.certain):
            changed.add(self.number(("@", agent)))
        if old.load != new.load:
            changed.update(key for key, _ in old.load.items() ^ new.load.items())
        return changed
