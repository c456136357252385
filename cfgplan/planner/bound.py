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

The :class:`Bound` owns its caches: the summary of each ground instance and
the names each signature reaches depend only on the task, so one Bound serves
every search of a task. Summaries are computed without recursion (a method
hierarchy may be thousands of levels deep): :meth:`Bound.summary` runs the
summarising generators on an explicit stack.
"""

from __future__ import annotations

from collections.abc import Generator, Iterable, Set
from dataclasses import dataclass, field

from cfgplan.planner import clock
from cfgplan.planner.ground import channel_kind
from cfgplan.planner.match import bindings
from cfgplan.planner.partial import Key, Partial
from cfgplan.planner.task import Ground, MethodSchema, Signature, Task
from cfgplan.planner.unify import Bindings, bind_name, is_ground, substitute

ChannelId = tuple[str, Ground, Key | None, Key | None]
"""(kind, data, sender, receiver): None where the end is not known yet."""


@dataclass(frozen=True)
class Summary:
    """What every feasible expansion of one ground instance contains."""

    feasible: bool
    functionalities: frozenset[Key] = frozenset()
    robots: frozenset[str] = frozenset()  # where some functionality runs, in every expansion
    channels: frozenset[ChannelId] = frozenset()
    producers: tuple[tuple[Ground, Key | None], ...] = ()  # :out data -> certain producer
    minimum: float = 0.0  # the least its functionalities can cost, if none is in C yet
    wiring: float = 0.0  # the least the channels of its expansions can cost, likewise

    def producer(self, data: Ground) -> Key | None:
        for d, key in self.producers:
            if d == data:
                return key
        return None


@dataclass(frozen=True)
class Expanded:
    """One expansion of a method: what it certainly contains."""

    functionalities: frozenset[Key]
    robots: frozenset[str]
    channels: frozenset[ChannelId]
    producers: dict[Ground, Key | None]
    minimum: float
    wiring: float


INFEASIBLE = Summary(False)
UNKNOWN = Summary(True)
"""The summary of an instance met again inside its own expansion.

