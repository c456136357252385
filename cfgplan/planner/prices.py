"""What each key of the partitioned bound costs at one node
(:mod:`cfgplan.planner.partition`, whose docstring gives the rules): the
keys counted, channels as the bound prices them (:class:`Wire`), the
prices of one node (:class:`Prices`), and the price of a method instance's
expansions at those prices (:func:`price_options`). The cheapest derivation
of each ground instance at them is :mod:`cfgplan.planner.least`'s.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import NamedTuple, Protocol

from cfgplan.planner.partial import Partial
from cfgplan.planner.room import Load, Need
from cfgplan.planner.task import Ground, Task

Fits = Callable[[tuple[Need, ...], Load], bool]
"""Whether the media carry an expansion's needs on top of a node's load
(:meth:`cfgplan.planner.room.Room.fits`)."""

PriceKey = tuple[object, ...]
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


class Wire(NamedTuple):
    """A channel as this bound prices it: ``weight / S``, S the sum of the
    counts of ``shares`` (the channels it might merge with, itself included);
    nothing when C holds a channel with key ``free``. Its occurrence counts
    towards ``counted``. Keys by their numbers; ``number``: the wire's own
    (:meth:`cfgplan.planner.graph.Graph.wire` makes each once), by which
    :attr:`Prices.shared` keeps its price."""

    weight: float
    counted: tuple[int, ...]
    shares: tuple[int, ...]
    free: int
    number: int


def wire_keys(
    kind: str, data: object, sender: Ground | None, receiver: Ground | None
) -> tuple[tuple[PriceKey, ...], tuple[PriceKey, ...], PriceKey]:
    """What a channel whose known ends (functionality calls) are given counts
    towards, what it shares with, and what makes it free (:class:`Wire`)."""
    every: PriceKey = ("*", kind, data)
    opened: PriceKey = ("?", kind, data)
    if sender is not None and receiver is not None:
        key: PriceKey = ("=", kind, data, sender, receiver)
        to: PriceKey = ("to", kind, data, receiver)
        by: PriceKey = ("from", kind, data, sender)
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


@dataclass(eq=False, repr=False)
class Prices:
    """What each key costs at one node: its weight, shared (the rules:
    :mod:`cfgplan.planner.partition`)."""

    task: Task
    node: Partial
    certain: frozenset[str]
    totals: Counts
    present: set[int]
    number: Callable[[PriceKey], int]
    load: Load  # what the node's global channels load the media with (room.py)
    agents: dict[str, float] = field(default_factory=dict)  # the agent prices found so far
    shared: dict[int, float] = field(default_factory=dict)
    """Each wire's ``weight / S`` found so far, by wire number: it reads
    ``totals`` only, so nodes given one ``totals`` (siblings,
    :class:`cfgplan.planner.occurrences.Kept`) share one of these."""

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
        occur (the rules: :mod:`cfgplan.planner.partition`)."""
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
    (:mod:`cfgplan.planner.room`)."""
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
