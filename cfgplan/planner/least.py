"""The cheapest derivation of every ground instance below a node's pending
items at its prices (:mod:`cfgplan.planner.prices`), for the partitioned
bound (:mod:`cfgplan.planner.partition`): :class:`Least`.

It evaluates a node's instances bottom-up. A node whose pending items are
those of a node evaluated before (siblings: the children of one expansion
whose body is all functionalities) starts from that evaluation and prices
again only the expansions that read a price that differs between the two
nodes, then the instances above them whose cheapest changed. Every value is
the one a fresh evaluation finds, float for float (each expansion's price is
added up in one order, :func:`~cfgplan.planner.prices.price_options`): the
search, its node counts and its answers do not depend on which nodes were
evaluated before.
"""

from __future__ import annotations

import heapq
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from math import inf as INF
from typing import TYPE_CHECKING

from cfgplan.planner.prices import PriceKey, Prices, price_options
from cfgplan.planner.room import Room

if TYPE_CHECKING:
    from cfgplan.planner.graph import Instance


@dataclass(eq=False, repr=False, slots=True)
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
        functionality, fits = prices.functionality, self.room.fits
        for order in orders:
            for instance in order:
                key = instance.key
                if key in memo:
                    continue
                if instance.functionality:
                    memo[key] = functionality(instance.call, instance.weight, key)
                    continue
                priced = [0.0] * len(instance.options)
                price_options(instance, range(len(priced)), priced, memo, prices, fits)
                memo[key] = min(priced, default=INF)
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
        for order in orders:
            for instance in order:
                key = instance.key
                if key in memo:
                    continue
                if instance.functionality:
                    memo[key] = prices.functionality(instance.call, instance.weight, key)
                    height[key] = 0
                    continue
                priced = self.priced(instance, memo, prices)
                memo[key] = min(priced) if priced else INF
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
        :class:`~cfgplan.planner.occurrences.Kept` does (``before`` is
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
