"""What every feasible expansion of a ground instance contains: the static
summaries the bound of a node is made of (:mod:`cfgplan.planner.bound`).

A :class:`Summary` intersects the expansions of one ground instance (4.5:
its method versions and precondition bindings): the functionality
instances, robots and channels all of them hold, and the least their
functionalities and channels can cost. It is a pass over the grounder's
graph of ground instances (:func:`cfgplan.planner.graph.graph_of`:
each option stands for one of the expansions the search takes), as the
partitioned bound is. They depend only on the task, so one
:class:`Summaries` serves every search of a task. Summaries are computed
without recursion (a method hierarchy may be thousands of levels deep):
:meth:`Summaries.summary` runs the summarising generators on an explicit
stack.
"""

from __future__ import annotations

from collections.abc import Generator, Sequence
from dataclasses import dataclass, field, replace
from typing import NamedTuple

from cfgplan.planner import clock
from cfgplan.planner.graph import graph_of
from cfgplan.planner.ground import Expansion, Grounder
from cfgplan.planner.match import exists
from cfgplan.planner.parts import Part, least, own_part
from cfgplan.planner.reach import Reach
from cfgplan.planner.task import Ground, Task
from cfgplan.planner.unify import bind_name, substitute

ChannelId = tuple[str, Ground, Ground | None, Ground | None]
"""(kind, data, sender, receiver): None where the end is not known yet."""


