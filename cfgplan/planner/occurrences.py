"""How many times each key can occur in one derivation below a ground
instance, and in all of a stack of pending items: the counts S by which the
partitioned bound divides what may be shared (:mod:`cfgplan.planner.partition`,
whose docstring gives the rules).

The counts of an instance are a pass over the graph of ground instances
(:mod:`cfgplan.planner.graph`), children before parents: the most of each
key over its expansions, each expansion's the sum of its children's plus its
own channels and agents. A stack's sum is made from the sum of a stack met
before (its parent's, or a suffix's) a few keys at a time, and kept a while
(:class:`Kept`), with the last evaluation of a node with those items.

An instance that can recur into itself (below itself) has no finite count:
then every count is None and the bound is off.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

from cfgplan.planner.graph import Graph, Instance, Option
from cfgplan.planner.least import Evaluation
from cfgplan.planner.numbering import Numbering
from cfgplan.planner.prices import Counts, Wire, add, most
from cfgplan.planner.task import Ground, Task

STACKS = 64
"""Stacks of pending items whose summed counts (and last evaluation) are
kept, then forgotten all at once: siblings are refined soon after each other
(the search takes them at nearly the same priority), so a few suffice, and
memory stays bounded."""

SUFFIXES = 4
"""How many of a stack's suffixes are looked up for a sum to start from
(a child's stack is its parent's with the top replaced by the top's body:
its suffix below the body was summed for the parent)."""


@dataclass(eq=False, repr=False, slots=True)
class Kept:
    """What is kept for one stack of pending items: their summed counts
    (None: the bound is off), and the last node with them evaluated
    (:class:`cfgplan.planner.least.Least`: the next starts from it)."""

    pending: Counts | None
    items: tuple[tuple[int, str | None], ...] = ()
    """Each pending item's instance number, and the agent it runs on when
    it is a functionality (None: a method)."""
    last: Evaluation | None = None
    evaluated: int = 0  # nodes with them evaluated from scratch (the first two are)
    reuse: bool = True  # False: their nodes differ too much to start from another's
    _future: tuple[int, ...] = ()  # the wires :meth:`waiting` was given last (by id: made once)
    _totals: Counts | None = None  # and what it answered
    _shared: dict[int, float] = field(default_factory=dict)
    _raised: tuple[int, ...] = ()
    _touched: dict[int, int] | None = None

    def waiting(self, future: list[Wire]) -> tuple[Counts, dict[int, float]]:
        """The totals of a node with these pending items whose channels
        waiting for an end are ``future`` (each will be one channel of the
        configuration: its counted keys one more), and the wires' prices at
        those totals found so far (:attr:`cfgplan.planner.prices.Prices.shared`).
        Kept, as the last answer, from the second node with these items on
        (siblings' channels wait alike): the totals never to be changed, the
        prices only added to."""
        ident = tuple(map(id, future))
        if self._totals is None or ident != self._future:
            assert self.pending is not None  # the bound is on for these items
            totals = dict(self.pending)
            get = totals.get
            raised: list[int] = []
            for wire in future:
                raised.extend(wire.counted)
                for key in wire.counted:
                    totals[key] = get(key, 0) + 1
            if not self.evaluated:
                # The first node with these items: most stacks are met once
                # (a chain), and a copy of the totals kept for each of
                # them would add a tenth to the search's memory.
                return totals, {}
            self._future, self._totals, self._shared = ident, totals, {}
            self._raised, self._touched = tuple(raised), None
        return self._totals, self._shared

    def touched(self, lowered: dict[int, int]) -> dict[int, int]:
        """The totals of the keys whose totals differ from the pending items'
        counts at the node :meth:`waiting` answered last: those its waiting
        channels raised, and those the media ``lowered`` (never to be changed)."""
        if self._touched is None:
            assert self._totals is not None  # waiting() answered
            totals = self._totals
            self._touched = {key: totals[key] for key in self._raised}
        return {**self._touched, **lowered} if lowered else self._touched


@dataclass(eq=False, repr=False)
class Occurrences:
    """The counts of one task's ground instances and of the stacks of pending
    items met, over one graph."""

    task: Task
    graph: Graph
    number: Numbering
    """The small integers that stand for keys (the grounder's numbering)."""
    _counts: dict[Ground, Counts] = field(default_factory=dict)
    cyclic: bool = False
    """Some instance met can recur into itself: no counts (the bound is off)."""
    _stacks: dict[tuple[Ground, ...], Kept] = field(default_factory=dict)
    _sums: dict[tuple[Ground, ...], Counts] = field(default_factory=dict)
    """The summed counts of stacks and their suffixes (:meth:`_sum`)."""
    _extra: dict[Ground, tuple[Counter[Ground], Counts]] = field(default_factory=dict)
    """A method instance's counts taken apart (:meth:`_count`): the children
    every option has, and the most of the rest."""
    _over: dict[tuple[Ground, ...], tuple[Ground, Counts]] = field(default_factory=dict)
    """A stack's items below its top, and the top and the stack's summed
    counts: what a child's stack that ends with those items is summed from
    (:meth:`_derive`)."""

    def counts(self, call: Ground) -> Counts | None:
        """Most occurrences of each key in one derivation of ``call``; None
        when ``call`` can recur into itself."""
        if self.cyclic:
            return None
        found = self._counts.get(call)
        if found is not None:
            return found
        order = self.graph.below(call, self._counts)
        if order is None:
            self.cyclic = True
            return None
        for current in order:
            self._counts[current] = self._count(self.graph.instances[current])
        return self._counts[call]

    def _count(self, instance: Instance) -> Counts:
        """The most occurrences below ``instance``: over its options, the most
        of each option's. A child every option has is taken out first and
        added once, ``most(c + o for o) == c + most(o for o)`` key by key:
        the same integers, but a level of a deep chain, whose every version
        calls the level below, copies that level's counts once instead of
        walking them per version."""
        if instance.functionality:
            return {instance.key: 1}
        options = instance.options
        if not options:
            return {}
        shared = Counter(options[0].children)
        for option in options[1:]:
            shared &= Counter(option.children)
        total: Counts = {}
        for child in shared.elements():
            if total:
                add(total, self._counts[child])
            else:
                total = dict(self._counts[child])
        extra = most(self._option_count(option, shared) for option in options)
        self._extra[instance.call] = shared, extra
        add(total, extra)
        return total

    def _option_count(self, option: Option, shared: Counter[Ground]) -> Counts:
        """The occurrences in a derivation through ``option``, its children's
        most, less the ``shared`` children (counted by the caller)."""
        total: Counts = {}
        skip = shared.copy()
        for child in option.children:
            if skip[child] > 0:
                skip[child] -= 1
                continue
            add(total, self._counts[child])
        for own in option.channels:
            for key in own.counted:
                total[key] = total.get(key, 0) + 1
        for key in option.agent_keys:
            total[key] = total.get(key, 0) + 1
        return total

    def stack(self, calls: tuple[Ground, ...]) -> Kept:
        """The summed counts of the pending items ``calls`` (None: off, some
        can recur), made once per stack: the children of an expansion whose
        body is all functionalities share one (fusion: every sibling)."""
        found = self._stacks.get(calls)
        if found is None:
            if len(self._stacks) >= STACKS:
                self.forget()
            derived = self._derive(calls)
            if derived is not None:
                self._sums[calls] = derived
            found = self._stacks[calls] = Kept(self._sum(calls) if derived is None else derived)
            if found.pending is not None:
                method, instances = self.task.is_method, self.graph.instances
                found.items = tuple(
                    (instances[call].key, None if method(call) else call[1]) for call in calls
                )
                if calls and method(calls[0]):
                    self._over[calls[1:]] = calls[0], found.pending
        return found

    def forget(self) -> None:
        """Forget every stack's sums and evaluations (memory stays bounded:
        :data:`STACKS`)."""
        self._stacks.clear()
        self._sums.clear()
        self._over.clear()

    def _derive(self, calls: tuple[Ground, ...]) -> Counts | None:
        """The summed counts of ``calls`` made from those of a parent's stack,
        ``(top, *below)`` where ``calls`` ends with ``below`` (among the next
        :data:`SUFFIXES` suffixes): the top's counts are those of the children
        every option has plus the most of the rest (:meth:`_count`), so the
        sum is the parent's less that rest, less those children no longer
        pending (placed), plus the items that are not among them (and each
        pending functionality's agent). On a chain, a few keys a level
        instead of every level below (:meth:`_sum` adds up the level below
        the top). None when no such parent was summed. Integers: the same
        sums as made afresh (a key counted 0 times is left out, as there)."""
        for start in range(1, min(len(calls), SUFFIXES) + 1):
            found = self._over.get(calls[start:])
            if found is not None:
                break
        else:
            return None
        top, summed = found
        extra = self._extra.get(top)
        if extra is None:
            return None
        shared, rest = extra
        pending = Counter(calls[:start])
        totals = dict(summed)
        get, counts = totals.get, self.counts
        changed = list(rest)
        for key, n in rest.items():
            totals[key] = get(key, 0) - n
        for call in (shared - pending).elements():
            below = counts(call)
            assert below is not None  # below a top that does not recur
            changed.extend(below)
            for key, n in below.items():
                totals[key] = get(key, 0) - n
        for call in (pending - shared).elements():
            below = counts(call)
            if below is None:
                return None
            for key, n in below.items():
                totals[key] = get(key, 0) + n
        for call in calls[:start]:
            agent = self._agent(call)
            if agent is not None:
                totals[agent] = get(agent, 0) + 1
        for key in changed:
            if totals.get(key) == 0:
                del totals[key]
        return totals

    def _sum(self, calls: tuple[Ground, ...]) -> Counts | None:
        """The pending items' counts added up (None: some can recur). A
        node's stack is its parent's less the top, plus the top's body: so
        the sum of a stack is made from that of its longest suffix summed
        before (among the next :data:`SUFFIXES`), one item at a time, each
        step kept, and the next stack down the chain finds them. Integers:
        the same sums in any order."""
        sums = self._sums
        start = next(
            (i for i in range(1, min(len(calls), SUFFIXES) + 1) if calls[i:] in sums), None
        )
        if start is None:
            start = 1
            rest = self._add(calls[1:], {})
            if rest is None:
                return None
            sums[calls[1:]] = rest
        total = sums[calls[start:]]
        for i in range(start - 1, -1, -1):
            call = calls[i]
            counts = self.counts(call)
            if counts is None:
                return None
            # The larger copied, the smaller added to it: a level of a deep
            # chain counts every level below, the items below it few.
            small, total = (
                (total, dict(counts)) if len(counts) > len(total) else (counts, dict(total))
            )
            add(total, small)
            agent = self._agent(call)
            if agent is not None:
                total[agent] = total.get(agent, 0) + 1
            sums[calls[i:]] = total
        return total

    def _add(self, calls: tuple[Ground, ...], totals: Counts) -> Counts | None:
        """``totals`` with the counts of ``calls`` added (a pending
        functionality places itself on its agent too); None when one can recur."""
        get = totals.get
        for call in calls:
            counts = self.counts(call)
            if counts is None:
                return None
            for key, n in counts.items():
                totals[key] = get(key, 0) + n
            agent = self._agent(call)
            if agent is not None:
                totals[agent] = get(agent, 0) + 1
        return totals

    def _agent(self, call: Ground) -> int | None:
        """The key of the agent a pending item places itself on, counted once
        more in a stack's sum: a functionality's robot (None: a method)."""
        return None if self.task.is_method(call) else self.number(("@", call[1]))
