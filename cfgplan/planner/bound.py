"""An admissible lower bound on what a partial configuration still costs.

Best-first search (:mod:`cfgplan.planner.search`) orders nodes by ``cost so
far + bound``. The bound counts only what every completion must add, so it
never overestimates (and the first configuration found is the cheapest):

- the *mandatory* functionality instances of each pending stack item: those in
  every feasible expansion of it (a method's versions and bindings are
  intersected), not yet in C;
- the robots every feasible expansion of a pending item runs something on
  (intersected the same way), not yet in C;
- channels that every completion must hold and that cannot merge with one
  already in C: those whose two ends are known, and those whose receiving end
  is known (one per kind, data and receiver);
- at least, for the functionalities and for the channels, the least any
  expansion of each pending item creates (its ``minimum`` and ``wiring``),
  less what C already has under the names that item can reach. Items that can
  reach no common functionality name (or channel data predicate) cannot share
  an instance, so their parts add up; items that can share count once (the
  largest). This is what sees the cost of a deep hierarchy below a method.

Sharing is accounted for by working with sets of concrete instances or of
names: two pending items needing ``camera(Emil)`` count it once, and nothing
already in C counts. A pending item with no feasible expansion makes the node
dead.

The pending items are read through their static summaries
(:mod:`cfgplan.planner.summary`), which depend only on the task, so one
:class:`Bound` serves every search of a task.
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Set
from dataclasses import dataclass, field

from cfgplan.planner.ground import Grounder
from cfgplan.planner.partial import Key, Partial
from cfgplan.planner.summary import ChannelId, Summaries, Summary, least, own_part
from cfgplan.planner.task import Ground, Task


@dataclass
class Bound:
    """The bound for one task; :meth:`estimate` on each node."""

    task: Task
    grounder: Grounder | None = None
    """The search's grounding memo, whose bindings the summaries share."""
    summaries: Summaries = field(init=False)

    def __post_init__(self) -> None:
        binder = None if self.grounder is None else self.grounder.method_bindings
        self.summaries = Summaries(self.task, binder)

    def feasible(self, node: Partial) -> float | None:
        """0 when every pending item may still complete, else None (no
        completion): what ``--all`` needs, where no estimate can stop early."""
        summary = self.summaries.summary
        for item in node.stack:
            if not summary(item.call).feasible:
                return None
        return 0.0

    def certain_agents(self, node: Partial) -> frozenset[str]:
        """Agents some pending item runs something on in every expansion."""
        agents: set[str] = set()
        for item in node.stack:
            agents |= self.summaries.summary(item.call).robots
        return frozenset(agents)

    def estimate(self, node: Partial) -> float | None:
        """A lower bound on the cost still to come, or None when no completion exists."""
        task = self.task
        placed = node.labels
        needed: set[Key] = set()
        new_robots: set[str] = set()
        future: set[ChannelId] = set()
        pending: dict[int, tuple[Ground, Summary]] = {}
        for item in node.stack:
            sub = self.summaries.summary(item.call)
            if not sub.feasible:
                return None
            pending[item.label] = (item.call, sub)
            needed |= sub.functionalities
            new_robots |= sub.robots
            future |= sub.channels
        by_label = {p.label: p.call for p in node.placed}
        resolved: set[tuple[str, Ground, Key, Key]] = set()
        for ch in node.channels:
            src, dst = by_label.get(ch.source), by_label.get(ch.target)
            if src is not None and dst is not None:
                resolved.add((ch.kind, ch.data, src, dst))
                continue
            sender = src if src is not None else _pending_end(pending, ch.source, ch.data, task)
            receiver = dst if dst is not None else _pending_call(pending, ch.target, task)
            future.add((ch.kind, ch.data, sender, receiver))
        mandatory = 0.0
        for key in needed:
            if key not in placed:
                schema = task.functionalities[(key[0], len(key) - 1)]
                mandatory += task.functionality_cost(schema, key)
        # Two lower bounds on the functionalities still to add, counted two ways
        # (certain instances; least cost per group of items that cannot share).
        # Either may be the larger, and both may count the same instance, so
        # they cannot be added up: their max is a lower bound.
        # Each of the two least costs is taken twice, the larger counting: over
        # every pending item, and without the items that repeat a method
        # instance already being expanded in this node (see _repeats).
        repeats = _repeats(node, task)
        alone = self._alone(node, pending, future)
        deepest = self._deepest(node, pending, alone)
        widest = self._widest(pending, future, resolved, alone)
        if repeats:
            kept = {label: entry for label, entry in pending.items() if label not in repeats}
            deepest = max(deepest, self._deepest(node, kept, alone))
            widest = max(widest, self._widest(kept, future, resolved, alone))
        total = max(mandatory, deepest)
        total += sum(task.agent_cost(agent) for agent in new_robots - node.robots)
        return total + widest

    def _alone(
        self, node: Partial, pending: dict[int, tuple[Ground, Summary]], future: set[ChannelId]
    ) -> frozenset[Key]:
        """Pending functionality instances (and ends of channels waiting for
        an end) that no pending method item can derive, as only its
        ancestors call them (:meth:`Summaries.beyond`): each is a part of its
        own, which shares with nothing else pending. On a recursive path (a
        conversion graph, issue 35) the path's own functionalities wait on
        the stack below the method deriving their inputs; named by their
        names, they would all count as one with it."""
        if not self.task.recursive:
            return frozenset()
        task, beyond = self.task, self.summaries.beyond
        above = [item.ancestors for item in node.stack if task.is_method(item.call)]
        keys = {call for call, _ in pending.values() if not task.is_method(call)}
        keys |= {end for _, _, sender, receiver in future for end in (sender, receiver) if end}
        return frozenset(k for k in keys if all(beyond(k, ancestors) for ancestors in above))

    def _deepest(
        self, node: Partial, pending: dict[int, tuple[Ground, Summary]], alone: frozenset[Key]
    ) -> float:
        """What the pending items must still add in functionalities, by their
        minimums: items that can reach no common functionality name add up
        (less what C already has of those names); the others count once.
        A functionality in ``alone`` is a part of its own."""
        have: dict[str, float] = {}
        for p in node.placed:
            cost = self.task.functionality_cost(p.schema, p.call)
            have[p.call[0]] = have.get(p.call[0], 0.0) + cost
        guarded = self._guarded(node, pending)
        parts: list[tuple[Set[Hashable], float]] = []
        for label, (call, sub) in pending.items():
            if call in alone:
                parts.append((own_part(call), 0.0 if call in node.labels else sub.minimum))
                continue
            names = self.summaries.names(call)
            reusable = sum(cost for name, cost in have.items() if name in names)
            reusable -= guarded.get(label, 0.0)
            parts.append((names, max(0.0, sub.minimum - reusable)))
        return least(parts)

    def _guarded(
        self, node: Partial, pending: dict[int, tuple[Ground, Summary]]
    ) -> dict[int, float]:
        """Per pending method item, the cost of the functionalities in C that
        its expansion cannot reuse, as only its ancestors call them
        (:meth:`Summaries.beyond`): on a recursive path (a conversion graph,
        issue 35) C holds the path's own functionalities, which would
        otherwise each lower the item's least cost."""
        if not self.task.recursive:
            return {}
        summaries, task = self.summaries, self.task
        guarded: dict[int, float] = {}
        for item in node.stack:
            if item.label not in pending or not task.is_method(item.call):
                continue
            names = summaries.names(item.call)
            total = 0.0
            for p in node.placed:
                if p.call[0] in names and summaries.beyond(p.call, item.ancestors):
                    total += task.functionality_cost(p.schema, p.call)
            if total:
                guarded[item.label] = total
        return guarded

    def _widest(
        self,
        pending: dict[int, tuple[Ground, Summary]],
        future: set[ChannelId],
        resolved: set[tuple[str, Ground, Key, Key]],
        alone: frozenset[Key],
    ) -> float:
        """What must still be added in channels: the channels already waiting
        for their ends (``future``), and each pending item's least wiring (less
        the resolved channels with data it can carry); parts whose data
        predicates differ cannot merge, so they add up. A channel from or
        into a functionality in ``alone`` can merge with none a pending item
        makes (those have both ends inside its expansion): they are a part of
        their own."""
        have: dict[str, float] = {}
        for kind, data, _, _ in resolved:
            have[data[0]] = have.get(data[0], 0.0) + self.task.channel_cost(kind)
        apart = {c for c in future if c[2] in alone or c[3] in alone}
        rest = future - apart if apart else future
        parts: list[tuple[Set[Hashable], float]] = [
            (
                frozenset(data[0] for _, data, _, _ in rest),
                _channel_bound(rest, resolved, self.task),
            )
        ]
        if apart:
            parts.append((own_part("channels"), _channel_bound(apart, resolved, self.task)))
        for call, sub in pending.values():
            names = self.summaries.data_names(call)
            reusable = sum(cost for name, cost in have.items() if name in names)
            parts.append((names, max(0.0, sub.wiring - reusable)))
        return least(parts)