It claims the least possible: feasible, nothing certain, costing nothing.
Summaries are intersections (of contents) and minimums (of costs) over
expansions, so a part that claims less can only make the summaries built on
it claim less: they stay below what every real expansion contains and costs,
and the bound stays admissible. Claiming *feasible* is the optimistic side
too: the search prunes the recursion on its own path, but another version
may still complete, and the bound must not cut a node that has a completion.
"""

Summarising = Generator[Ground, Summary, Summary]
"""A summary being made: it yields each call whose summary it needs, is sent
that summary, and returns its own."""


@dataclass
class Bound:
    """The bound for one task; :meth:`estimate` on each node."""

    task: Task
    _memo: dict[Ground, Summary] = field(default_factory=dict)
    _reached: dict[Signature, tuple[frozenset[str], frozenset[str]]] = field(
        default_factory=dict
    )

    # -- static summaries of ground instances -------------------------------
    def summary(self, call: Ground) -> Summary:
        """What every feasible expansion of ``call`` contains (memoised)."""
        found = self._memo.get(call)
        if found is not None:
            return found
        frames: list[tuple[Ground, Summarising]] = [(call, self._summarise(call))]
        active = {call}
        reply: Summary | None = None
        while frames:
            clock.check()
            current, making = frames[-1]
            try:
                need = making.send(reply)  # type: ignore[arg-type]  # None starts it
            except StopIteration as made:
                self._memo[current] = made.value
                active.discard(current)
                frames.pop()
                reply = made.value
                continue
            reply = self._memo.get(need)
            if reply is None:
                if need in active:
                    reply = UNKNOWN  # see UNKNOWN: recursion is summarised as unknown
                else:
                    active.add(need)
                    frames.append((need, self._summarise(need)))
        return self._memo[call]

    def _summarise(self, call: Ground) -> Summarising:
        schema = self.task.functionality(call)
        if schema is not None:
            env = bind_name(schema.params, call[1:])
            if env is None or next(iter(bindings(self.task, schema.tests, env)), None) is None:
                return INFEASIBLE
            # Outputs that use a variable its preconditions bind stay open
            # (not ground), so they name no certain producer: weaker, still a bound.
            outs = tuple((substitute(o, env), call) for o in schema.outputs)
            cost = self.task.functionality_cost(schema, call)
            return Summary(True, frozenset({call}), frozenset({call[1]}), frozenset(), outs, cost)
        expansions: list[Expanded] = []
        for method in self.task.versions(call):
            env0 = bind_name(method.params, call[1:])
            if env0 is None:
                continue
            for env in bindings(self.task, method.tests, env0):
                expansion = yield from self._expansion(method, env)
                if expansion is not None:
                    expansions.append(expansion)
        if not expansions:
            return INFEASIBLE
        funcs = frozenset.intersection(*(e.functionalities for e in expansions))
        robots = frozenset.intersection(*(e.robots for e in expansions))
        channels = _common_channels([e.channels for e in expansions])
        first = expansions[0].producers
        producers = tuple(
            (data, key if all(e.producers.get(data) == key for e in expansions) else None)
            for data, key in first.items()
        )
        minimum = min(e.minimum for e in expansions)
        wiring = min(e.wiring for e in expansions)
        return Summary(True, funcs, robots, channels, producers, minimum, wiring)

    def _expansion(
        self, method: MethodSchema, env: Bindings
    ) -> Generator[Ground, Summary, Expanded | None]:
        body: dict[str, tuple[Ground, Summary, bool]] = {}
        funcs: set[Key] = set()
        robots: set[str] = set()
        channels: set[ChannelId] = set()
        for label, pattern in method.body:
            call = substitute(pattern, env)
            if not is_ground(call):
                return None
            sub = yield call
            if not sub.feasible:
                return None
            body[label] = (call, sub, not self.task.is_method(call))
            funcs |= sub.functionalities
            robots |= sub.robots
            channels |= sub.channels
        own: set[tuple[str, Ground]] = set()
        for spec in method.channels:
            data = substitute(spec.data, env)
            ends = substitute(("robots", *spec.robots), env)
            if not is_ground(data) or not is_ground(ends):
                return None
            kind = channel_kind(spec.kind, ends[1:])[0]
            own.add((kind, data))
            src_call, src_sum, src_func = body[spec.source]
            dst_call, _, dst_func = body[spec.target]
            sender = src_call if src_func else src_sum.producer(data)
            receiver = dst_call if dst_func else None
            channels.add((kind, data, sender, receiver))
        producers: dict[Ground, Key | None] = {}
        for port in method.outputs:
            data = substitute(port.data, env)
            call, sub, is_functionality = body[port.label]
            producers.setdefault(data, call if is_functionality else sub.producer(data))
        parts = [(self.names(call), sub.minimum) for call, sub, _ in body.values()]
        own_cost = float(sum(self.task.channel_cost(kind) for kind, _ in own))
        wires: list[tuple[Set[str], float]] = [({data[0] for _, data in own}, own_cost)]
        wires += [(self.data_names(call), sub.wiring) for call, sub, _ in body.values()]
        return Expanded(
            frozenset(funcs),
            frozenset(robots),
            frozenset(channels),
            producers,
            _least(parts),
            _least(wires),
        )

    # -- what a signature can reach ---------------------------------------------
    def names(self, call: Ground) -> frozenset[str]:
        """The functionality names an instance can reach through method bodies."""
        return self._reach(call)[0]

    def data_names(self, call: Ground) -> frozenset[str]:
        """The data predicates of the channels its expansions can create."""
        return self._reach(call)[1]

    def _reach(self, call: Ground) -> tuple[frozenset[str], frozenset[str]]:
        sig = (call[0], len(call) - 1)
        found = self._reached.get(sig)
        if found is not None:
            return found
        names: set[str] = set()
        data: set[str] = set()
        seen = {sig}
        todo = [sig]
        while todo:
            current = todo.pop()
            if current in self.task.functionalities:
                names.add(current[0])
                continue
            for method in self.task.methods.get(current, ()):
                data.update(c.data[0] for c in method.channels)
                for _, pattern in method.body:
                    child = (pattern[0], len(pattern) - 1)
                    if child not in seen:
                        seen.add(child)
                        todo.append(child)
        result = self._reached[sig] = (frozenset(names), frozenset(data))
        return result

    # -- the bound of a node ----------------------------------------------------
    def feasible(self, node: Partial) -> float | None:
        """0 when every pending item may still complete, else None (no
        completion): what ``--all`` needs, where no estimate can stop early."""
        summary = self.summary
        for item in node.stack:
            if not summary(item.call).feasible:
                return None
        return 0.0

    def certain_agents(self, node: Partial) -> frozenset[str]:
        """Agents some pending item runs something on in every expansion."""
        agents: set[str] = set()
        for item in node.stack:
            agents |= self.summary(item.call).robots
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
            sub = self.summary(item.call)
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
        total = max(mandatory, self._deepest(node, pending))
        total += sum(task.agent_cost(agent) for agent in new_robots - node.robots)
        total += self._widest(pending, future, resolved)
        return total

    def _deepest(self, node: Partial, pending: dict[int, tuple[Ground, Summary]]) -> float:
        """What the pending items must still add in functionalities, by their
        minimums: items that can reach no common functionality name add up
        (less what C already has of those names); the others count once."""
        have: dict[str, float] = {}
        for p in node.placed:
            cost = self.task.functionality_cost(p.schema, p.call)
            have[p.call[0]] = have.get(p.call[0], 0.0) + cost
        parts = []
        for call, sub in pending.values():
            names = self.names(call)
            reusable = sum(cost for name, cost in have.items() if name in names)
            parts.append((names, max(0.0, sub.minimum - reusable)))
        return _least(parts)

    def _widest(
        self,
        pending: dict[int, tuple[Ground, Summary]],
        future: set[ChannelId],
        resolved: set[tuple[str, Ground, Key, Key]],
    ) -> float:
        """What must still be added in channels: the channels already waiting
        for their ends (``future``), and each pending item's least wiring (less
        the resolved channels with data it can carry); parts whose data
        predicates differ cannot merge, so they add up."""
        have: dict[str, float] = {}
        for kind, data, _, _ in resolved:
            have[data[0]] = have.get(data[0], 0.0) + self.task.channel_cost(kind)
        parts = [
            (
                frozenset(data[0] for _, data, _, _ in future),
                _channel_bound(future, resolved, self.task),
            )
        ]
        for call, sub in pending.values():
            names = self.data_names(call)
            reusable = sum(cost for name, cost in have.items() if name in names)
            parts.append((names, max(0.0, sub.wiring - reusable)))
        return _least(parts)


def _least(parts: Iterable[tuple[Set[str], float]]) -> float:
    """The least the functionalities of one expansion can cost: body items
    whose reachable names are disjoint cannot share an instance, so their
    minimums add; items that may share count as the largest of them."""
    groups: list[tuple[set[str], float]] = []
    for names, least in parts:
        merged_names, merged_least = set(names), least
        rest = []
        for group_names, group_least in groups:
            if group_names & merged_names:
                merged_names |= group_names
                merged_least = max(merged_least, group_least)
            else:
                rest.append((group_names, group_least))
        groups = [*rest, (merged_names, merged_least)]
    return sum(least for _, least in groups)


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


def _common_channels(sets: list[frozenset[ChannelId]]) -> frozenset[ChannelId]:
    """Channels in every expansion; where only the sender differs, keep the
    channel with its sender unknown."""
    exact = frozenset.intersection(*sets)
    loose: set[ChannelId] = set(exact)
    receivers = [{(k, d, r) for k, d, _, r in s if r is not None} for s in sets]
    for kind, data, receiver in set.intersection(*receivers):
        if not any(c[0] == kind and c[1] == data and c[3] == receiver for c in exact):
            loose.add((kind, data, None, receiver))
    return frozenset(loose)


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
