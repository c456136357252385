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
- a channel costs ``w / S`` over the channels it might turn out identical
  to (merged, 4.5): of its kind and data, with the same ends where its ends
  are known functionality instances. An end at a method is not known until
  that method is expanded (the channel is re-wired then), so a channel with
  both ends known may merge with those that have the same sender or the
  same receiver and the other end open, or both ends open; a channel with
  only its receiver known, with every channel of that receiver, every one
  with only its sender known, and every open one; and so on. A channel
  costs nothing when C already holds one it might merge with. So the
  channels that end up as one channel are charged ``w`` at most, together:
  each of them counts all the others among its S.

Where the media let a functionality instance, robot or device serve only
so many of the expansions that bring it (each sends a view of its own over
one link), S is that many at most (:mod:`cfgplan.planner.capacity`).

Then the cost of each pending item is a plain minimum over its expansions,
leaving out those whose own global channels the media cannot carry on top
of the node's (:mod:`cfgplan.planner.room`), computed bottom-up over the
graph of ground instances (:mod:`cfgplan.planner.graph`; this bound is a
pass over it, as the capacity's and the parts' are), and the items' costs
add up: in
any completion, a shared cost is charged at most as often as it can occur,
each time ``w / S``, so never more than ``w`` in all. The search takes the
larger of the two bounds (:func:`cfgplan.planner.plan.combined`).

Items whose expansions can recur into themselves (a ground instance below
itself) have no finite occurrence count: for such tasks this bound is off.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

from cfgplan.planner.capacity import Capacity
from cfgplan.planner.graph import Instance, Option
from cfgplan.planner.ground import Grounder
from cfgplan.planner.least import Evaluation, Least
from cfgplan.planner.numbering import Numbering
from cfgplan.planner.partial import Partial
from cfgplan.planner.prices import Counts, Prices, Wire, add, most
from cfgplan.planner.split import Split, split_at
from cfgplan.planner.task import Ground

STACKS = 64
"""Stacks of pending items whose summed counts (and last evaluation) are
kept, then forgotten all at once: siblings are refined soon after each other
(the search takes them at nearly the same priority), so a few suffice, and
memory stays bounded."""

SUFFIXES = 4
"""How many of a stack's suffixes are looked up for a sum to start from
(a child's stack is its parent's with the top replaced by the top's body:
its suffix below the body was summed for the parent)."""


@dataclass(slots=True)
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


