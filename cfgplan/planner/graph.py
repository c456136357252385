"""The AND/OR graph of ground instances (4.5), and the passes over it made once
per task and goal.

The AND/OR graph of ground instances (4.5): every method instance with one
option per feasible expansion (its method versions in domain order, the
bindings of their preconditions in state order), every functionality
instance with its weight. Made on demand from the grounder's expansions,
each instance once, and kept with the grounder (:func:`graph_of`: one per task,
as the grounder is, :func:`cfgplan.planner.plan.analysis`), numbered by its
numbering.

The passes over it are elsewhere: what every expansion of an instance
contains (:mod:`cfgplan.planner.bound`, the first bound), the partitioned
bound's occurrence counts and cheapest derivations (:mod:`cfgplan.planner.partition`,
:mod:`cfgplan.planner.partition`, :mod:`cfgplan.planner.partition`,
:mod:`cfgplan.planner.partition`), how often the
media let a shared cost occur (:mod:`cfgplan.planner.partition`), and the
independent parts of a goal (:mod:`cfgplan.planner.combine`). What the
graph holds of an expansion is what those passes read: its children and
their numbers, its own channels as the bound prices them
(:class:`~cfgplan.planner.partition.Wire`), the agents its functionalities run
on, and what its global channels need of the media
(:mod:`cfgplan.planner.partial`).

Which method instances may occur again in one derivation: the
ones a search remembers for replays (:mod:`cfgplan.planner.grow`). Passes
over the grounder's graph of ground instances,
made once per task and goal (:meth:`cfgplan.planner.grow.Grower`), with the
recursion guard of 4.5 ignored: they over-approximate, which only makes a
search remember more than it replays.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Container, Iterable
from dataclasses import dataclass, field
from typing import NamedTuple

from cfgplan.planner.ground import ChannelSpec, Expansion, Grounder, Numbering
from cfgplan.planner.partial import Channel, Need, Placed, Room, channel_number
from cfgplan.planner.report import DeadEnd
from cfgplan.planner.task import Ground

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


class Option(NamedTuple):
    """One expansion of a method, as the passes over the graph see it."""

    expansion: Expansion  # the grounder's, which it stands for (what the summaries read)
    child_keys: tuple[int, ...]  # its children's numbers
    channels: tuple[Wire, ...]
    agents: tuple[str, ...]  # agents its functionality children run on, each once
    agent_keys: tuple[int, ...]  # their numbers as keys ("@", agent)
    needs: tuple[Need, ...]  # what its own global channels need of the media
    choice: int = 0  # its number among the method's expansions, as successors numbers them

    @property
    def children(self) -> tuple[Ground, ...]:
        """Its body's calls (the expansion's)."""
        return self.expansion.body


class Instance(NamedTuple):
    """A ground instance in the AND/OR graph: a functionality (no options, its
    weight) or a method with one option per feasible expansion."""

    call: Ground
    functionality: bool
    options: tuple[Option, ...] = ()
    weight: float = 0.0
    key: int = -1  # its number: the key of a functionality; a method's in memos


@dataclass(eq=False, repr=False)
class Graph:
    """The ground instances met so far, each made once, and what is below each."""

    grounder: Grounder
    room: Room
    """The media (what an option's global channels need of them)."""
    number: Numbering
    """The small integers that stand for keys (instances, agents, channels)."""
    instances: dict[Ground, Instance] = field(default_factory=dict)
    made: list[Instance] = field(default_factory=list)
    """Every instance, in the order made (a pass indexes those new to it)."""
    _orders: dict[Ground, tuple[Instance, ...]] = field(default_factory=dict)
    _below_sets: dict[Ground, dict[int, Instance]] = field(default_factory=dict)
    """Each ordered instance's :meth:`order` as a map from instance numbers."""
    _wires: dict[tuple[object, ...], Wire] = field(default_factory=dict)
    _between: dict[tuple[int, int, int], Wire] = field(default_factory=dict)
    """:meth:`between`'s wires by channel number and the ends' names."""

    def wire(self, kind: str, data: object, sender: Ground | None, receiver: Ground | None) -> Wire:
        """A channel of ``kind`` and ``data`` with the known ends given (made once)."""
        ident = (kind, data, sender, receiver)
        found = self._wires.get(ident)
        if found is None:
            counted, shares, free = wire_keys(kind, data, sender, receiver)
            weight = self.grounder.task.costs.channel(kind)
            number = self.number
            found = Wire(
                weight,
                tuple(map(number, counted)),
                tuple(map(number, shares)),
                number(free),
                len(self._wires),
            )
            self._wires[ident] = found
        return found

    def between(self, channel: Channel, sender: Placed, receiver: Placed) -> Wire:
        """:meth:`wire` of ``channel`` with both ends placed, looked up by
        small integers (its number and the ends' names: the same kind, data
        and calls) rather than by the calls themselves."""
        numbered = channel.number  # (most are numbered when made: no call then)
        if numbered < 0:
            numbered = channel_number(channel, self.number)
        ident = (numbered, sender.name, receiver.name)
        found = self._between.get(ident)
        if found is None:
            found = self._between[ident] = self.wire(
                channel.kind, channel.data, sender.call, receiver.call
            )
        return found

    def instance(self, call: Ground) -> Instance:
        found = self.instances.get(call)
        if found is None:
            task = self.grounder.task
            schema = task.functionality(call)
            if schema is not None:
                weight = task.costs.functionality(schema, call)
                found = Instance(call, True, weight=weight, key=self.number(("f", call)))
            else:
                options = []
                choice = 0
                for method in task.versions(call):
                    for expansion in self.grounder.expansions(method, call):
                        if not isinstance(expansion, DeadEnd):
                            options.append(self._option(expansion, choice))
                        choice += 1
                found = Instance(call, False, tuple(options), key=self.number(("f", call)))
            self.instances[call] = found
            self.made.append(found)
        return found

    def order(self, call: Ground) -> tuple[Instance, ...]:
        """Every instance below ``call`` (itself last), children before
        parents: the order :meth:`cfgplan.planner.partition.Least.full` evaluates
        them in, made once."""
        found = self.reach(call)
        assert found is not None  # counts() found no recursion below the pending items
        return found

    def reach(self, call: Ground) -> tuple[Instance, ...] | None:
        """:meth:`order`, or None when an instance recurs below itself. Each
        instance's order is its children's, joined without repeats, then
        itself: made from theirs (copies of small-integer maps), not by a walk
        below every level of a deep chain again."""
        found = self._orders.get(call)
        if found is None:
            below = self.below(call, self._below_sets)
            if below is None:
                return None
            sets, orders = self._below_sets, self._orders
            for current in below:
                instance = self.instance(current)
                joined: dict[int, Instance] = {}
                # Each child once (on a chain every version calls the level
                # below): the same map, its keys in the same order.
                for child in dict.fromkeys(
                    c for option in instance.options for c in option.children
                ):
                    joined.update(sets[child])
                joined[instance.key] = instance
                sets[current] = joined
                orders[current] = tuple(joined.values())
            found = orders[call]
        return found

    def below(self, call: Ground, done: Container[Ground]) -> list[Ground] | None:
        """The instances below ``call`` (itself included) not in ``done``,
        children before parents, found without recursion; None when one is
        met again on its own path (the recursion guard of 4.5 would prune it
        there: its occurrences have no bound)."""
        order: list[Ground] = []
        state: dict[Ground, bool] = {}  # True: on the path; False: finished
        stack: list[tuple[Ground, bool]] = [(call, False)]
        while stack:
            current, finished = stack.pop()
            if finished:
                state[current] = False
                order.append(current)
                continue
            if current in done:
                continue
            on_path = state.get(current)
            if on_path:
                return None
            if on_path is False:
                continue
            state[current] = True
            stack.append((current, True))
            for option in self.instance(current).options:
                stack.extend((child, False) for child in option.children)
        return order

    def _option(self, expansion: Expansion, choice: int) -> Option:
        task = self.grounder.task
        channels = tuple(self._own(expansion, spec) for spec in expansion.channels)
        agents = tuple(dict.fromkeys(c[1] for c in expansion.body if not task.is_method(c)))
        keys = tuple(self.number(("@", agent)) for agent in agents)
        children = tuple(self.number(("f", call)) for call in expansion.body)
        needs = self.room.needs(expansion.channels)
        return Option(expansion, children, channels, agents, keys, needs, choice)

    def _own(self, expansion: Expansion, spec: ChannelSpec) -> Wire:
        """An own channel of an expansion: an end at a functionality of the body
        is known, one at a method is not (it is re-wired when that is expanded)."""
        task = self.grounder.task
        kind, _, source, target, data, _ = spec
        sender, receiver = expansion.body[source], expansion.body[target]
        known_sender = None if task.is_method(sender) else sender
        known_receiver = None if task.is_method(receiver) else receiver
        return self.wire(kind, data, known_sender, known_receiver)


def graph_of(grounder: Grounder, media: bool = True) -> Graph:
    """The AND/OR graph of ``grounder``'s ground instances, made once and kept
    with it (:attr:`Grounder.graphs`): both bounds (the summaries and the
    partitioned bound), the capacity caps and the independent parts are
    passes over it. ``media``: whether an option notes what its global
    channels need of the media (:attr:`cfgplan.planner.options.SearchOptions.media`)."""
    found = grounder.graphs.get(media)
    if not isinstance(found, Graph):
        room = Room(grounder.task, grounder.numbering, media)
        found = grounder.graphs[media] = Graph(grounder, room, grounder.numbering)
    return found


def repeatable(
    graph: Graph, roots: Iterable[Ground], least: int = 1, worth: float = 0
) -> frozenset[Ground]:
    """The method instances below ``roots`` that may occur twice in one
    derivation (the recursion guard ignored): below two method items of one
    option's body, or below two roots; and whose derivations may take at
    least ``least`` method expansions (one below itself: any). Only they are
    remembered; none when replays could save fewer than ``worth`` expansions
    in all (each later occurrence of each, at its longest: the thesis's
    build-a-wall, two or three short repeats)."""
    task = graph.grounder.task
    reach: dict[Ground, frozenset[Ground]] = {}

    def below(call: Ground) -> frozenset[Ground]:
        found = reach.get(call)
        if found is None:
            seen = {call}
            todo = [call]
            while todo:
                current = todo.pop()
                for option in graph.instance(current).options:
                    for child in option.children:
                        if child not in seen and task.is_method(child):
                            seen.add(child)
                            todo.append(child)
            found = reach[call] = frozenset(seen)
        return found

    methods = [call for call in roots if task.is_method(call)]
    found: set[Ground] = set()
    _twice(methods, below, found)
    for call in {c for root in methods for c in below(root)}:
        for option in graph.instance(call).options:
            slots = [child for child in option.children if task.is_method(child)]
            if len(slots) > 1:
                _twice(slots, below, found)
    if least > 1 or worth > 0:
        longest = _longest(graph, found)
        found = {call for call in found if longest[call] >= least}
        if worth > 0 and found:
            occurs = _occurrences(graph, methods, {c for root in methods for c in below(root)})
            saved = sum((occurs[call] - 1) * longest[call] for call in found)
            if saved < worth:
                found = set()
    return frozenset(found)


def _occurrences(graph: Graph, roots: list[Ground], calls: set[Ground]) -> dict[Ground, float]:
    """At most how often each of ``calls`` (every method instance below
    ``roots``) occurs in one derivation: once per root, and for each caller,
    as often as the caller times the most the caller's one body holds it
    (infinite on and below a cycle)."""
    task = graph.grounder.task
    most: dict[Ground, dict[Ground, int]] = {}  # caller -> child -> most per body
    waiting = dict.fromkeys(calls, 0)  # callers not yet counted
    for call in calls:
        per: dict[Ground, int] = {}
        for option in graph.instance(call).options:
            counts: dict[Ground, int] = {}
            for child in option.children:
                if task.is_method(child):
                    counts[child] = counts.get(child, 0) + 1
            for child, count in counts.items():
                per[child] = max(per.get(child, 0), count)
        most[call] = per
        for child in per:
            waiting[child] += 1
    occurs: dict[Ground, float] = dict.fromkeys(calls, 0.0)
    for root in roots:
        occurs[root] += 1
    ready = [call for call, count in waiting.items() if count == 0]
    while ready:
        call = ready.pop()
        for child, count in most[call].items():
            occurs[child] += occurs[call] * count
            waiting[child] -= 1
            if waiting[child] == 0:
                ready.append(child)
    for call, count in waiting.items():
        if count:  # on or below a cycle
            occurs[call] = math.inf
    return occurs


def _longest(graph: Graph, calls: Iterable[Ground]) -> dict[Ground, float]:
    """The most method expansions a derivation of each call may take (the
    recursion guard ignored: infinite where an instance is below itself)."""
    task = graph.grounder.task
    longest: dict[Ground, float] = {}
    on_path: set[Ground] = set()
    for start in calls:
        todo: list[tuple[Ground, bool]] = [(start, False)]
        while todo:
            call, ready = todo.pop()
            if call in longest:
                continue
            options = graph.instance(call).options
            children = {c for o in options for c in o.children if task.is_method(c)}
            if not ready:
                on_path.add(call)
                todo.append((call, True))
                for child in children:
                    if child in on_path:
                        longest[call] = math.inf  # below itself
                    elif child not in longest:
                        todo.append((child, False))
                continue
            on_path.discard(call)
            if call in longest:
                continue
            longest[call] = max(
                (
                    1 + sum(longest.get(c, math.inf) for c in o.children if task.is_method(c))
                    for o in options
                ),
                default=1,
            )
    return longest


def _twice(
    slots: list[Ground], below: Callable[[Ground], frozenset[Ground]], found: set[Ground]
) -> None:
    """Add to ``found`` what is below two of ``slots``."""
    once: set[Ground] = set()
    for slot in slots:
        for call in below(slot):
            if call in once:
                found.add(call)
            else:
                once.add(call)
