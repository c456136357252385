"""The AND/OR graph of ground instances (4.5): every method instance with one
option per feasible expansion (its method versions in domain order, the
bindings of their preconditions in state order), every functionality
instance with its weight. Made on demand from the grounder's expansions,
each instance once, and kept with the grounder (:func:`graph_of`: one per task,
as the grounder is, :func:`cfgplan.planner.plan.analysis`), numbered by its
numbering.

The passes over it are elsewhere: what every expansion of an instance
contains (:mod:`cfgplan.planner.summary`, the first bound), the partitioned
bound's occurrence counts and cheapest derivations (:mod:`cfgplan.planner.partition`,
:mod:`cfgplan.planner.occurrences`, :mod:`cfgplan.planner.prices`,
:mod:`cfgplan.planner.least`), how often the
media let a shared cost occur (:mod:`cfgplan.planner.capacity`), and the
independent parts of a goal (:mod:`cfgplan.planner.components`). What the
graph holds of an expansion is what those passes read: its children and
their numbers, its own channels as the bound prices them
(:class:`~cfgplan.planner.prices.Wire`), the agents its functionalities run
on, and what its global channels need of the media
(:mod:`cfgplan.planner.room`).
"""

from __future__ import annotations

from collections.abc import Container
from dataclasses import dataclass, field
from typing import NamedTuple

from cfgplan.planner.canonical import channel_number
from cfgplan.planner.ground import ChannelSpec, Expansion, Grounder
from cfgplan.planner.numbering import Numbering
from cfgplan.planner.partial import Placed
from cfgplan.planner.prices import Wire, wire_keys
from cfgplan.planner.report import DeadEnd
from cfgplan.planner.room import Need, Room
from cfgplan.planner.task import Ground
from cfgplan.planner.wiring import Channel


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
        parents: the order :meth:`cfgplan.planner.least.Least.full` evaluates
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