@dataclass(frozen=True)
class Summary:
    """What every feasible expansion of one ground instance contains."""

    feasible: bool
    functionalities: frozenset[Ground] = frozenset()
    robots: frozenset[str] = frozenset()  # where some functionality runs, in every expansion
    channels: frozenset[ChannelId] = frozenset()
    producers: tuple[tuple[Ground, Ground | None], ...] = ()  # :out data -> certain producer
    minimum: float = 0.0  # the least its functionalities can cost, if none is in C yet
    wiring: float = 0.0  # the least the channels of its expansions can cost, likewise
    together: float = 0.0
    """The least its functionalities and channels can cost together: the
    least over expansions of their sum, which may be more than ``minimum +
    wiring`` (those two may come from different expansions: on a chain one
    version has the cheaper functionalities, another the cheaper channels)."""

    slack: bool = field(init=False)
    """Whether ``together`` says more than ``minimum + wiring``: else the
    bound counting them apart is at least the one counting them together
    (:meth:`cfgplan.planner.bound.Bound.estimate`)."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "slack", self.together > self.minimum + self.wiring + 1e-9)

    def producer(self, data: Ground) -> Ground | None:
        for d, key in self.producers:
            if d == data:
                return key
        return None


class Expanded(NamedTuple):
    """One expansion of a method: what it certainly contains."""

    functionalities: frozenset[Ground]
    robots: frozenset[str]
    channels: frozenset[ChannelId]
    producers: dict[Ground, Ground | None]
    minimum: float
    wiring: float
    together: float


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


@dataclass(eq=False, repr=False)
class Summaries:
    """The summaries of one task's ground instances, memoised."""

    task: Task
    grounder: Grounder | None = None
    """Whose graph of ground instances is summarised (:func:`~cfgplan.planner.graph.graph_of`):
    the search's, so that each instance is matched and instantiated once;
    None: a grounder of their own."""
    media: bool = True
    """Which of the grounder's graphs (:attr:`cfgplan.planner.options.SearchOptions.media`):
    the one the partitioned bound reads too."""
    _memo: dict[Ground, Summary] = field(default_factory=dict)
    _parents: dict[Ground, set[Ground]] = field(default_factory=dict)
    """Functionality instance -> the method instances whose bodies call it,
    over every ground instance reachable from a summarised call."""
    _walked: set[Ground] = field(default_factory=set)

    def __post_init__(self) -> None:
        grounder = self.grounder or Grounder(self.task)
        self._instance = graph_of(grounder, self.media).instance
        self.reach = Reach(self.task)
        """The names each instance can reach: what names a summary's parts."""

    def summary(self, call: Ground) -> Summary:
        """What every feasible expansion of ``call`` contains (memoised)."""
        found = self._memo.get(call)
        if found is not None:
            return found
        self._walk(call)
        frames: list[tuple[Ground, Summarising]] = [(call, self._summarise(call))]
        active = {call}
        guessed: set[Ground] = set()  # frames that were told UNKNOWN, or built on one that was
        recursive: list[Ground] = []  # the summaries built on UNKNOWN, in the order made
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
                if current in guessed:
                    recursive.append(current)
                    if frames:
                        guessed.add(frames[-1][0])
                continue
            reply = self._memo.get(need)
            if reply is not None and need in guessed:
                guessed.add(current)  # built on a summary the fixpoint will raise
            elif reply is None:
                if need in active:
                    reply = UNKNOWN  # see UNKNOWN: recursion is summarised as unknown
                    guessed.add(current)
                else:
                    active.add(need)
                    frames.append((need, self._summarise(need)))
        if recursive:
            self._raise_least_costs(recursive)
        return self._memo[call]

    def _raise_least_costs(self, recursive: list[Ground]) -> None:
        """Raise the least costs of summaries built on :data:`UNKNOWN` towards
        the cheapest derivation's, ignoring the recursion guard.

        Priced at 0, a recursive call makes every instance of its cycle look
        almost free (a conversion graph's root bound was 13 against an
        optimum of 27). The least costs of the instances of one cycle are
        the least fixpoint of their equations (``minimum`` is a min over
        expansions of sums and maxima of their parts' minimums, and so is
        ``wiring`` and ``together``): the cost of the lightest derivation tree (Knuth's
        lightest derivation). Iterating the equations from the costs made
        with UNKNOWN's 0 stays below that fixpoint at every round, as the
        equations are monotone; and the fixpoint is at most what any
        derivation the search can make costs, since the recursion guard of
        4.5 only removes derivations. So every round is admissible, and the
        rounds stop when nothing changes or after a number of rounds that
        bounds the work on long cycles. The contents (functionalities,
        robots, channels) keep their first, weaker values: they are
        intersections, and raising them needs another argument.
        """
        limit = 2 * len(recursive) + 8
        for _ in range(limit):
            changed = False
            for call in recursive:
                clock.check()
                old = self._memo[call]
                making = self._summarise(call)
                reply: Summary | None = None
                try:
                    while True:
                        need = making.send(reply)  # type: ignore[arg-type]
                        reply = self._memo[need]
                except StopIteration as made:
                    new: Summary = made.value
                if not new.feasible:
                    continue  # its expansions all lead to infeasible parts: keep the first
                raised = replace(
                    old,
                    minimum=max(old.minimum, new.minimum),
                    wiring=max(old.wiring, new.wiring),
                    together=max(old.together, new.together),
                )
                if raised != old:
                    self._memo[call] = raised
                    changed = True
            if not changed:
                return

    def _walk(self, root: Ground) -> None:
        """Note the callers of every functionality instance reachable from
        ``root`` (see :meth:`_own`)."""
        if root in self._walked:
            return
        self._walked.add(root)
        todo = [root]
        while todo:
            clock.check()
            call = todo.pop()
            for option in self._instance(call).options:
                for child in option.children:
                    if not self.task.is_method(child):
                        self._parents.setdefault(child, set()).add(call)
                    elif child not in self._walked:
                        self._walked.add(child)
                        todo.append(child)

    def beyond(self, functionality: Ground, ancestries: Sequence[frozenset[Ground]]) -> bool:
        """Whether no expansion of an item below any of ``ancestries`` (each
        an item's ancestors) can derive ``functionality``: every method
        instance whose body calls it is one of those ancestors, which the
        recursion guard of 4.5 prunes there (so True when there are none).

        Only callers whose signatures can recur are trusted to be ancestors
        (:attr:`Task.recursive`): those are the ancestors the canonical form
        keeps (:mod:`cfgplan.planner.canonical`), so two nodes of one form
        agree. The callers are those of the instances reachable from every
        call summarised so far: all those reachable from the item, once its
        own summary was asked for."""
        if not ancestries:
            return True
        callers = self._parents.get(functionality)
        if not callers:
            return False
        for ancestors in ancestries:
            if not callers <= ancestors:
                return False
        recursive = self.task.recursive
        return all((c[0], len(c) - 1) in recursive for c in callers)

    def _own(self, functionality: Ground, caller: Ground) -> bool:
        """Whether only ``caller``'s bodies call ``functionality``.

        Then no part of ``caller``'s body derives it: every derivation of it
        passes through ``caller``, which the recursion guard of 4.5 prunes
        below ``caller`` itself. So it cannot be shared with another part of
        the body, nor can a channel into it (a channel made inside a part
        ends inside that part)."""
        return self._parents.get(functionality, set()) == {caller}

    def _summarise(self, call: Ground) -> Summarising:
        schema = self.task.functionality(call)
        if schema is not None:
            env = bind_name(schema.params, call[1:])
            if env is None or not exists(self.task, schema.tests, env):
                return INFEASIBLE
            # Outputs that use a variable its preconditions bind stay open
            # (not ground), so they name no certain producer: weaker, still a bound.
            outs = tuple((substitute(o, env), call) for o in schema.outputs)
            cost = self.task.costs.functionality(schema, call)
            return Summary(
                True, frozenset({call}), frozenset({call[1]}), frozenset(), outs, cost, 0.0, cost
            )
        expansions: list[Expanded] = []
        for option in self._instance(call).options:  # the feasible expansions, in order
            expansion = yield from self._expansion(call, option.expansion)
            if expansion is not None:
                expansions.append(expansion)
        if not expansions:
            return INFEASIBLE
        funcs = frozenset.intersection(*(e.functionalities for e in expansions))
        robots = frozenset.intersection(*(e.robots for e in expansions))
        channels = common_channels([e.channels for e in expansions])
        first = expansions[0].producers
        producers = tuple(
            (data, key if all(e.producers.get(data) == key for e in expansions) else None)
            for data, key in first.items()
        )
        minimum = min(e.minimum for e in expansions)
        wiring = min(e.wiring for e in expansions)
        together = min(e.together for e in expansions)
        return Summary(True, funcs, robots, channels, producers, minimum, wiring, together)

    def _expansion(
        self, caller: Ground, expansion: Expansion
    ) -> Generator[Ground, Summary, Expanded | None]:
        body: list[tuple[Ground, Summary, bool]] = []
        funcs: set[Ground] = set()
        robots: set[str] = set()
        channels: set[ChannelId] = set()
        for call in expansion.body:
            sub = yield call
            if not sub.feasible:
                return None
            body.append((call, sub, not self.task.is_method(call)))
            funcs |= sub.functionalities
            robots |= sub.robots
            channels |= sub.channels
        own: set[tuple[str, Ground]] = set()
        into_own: set[tuple[str, Ground, Ground]] = set()  # channels into an own functionality
        for kind, _, source, target, data, _ in expansion.channels:
            src_call, src_sum, src_func = body[source]
            dst_call, _, dst_func = body[target]
            if dst_func and self._own(dst_call, caller):
                into_own.add((kind, data, dst_call))
            else:
                own.add((kind, data))
            sender = src_call if src_func else src_sum.producer(data)
            receiver = dst_call if dst_func else None
            channels.add((kind, data, sender, receiver))
        producers: dict[Ground, Ground | None] = {}
        for data, (offset, _) in expansion.outputs.items():
            call, sub, is_functionality = body[offset]
            producers[data] = call if is_functionality else sub.producer(data)
        # A part is named by what it can reach; an own functionality (and a
        # channel into one) by itself alone: it shares with no other part.
        own_cost = float(sum(self.task.costs.channel(kind) for kind, _ in own))
        wires: list[Part] = [({data[0] for _, data in own}, own_cost)]
        wires += [(own_part(c), self.task.costs.channel(c[0])) for c in into_own]
        # Together: a part is named by both kinds of name (a functionality name
        # and a data predicate never mean one thing, so at worst two parts are
        # taken as sharing that cannot: weaker, still a bound).
        whole = list(wires)
        parts: list[Part] = []
        for call, sub, func in body:
            reached, carried, both = self.reach.of(call)
            wires.append((carried, sub.wiring))
            if func and self._own(call, caller):
                parts.append((own_part(call), sub.minimum))
                whole.append((own_part(call), sub.together))
            else:
                parts.append((reached, sub.minimum))
                whole.append((both, sub.together))
        return Expanded(
            frozenset(funcs),
            frozenset(robots),
            frozenset(channels),
            producers,
            least(parts),
            least(wires),
            least(whole),
        )


def common_channels(sets: list[frozenset[ChannelId]]) -> frozenset[ChannelId]:
    """Channels in every expansion; where only the sender differs, keep the
    channel with its sender unknown."""
    exact = frozenset.intersection(*sets)
    loose: set[ChannelId] = set(exact)
    receivers = [{(k, d, r) for k, d, _, r in s if r is not None} for s in sets]
    for kind, data, receiver in set.intersection(*receivers):
        if not any(c[0] == kind and c[1] == data and c[3] == receiver for c in exact):
            loose.add((kind, data, None, receiver))
    return frozenset(loose)
