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
- a robot or device not yet in C, and not certain to be used, costs
  ``w / S`` per functionality placed on it, S counted likewise;
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
each time ``w / S``, so never more than ``w`` in all. The two bounds are
combined by their maximum (:func:`combined`).

Items whose expansions can recur into themselves (a ground instance below
itself) have no finite occurrence count: for such tasks this bound is off.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from cfgplan.planner.ground import ChannelSpec, Expansion, Grounder
from cfgplan.planner.partial import Partial
from cfgplan.planner.report import DeadEnd
from cfgplan.planner.task import Ground

Counts = dict[tuple[object, ...], int]
"""Most occurrences of each thing that costs in one derivation. Keys: a
functionality call; ``("@", agent)``; for channels ``("=", kind, data, sender,
receiver)`` (both ends known), ``("?", kind, data)`` (an end open) and
``("*", kind, data)`` (every channel of that kind and data)."""


@dataclass(frozen=True)
class Node:
    """A ground instance in the AND/OR graph: a functionality (no expansions)
    or a method with its feasible expansions."""

    call: Ground
    functionality: bool
    expansions: tuple[Expansion, ...] = ()


@dataclass
class Partition:
    """The partitioned bound for one task; :meth:`estimate` on each node."""

    grounder: Grounder
    _nodes: dict[Ground, Node] = field(default_factory=dict)
    _counts: dict[Ground, Counts] = field(default_factory=dict)
    _cyclic: bool = False

    # -- the AND/OR graph of ground instances, made once ----------------------
    def node(self, call: Ground) -> Node:
        found = self._nodes.get(call)
        if found is None:
            task = self.grounder.task
            if not task.is_method(call):
                found = Node(call, True)
            else:
                expansions = []
                for method in task.versions(call):
                    for env in self.grounder.method_bindings(method, call):
                        expansion = self.grounder.expansion(method, env, "")
                        if not isinstance(expansion, DeadEnd):
                            expansions.append(expansion)
                found = Node(call, False, tuple(expansions))
            self._nodes[call] = found
        return found

    def counts(self, call: Ground) -> Counts | None:
        """Most occurrences, in one derivation of ``call``, of each instance,
        agent and channel class; None when ``call`` can recur into itself."""
        if self._cyclic:
            return None
        found = self._counts.get(call)
        if found is not None:
            return found
        # Post-order over the instances below ``call``, without recursion.
        order: list[Ground] = []
        state: dict[Ground, int] = {}  # 1: on the path, 2: done
        stack: list[tuple[Ground, int]] = [(call, 0)]
        while stack:
            current, phase = stack.pop()
            if phase == 1:
                state[current] = 2
                order.append(current)
                continue
            if current in self._counts or state.get(current) == 2:
                continue
            if state.get(current) == 1:
                self._cyclic = True  # reached again on its own path
                return None
            state[current] = 1
            stack.append((current, 1))
            for expansion in self.node(current).expansions:
                stack.extend((child, 0) for child in expansion.body)
        for current in order:
            self._counts[current] = self._count(self.node(current))
        return self._counts[call]

    def channel_keys(
        self, expansion: Expansion, spec: ChannelSpec
    ) -> tuple[tuple[object, ...], ...]:
        """How an expansion's own channel is counted: its identity when both of
        its ends are functionality calls of the body, else open; and its class."""
        kind, _, source, target, data, _ = spec
        sender, receiver = expansion.body[source], expansion.body[target]
        task = self.grounder.task
        if not task.is_method(sender) and not task.is_method(receiver):
            return ("=", kind, data, sender, receiver), ("*", kind, data)
        return ("?", kind, data), ("*", kind, data)

    def _count(self, node: Node) -> Counts:
        if node.functionality:
            return {node.call: 1, ("@", node.call[1]): 1}
        most: Counts = {}
        for expansion in node.expansions:
            total: Counts = {}
            for child in expansion.body:
                for key, n in self._counts[child].items():
                    total[key] = total.get(key, 0) + n
            for spec in expansion.channels:
                for key in self.channel_keys(expansion, spec):
                    total[key] = total.get(key, 0) + 1
            for key, n in total.items():
                if n > most.get(key, 0):
                    most[key] = n
        return most

    # -- the bound of a node ----------------------------------------------------
    def _pending(self, node: Partial, label: int) -> Ground | None:
        """The functionality call a pending label will be placed as, if it is one."""
        for item in node.stack:
            if item.label == label:
                return None if self.grounder.task.is_method(item.call) else item.call
        return None

    def estimate(self, node: Partial, certain: frozenset[str]) -> float | None:
        """A lower bound on the cost still to come (0 when off), or None when
        some pending item has no derivation; ``certain`` are agents every
        completion uses: they are counted in full, once."""
        if self._cyclic:
            return 0.0
        totals: Counts = {}
        for item in node.stack:
            counts = self.counts(item.call)
            if counts is None:
                return 0.0
            for key, n in counts.items():
                totals[key] = totals.get(key, 0) + n
        task = self.grounder.task
        present: set[tuple[object, ...]] = set()
        future: list[tuple[object, ...]] = []
        for ch in node.channels:
            src, dst = node.located.get(ch.source), node.located.get(ch.target)
            if src is not None and dst is not None:
                present.add(("=", ch.kind, ch.data, src.call, dst.call))
                present.add(("*", ch.kind, ch.data))
                continue
            sender = src.call if src is not None else self._pending(node, ch.source)
            receiver = dst.call if dst is not None else self._pending(node, ch.target)
            if sender is not None and receiver is not None:
                future.append(("=", ch.kind, ch.data, sender, receiver))
            else:
                future.append(("?", ch.kind, ch.data))
        for key in future:
            totals[key] = totals.get(key, 0) + 1
            cls = ("*", *key[1:3])
            totals[cls] = totals.get(cls, 0) + 1

        def share(key: tuple[object, ...], weight: float) -> float:
            return weight / totals[key]

        def channel(key: tuple[object, ...]) -> float:
            """What a channel is charged (see the module docstring)."""
            kind = key[1]
            assert isinstance(kind, str)
            cls = ("*", kind, key[2])
            if key[0] == "=":
                if key in present:
                    return 0.0
                opened = totals.get(("?", kind, key[2]), 0)
                return task.channel_cost(kind) / (totals[key] + opened)
            return 0.0 if cls in present else share(cls, task.channel_cost(kind))

        def functionality(call: Ground) -> float:
            cost = 0.0
            if call not in node.labels:
                schema = task.functionality(call)
                assert schema is not None
                cost += share(call, task.functionality_cost(schema, call))
            agent = call[1]
            if agent not in node.robots and agent not in certain:
                cost += share(("@", agent), task.agent_cost(agent))
            return cost

        memo: dict[Ground, float] = {}
        total = sum(channel(key) for key in future)
        total += sum(task.agent_cost(agent) for agent in certain - node.robots)
        for item in node.stack:
            total += self._least(item.call, memo, functionality, channel)
        return None if total == float("inf") else total

    def _least(
        self,
        call: Ground,
        memo: dict[Ground, float],
        functionality: Callable[[Ground], float],
        channel: Callable[[tuple[object, ...]], float],
    ) -> float:
        """The cheapest derivation of ``call`` under the shared costs (bottom-up)."""
        found = memo.get(call)
        if found is not None:
            return found
        order: list[Ground] = []
        seen: set[Ground] = set()
        stack: list[tuple[Ground, bool]] = [(call, False)]
        while stack:
            current, ready = stack.pop()
            if ready:
                order.append(current)
                continue
            if current in memo or current in seen:
                continue
            seen.add(current)
            stack.append((current, True))
            for expansion in self.node(current).expansions:
                stack.extend((child, False) for child in expansion.body)
        for current in order:
            node = self.node(current)
            if node.functionality:
                memo[current] = functionality(current)
                continue
            best = float("inf")
            for expansion in node.expansions:
                cost = sum(memo[child] for child in expansion.body)
                cost += sum(
                    channel(self.channel_keys(expansion, spec)[0]) for spec in expansion.channels
                )
                best = min(best, cost)
            memo[current] = best
        return memo[call]