def _repeats(node: Partial, task: Task) -> set[int]:
    """The labels of pending method items whose ground instance is being
    expanded elsewhere in the node (an ancestor of another item).

    Left out of a least cost, such an item is priced at nothing, which it may
    cost (expanded as the other occurrence is, its functionalities are reused
    and its channels merge, 4.5). Any subset of the pending items gives a
    lower bound: parts that cannot share still add up, and what the left-out
    items add is at least nothing. Counted, the repeat could share with every
    part of the other occurrence's body and join them into one, priced as the
    largest (the shared sub-derivations of issue 35). Ancestors are part of
    the canonical form (:mod:`cfgplan.planner.canonical`), so two nodes of
    one form leave out the same items."""
    above: set[Ground] = set()
    for item in node.stack:
        above |= item.ancestors
    return {item.label for item in node.stack if item.call in above and task.is_method(item.call)}


def _pending_call(pending: dict[int, tuple[Ground, Summary]], label: int, task: Task) -> Key | None:
    """The functionality a label will be, when it is a pending functionality item."""
    entry = pending.get(label)
    if entry is None:
        return None
    call = entry[0]
    return None if task.is_method(call) else call


def _pending_end(
    pending: dict[int, tuple[Ground, Summary]], label: int, data: Ground, task: Task
) -> Key | None:
    """The certain producer of ``data`` behind a pending label, if there is one."""
    entry = pending.get(label)
    if entry is None:
        return None
    call, sub = entry
    if not task.is_method(call):
        return call
    return sub.producer(data)


def _channel_bound(
    future: Iterable[ChannelId], resolved: set[tuple[str, Ground, Key, Key]], task: Task
) -> float:
    """Channels certain to be new: fully known ones not in C, plus one per
    (kind, data, receiver) of those whose sender is unknown and that nothing
    known could be."""
    full: set[tuple[str, Ground, Key, Key]] = set()
    open_ends: set[tuple[str, Ground, Key]] = set()
    for kind, data, src, dst in future:
        if src is not None and dst is not None:
            if (kind, data, src, dst) not in resolved:
                full.add((kind, data, src, dst))
        elif src is None and dst is not None:
            open_ends.add((kind, data, dst))
    covered = {(k, d, r) for k, d, _, r in full} | {(k, d, r) for k, d, _, r in resolved}
    total = sum(task.channel_cost(kind) for kind, *_ in full)
    for kind, data, dst in open_ends:
        if (kind, data, dst) not in covered:
            total += task.channel_cost(kind)
    return total