@dataclass
class Partition:
    """The partitioned bound for one task; :meth:`estimate` on each node."""

    grounder: Grounder
    media: bool = True
    """Whether expansions the media cannot carry are priced as impossible
    (:attr:`cfgplan.planner.options.SearchOptions.media`)."""
    _counts: dict[Ground, Counts] = field(default_factory=dict)
    number: Numbering = field(init=False)
    """The small integers that stand for keys in counts and totals: the
    task's one numbering (:attr:`cfgplan.planner.ground.Grounder.numbering`),
    which canonical forms and fingerprints number their values by too."""
    _cyclic: bool = False
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

    def __post_init__(self) -> None:
        task, self.number = self.grounder.task, self.grounder.numbering
        self.graph = graph = self.grounder.graph(self.media)
        """The AND/OR graph of ground instances this bound is a pass over (the grounder's)."""
        self.room = graph.room
        self.capacity = Capacity(task, self.room, self.number, graph.instances, graph.order)
        self.least = Least(self.room, self.number, graph.made)

    # -- the most occurrences of each key, a pass over the graph -----------------
    def counts(self, call: Ground) -> Counts | None:
        """Most occurrences of each key in one derivation of ``call``; None
        when ``call`` can recur into itself."""
        if self._cyclic:
            return None
        found = self._counts.get(call)
        if found is not None:
            return found
        order = self.graph.below(call, self._counts)
        if order is None:
            self._cyclic = True
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

    # -- the bound of a node ----------------------------------------------------
    def estimate(self, node: Partial, certain: frozenset[str]) -> float | None:
        """A lower bound on the cost still to come (0 when off), or None when
        some pending item has no derivation; ``certain`` are agents every
        completion uses: they are counted in full, once."""
        return self.split(node, certain, apart=False)[0]

    def split(
        self, node: Partial, certain: frozenset[str], apart: bool = True
    ) -> tuple[float | None, Split | None]:
        """:meth:`estimate`, and (``apart``) the bound taken apart at the top
        item, which the node expands next (:mod:`cfgplan.planner.split`; None
        when the bound is off)."""
        if self._cyclic:
            return 0.0, None
        task = self.grounder.task
        calls = tuple(item.call for item in node.stack)
        kept = self._pending(calls)
        if kept.pending is None:
            return 0.0, None
        present, future = self._channels(node, kept)
        totals, shared = kept.waiting(future)
        load = self.room.load(node.channels)
        lowered = self.capacity.lower(totals, calls, load)
        if lowered:
            totals, shared = {**totals, **lowered}, {}
        prices = Prices(task, node, certain, totals, present, self.number, load, shared=shared)
        memo, costs = self._evaluate(kept, calls, prices, lowered)
        total = sum(map(prices.channel, future))
        total += sum(task.agent_cost(agent) for agent in certain - node.robots)
        agent = prices.agent
        for key, on in kept.items:
            total += memo[key]
            if on is not None:  # a pending functionality, on agent ``on``
                total += agent(on)
        if total == float("inf"):
            return None, None
        if not apart:
            return total, None
        top = self.graph.instances[node.stack[0].call]
        if top.functionality:
            return total, None
        found = costs.get(top.key) if costs is not None else None
        priced = self.least.priced(top, memo, prices) if found is None else found
        return total, split_at(top, total - memo[top.key], priced)

    def _evaluate(
        self, kept: Kept, calls: tuple[Ground, ...], prices: Prices, lowered: dict[int, int]
    ) -> tuple[dict[int, float], dict[int, tuple[float, ...]] | None]:
        """The cheapest derivation of each instance below the pending items
        ``calls`` at ``prices`` (and each expansion's price, when kept): from
        the last node with these pending items evaluated, when there is one
        and it pays; recorded for the next from the third node on (a stack
        met once or twice, as on a chain, is priced as cheaply as can be).
        ``lowered``: the totals the media lowered (:meth:`Kept.touched`)."""
        least = self.least
        orders = (self.graph.order(call) for call in dict.fromkeys(calls))
        if not kept.reuse or kept.evaluated < 2:
            kept.evaluated += 1
            memo = least.full(orders, prices)
            kept.reuse = len(memo) >= least.smallest
            return memo, None
        touched = kept.touched(lowered)
        if kept.last is None:
            kept.last = least.record(orders, prices, touched)
        else:
            evaluation = least.again(kept.last, prices, touched)
            if evaluation is None:  # too much changes between these nodes
                kept.last, kept.reuse = None, False
                return least.full(orders, prices), None
            kept.last = evaluation
        return kept.last.memo, kept.last.costs

    def _pending(self, calls: tuple[Ground, ...]) -> Kept:
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
                method, instances = self.grounder.task.is_method, self.graph.instances
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
        return None if self.grounder.task.is_method(call) else self.number(("@", call[1]))

    def _channels(self, node: Partial, kept: Kept) -> tuple[set[int], list[Wire]]:
        """The keys of the channels already in C (resolved), and the wires of
        those waiting for an end (each will be one channel of the
        configuration); ``kept``: the node's pending items (:meth:`_pending`)."""
        present: set[int] = set()
        future: list[Wire] = []
        # The calls of the pending functionalities: an end at a method is not known.
        pending = {
            item.label: item.call
            for item, (_, on) in zip(node.stack, kept.items, strict=True)
            if on is not None
        }
        located, graph = node.located.get, self.graph
        for ch in node.channels:
            src, dst = located(ch.source), located(ch.target)
            if src is not None and dst is not None:
                present.update(graph.between(ch, src, dst).counted)
                continue
            sender = src.call if src is not None else pending.get(ch.source)
            receiver = dst.call if dst is not None else pending.get(ch.target)
            future.append(graph.wire(ch.kind, ch.data, sender, receiver))
        return present, future
