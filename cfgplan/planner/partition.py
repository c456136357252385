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
- a channel whose two ends are known functionality instances costs ``w / S``
  over the channels with that identity (kind, data, ends) *and* the channels
  of its kind and data whose ends are not known yet (they might turn out
  identical); such an open channel costs ``w / S`` over all channels of its
  kind and data. A channel costs nothing when C already holds one it might
  merge with. So the channels that end up as one channel are charged ``w``
  at most, together.

Then the cost of each pending item is a plain minimum over its expansions,
computed bottom-up over ground instances, and the items' costs add up: in
any completion, a shared cost is charged at most as often as it can occur,
each time ``w / S``, so never more than ``w`` in all. The search takes the
larger of the two bounds (:func:`cfgplan.planner.plan.combined`).

Items whose expansions can recur into themselves (a ground instance below
itself) have no finite occurrence count: for such tasks this bound is off.
"""

from __future__ import annotations

from collections.abc import Container
from dataclasses import dataclass, field

from cfgplan.planner.ground import ChannelSpec, Expansion, Grounder
from cfgplan.planner.partial import Partial
from cfgplan.planner.report import DeadEnd
from cfgplan.planner.task import Ground, Task

Key = tuple[object, ...]
"""What costs, as counted: a functionality call; ``("@", agent)``; for
channels ``("=", kind, data, sender, receiver)`` (both ends known),
``("?", kind, data)`` (an end open) and ``("*", kind, data)`` (every channel
of that kind and data)."""

Counts = dict[Key, int]
"""Most occurrences of each key in one derivation."""


@dataclass(frozen=True, slots=True)
class Wire:
    """An own channel of an expansion, as this bound prices it."""

    key: Key  # its identity, or its open key
    known: bool  # the identity is known
    weight: float
    opened: Key  # the open key of its kind and data
    every: Key  # the key counting every channel of its kind and data


@dataclass(frozen=True, slots=True)
class Option:
    """One expansion of a method, as this bound sees it."""

    children: tuple[Ground, ...]
    channels: tuple[Wire, ...]
    agents: tuple[str, ...]  # agents its functionality children run on, each once


@dataclass(frozen=True, slots=True)
class Instance:
    """A ground instance in the AND/OR graph: a functionality (no options, its
    weight) or a method with one option per feasible expansion."""

    call: Ground
    functionality: bool
    options: tuple[Option, ...] = ()
    weight: float = 0.0


@dataclass
class Partition:
    """The partitioned bound for one task; :meth:`estimate` on each node."""

    grounder: Grounder
    _instances: dict[Ground, Instance] = field(default_factory=dict)
    _counts: dict[Ground, Counts] = field(default_factory=dict)
    _orders: dict[Ground, tuple[Ground, ...]] = field(default_factory=dict)
    _cyclic: bool = False

    # -- the AND/OR graph of ground instances, made once ----------------------
    def instance(self, call: Ground) -> Instance:
        found = self._instances.get(call)
        if found is None:
            task = self.grounder.task
            schema = task.functionality(call)
            if schema is not None:
                found = Instance(call, True, weight=task.functionality_cost(schema, call))
            else:
                options = []
                for method in task.versions(call):
                    for expansion in self.grounder.expansions(method, call):
                        if not isinstance(expansion, DeadEnd):
                            options.append(_option(task, expansion))
                found = Instance(call, False, tuple(options))
            self._instances[call] = found
        return found

    def counts(self, call: Ground) -> Counts | None:
        """Most occurrences of each key in one derivation of ``call``; None
        when ``call`` can recur into itself."""
        if self._cyclic:
            return None
        found = self._counts.get(call)
        if found is not None:
            return found
        order = self._below(call, self._counts)
        if order is None:
            self._cyclic = True
            return None
        for current in order:
            self._counts[current] = self._count(self.instance(current))
        return self._counts[call]

    def order(self, call: Ground) -> tuple[Ground, ...]:
        """Every instance below ``call`` (itself last), children before
        parents: the order :meth:`_least` evaluates them in, made once."""
        found = self._orders.get(call)
        if found is None:
            below = self._below(call, ())
            assert below is not None  # counts() found no recursion below the pending items
            found = self._orders[call] = tuple(below)
        return found

    def _below(self, call: Ground, done: Container[Ground]) -> list[Ground] | None:
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

    def _count(self, instance: Instance) -> Counts:
        if instance.functionality:
            return {instance.call: 1}
        most: Counts = {}
        for option in instance.options:
            total: Counts = {}
            for child in option.children:
                for key, n in self._counts[child].items():
                    total[key] = total.get(key, 0) + n
            for wire in option.channels:
                for key in (wire.key, wire.every):
                    total[key] = total.get(key, 0) + 1
            for agent in option.agents:
                key = ("@", agent)
                total[key] = total.get(key, 0) + 1
            for key, n in total.items():
                if n > most.get(key, 0):
                    most[key] = n
        return most

    # -- the bound of a node ----------------------------------------------------
    def estimate(self, node: Partial, certain: frozenset[str]) -> float | None:
        """A lower bound on the cost still to come (0 when off), or None when
        some pending item has no derivation; ``certain`` are agents every
        completion uses: they are counted in full, once."""
        if self._cyclic:
            return 0.0
        task = self.grounder.task
        totals: Counts = {}
        get = totals.get
        for item in node.stack:
            counts = self.counts(item.call)
            if counts is None:
                return 0.0
            if totals:
                for key, n in counts.items():
                    totals[key] = get(key, 0) + n
            else:
                totals.update(counts)
            if not task.is_method(item.call):  # a pending functionality places itself
                key = ("@", item.call[1])
                totals[key] = get(key, 0) + 1
        present, future = self._channels(node)
        for key in future:
            for counted in (key, ("*", *key[1:3])):
                totals[counted] = totals.get(counted, 0) + 1
        prices = Prices(task, node, certain, totals, present)
        total = sum(prices.channel(key) for key in future)
        total += sum(task.agent_cost(agent) for agent in certain - node.robots)
        memo: dict[Ground, float] = {}
        for item in node.stack:
            total += self._least(item.call, memo, prices)
            if not task.is_method(item.call):
                total += prices.agent(item.call[1])
        return None if total == float("inf") else total

    def _channels(self, node: Partial) -> tuple[set[Key], list[Key]]:
        """The keys of the channels already in C (resolved), and of those
        waiting for an end (each will be one channel of the configuration)."""
        present: set[Key] = set()
        future: list[Key] = []
        pending = {item.label: item.call for item in node.stack}
        task = self.grounder.task
        for ch in node.channels:
            src, dst = node.located.get(ch.source), node.located.get(ch.target)
            if src is not None and dst is not None:
                present.add(("=", ch.kind, ch.data, src.call, dst.call))
                present.add(("*", ch.kind, ch.data))
                continue
            sender = src.call if src is not None else pending.get(ch.source)
            receiver = dst.call if dst is not None else pending.get(ch.target)
            if (
                sender is not None
                and receiver is not None
                and not task.is_method(sender)
                and not task.is_method(receiver)
            ):
                future.append(("=", ch.kind, ch.data, sender, receiver))
            else:
                future.append(("?", ch.kind, ch.data))
        return present, future

    def _least(self, call: Ground, memo: dict[Ground, float], prices: Prices) -> float:
        """The cheapest derivation of ``call`` at ``prices`` (bottom-up)."""
        found = memo.get(call)
        if found is not None:
            return found
        # The hot loop of the search: prices inlined (see Prices for each rule).
        instances = self._instances
        agent_price, agent_prices = prices.agent, prices.agents
        totals, present, placed = prices.totals, prices.present, prices.node.labels
        for current in self.order(call):
            if current in memo:
                continue
            instance = instances[current]
            if instance.functionality:
                memo[current] = 0.0 if current in placed else instance.weight / totals[current]
                continue
            best = float("inf")
            for option in instance.options:
                cost = 0.0
                for child in option.children:
                    cost += memo[child]
                for wire in option.channels:
                    if wire.known:
                        if wire.key not in present:
                            cost += wire.weight / (totals[wire.key] + totals.get(wire.opened, 0))
                    elif wire.every not in present:
                        cost += wire.weight / totals[wire.every]
                for agent in option.agents:
                    price = agent_prices.get(agent)
                    cost += agent_price(agent) if price is None else price
                if cost < best:
                    best = cost
            memo[current] = best
        return memo[call]


@dataclass
class Prices:
    """What each key costs at one node: its weight, shared (module docstring)."""

    task: Task
    node: Partial
    certain: frozenset[str]
    totals: Counts
    present: set[Key]
    agents: dict[str, float] = field(default_factory=dict)  # the agent prices found so far

    def functionality(self, call: Ground) -> float:
        if call in self.node.labels:
            return 0.0
        schema = self.task.functionality(call)
        assert schema is not None
        return self.task.functionality_cost(schema, call) / self.totals[call]

    def agent(self, agent: str) -> float:
        found = self.agents.get(agent)
        if found is None:
            found = 0.0
            if agent not in self.node.robots and agent not in self.certain:
                found = self.task.agent_cost(agent) / self.totals[("@", agent)]
            self.agents[agent] = found
        return found

    def channel(self, key: Key) -> float:
        kind, data = key[1], key[2]
        assert isinstance(kind, str)
        if key[0] == "=":
            if key in self.present:
                return 0.0
            opened = self.totals.get(("?", kind, data), 0)
            return self.task.channel_cost(kind) / (self.totals[key] + opened)
        if ("*", kind, data) in self.present:
            return 0.0
        return self.task.channel_cost(kind) / self.totals[("*", kind, data)]


def _option(task: Task, expansion: Expansion) -> Option:
    channels = tuple(_wire(task, expansion, spec) for spec in expansion.channels)
    agents = tuple(dict.fromkeys(c[1] for c in expansion.body if not task.is_method(c)))
    return Option(expansion.body, channels, agents)


def _wire(task: Task, expansion: Expansion, spec: ChannelSpec) -> Wire:
    """An own channel: its identity when both its ends are functionality calls
    of the body, else its open key."""
    kind, _, source, target, data, _ = spec
    sender, receiver = expansion.body[source], expansion.body[target]
    opened: Key = ("?", kind, data)
    known = not task.is_method(sender) and not task.is_method(receiver)
    key: Key = ("=", kind, data, sender, receiver) if known else opened
    return Wire(key, known, task.channel_cost(kind), opened, ("*", kind, data))
