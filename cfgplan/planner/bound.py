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
  largest). This is what sees the cost of a deep hierarchy below a method;
- or else, the least any expansion of each pending item creates in
  functionalities and channels together (its ``together``), grouped alike by
  both kinds of name: where one version has the cheaper functionalities and
  another the cheaper channels (a deep chain), the sum of the two leasts is
  below what every version costs.

Sharing is accounted for by working with sets of concrete instances or of
names: two pending items needing ``camera(Emil)`` count it once, and nothing
already in C counts. A pending item with no feasible expansion makes the node
dead.

The pending items are read through their static summaries
(:mod:`cfgplan.planner.summary`), which depend only on the task, so one
:class:`Bound` serves every search of a task.
"""

from __future__ import annotations

from collections.abc import Iterable, Set
from dataclasses import dataclass, field
from itertools import compress, repeat

from cfgplan.planner.ground import Grounder
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.partial import Item, Partial
from cfgplan.planner.parts import Part, least, own_part
from cfgplan.planner.summary import ChannelId, Summaries, Summary
from cfgplan.planner.task import Ground, Task
from cfgplan.planner.waiting import sort_channels, unreached_by, waiting_parts


@dataclass(eq=False, repr=False)
class Bound:
    """The bound for one task; :meth:`estimate` on each node."""

    task: Task
    grounder: Grounder | None = None
    """The search's grounding memo, whose graph the summaries are a pass over."""
    media: bool = True
    """Which of its graphs (:attr:`cfgplan.planner.options.SearchOptions.media`)."""
    summaries: Summaries = field(init=False)

    def __post_init__(self) -> None:
        self.summaries = Summaries(self.task, self.grounder, self.media)

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

    def estimator(self, options: SearchOptions) -> Estimator:
        """:meth:`estimate` for one search, which stops counting the together
        least cost when it has not raised the bound in
        :attr:`SearchOptions.together` estimates (:class:`Together`)."""
        return Estimator(self, Together(options.together))

    def estimate(self, node: Partial, together: Together | None = None) -> float | None:
        """A lower bound on the cost still to come, or None when no completion
        exists. ``together``: one search's :class:`Together` (None: the
        together least cost is always counted where some item has slack)."""
        task = self.task
        placed = node.labels
        needed: set[Ground] = set()
        new_robots: set[str] = set()
        future: set[ChannelId] = set()
        pending: dict[int, tuple[Ground, Summary]] = {}
        methods: dict[int, Ground] = {}  # the pending method items, by label
        is_method = task.is_method
        for item in node.stack:
            sub = self.summaries.summary(item.call)
            if not sub.feasible:
                return None
            pending[item.label] = (item.call, sub)
            if is_method(item.call):
                methods[item.label] = item.call
            needed |= sub.functionalities
            new_robots |= sub.robots
            future |= sub.channels
        resolved = sort_channels(node, pending, methods, future)
        mandatory = 0.0
        for key in needed:
            if key not in placed:
                schema = task.functionalities[(key[0], len(key) - 1)]
                mandatory += task.costs.functionality(schema, key)
        # Two lower bounds on the functionalities still to add, counted two ways
        # (certain instances; least cost per group of items that cannot share).
        # Either may be the larger, and both may count the same instance, so
        # they cannot be added up: their max is a lower bound. A third counts
        # functionalities and channels together, by each item's least total (a
        # least of sums beats a sum of leasts where an item's cheaper
        # functionalities and cheaper channels come from different versions).
        # Each least cost is taken twice, the larger counting: over every
        # pending item, and without the items that repeat a method instance
        # already being expanded in this node (see _repeats).
        counted = together is None or together.counted
        alone = self._alone(node, pending, methods, future)
        have = _have(node, resolved, task)
        parts = self._parts(node, pending, methods, alone, have, counted)
        reach, cost = self.summaries.reach.names, task.costs.channel
        receivers = {c[3][0] for c in future if c[3] is not None}
        unreached = unreached_by(reach, receivers, methods.values())
        waiting = waiting_parts(cost, future, resolved, alone, unreached)
        deepest, widest, whole = parts.least(waiting)
        repeats = _repeats(node, methods)
        if repeats:
            # A channel waiting for an end merges with none a left-out item
            # makes, as far as this count goes: those are not counted at all.
            kept = {c for label, c in methods.items() if label not in repeats}
            more = unreached_by(reach, receivers - unreached, kept)
            if more:
                waiting = waiting_parts(cost, future, resolved, alone, unreached | more)
            again = parts.least(waiting, repeats)
            deepest, widest = max(deepest, again[0]), max(widest, again[1])
            whole = max(whole, again[2])
        total = max(mandatory, deepest) + widest
        if parts.slack:
            if together is not None:
                together.met(whole > total)
            total = max(total, whole)
        return total + sum(task.costs.agent(agent) for agent in new_robots - node.robots)

    def _alone(
        self,
        node: Partial,
        pending: dict[int, tuple[Ground, Summary]],
        methods: dict[int, Ground],
        future: set[ChannelId],
    ) -> frozenset[Ground]:
        """Pending functionality instances (and ends of channels waiting for
        an end) that no pending method item can derive, as only its
        ancestors call them (:meth:`Summaries.beyond`): each is a part of its
        own, which shares with nothing else pending. On a recursive path (a
        conversion graph) the path's own functionalities wait on
        the stack below the method deriving their inputs; named by their
        names, they would all count as one with it."""
        if not self.task.recursive:
            return frozenset()
        beyond = self.summaries.beyond
        above = _ancestries(i for i in node.stack if i.label in methods)
        keys = {call for label, (call, _) in pending.items() if label not in methods}
        keys |= {end for _, _, sender, receiver in future for end in (sender, receiver) if end}
        return frozenset(k for k in keys if beyond(k, above))

    def _parts(
        self,
        node: Partial,
        pending: dict[int, tuple[Ground, Summary]],
        methods: dict[int, Ground],
        alone: frozenset[Ground],
        have: Have,
        counted: bool = True,
    ) -> _Pending:
        """Each pending item as a part of the three least costs.

        Functionalities: an item's ``minimum``, less what C already has of the
        functionality names it can reach (those it could reuse). Channels: its
        ``wiring``, less C's resolved channels with the data predicates it can
        make (those it could merge with). Together: its ``together``, less
        both, named by both kinds of name; only when some item has
        :attr:`Summary.slack` (else, item by item, the together least cost is
        at most the two others' sum: every group it makes holds whole groups
        of the two others, each of its items costs at most its two parts),
        and while the search still ``counted`` it (:class:`Together`).
        A functionality in ``alone`` is a part of its own (it shares with
        nothing pending)."""
        guarded = self._guarded(node, methods)
        reach = self.summaries.reach.of
        parts = _Pending(slack=counted and any(sub.slack for _, sub in pending.values()))
        placed, resolved = have  # (often empty: no call then)
        for label, (call, sub) in pending.items():
            names, data, both = reach(call)
            wired = _within(resolved, data) if resolved else 0.0
            parts.labels.append(label)
            parts.channels.append((data, max(0.0, sub.wiring - wired)))
            if call in alone:
                new = call not in node.labels
                own = own_part(call)
                parts.functionalities.append((own, sub.minimum if new else 0.0))
                if parts.slack:
                    parts.together.append((own, sub.together if new else 0.0))
                continue
            reusable = _within(placed, names) if placed else 0.0
            if guarded:
                reusable -= guarded.get(label, 0.0)
            parts.functionalities.append((names, max(0.0, sub.minimum - reusable)))
            if parts.slack:
                parts.together.append((both, max(0.0, sub.together - reusable - wired)))
        return parts

    def _guarded(self, node: Partial, methods: dict[int, Ground]) -> dict[int, float]:
        """Per pending method item, the cost of the functionalities in C that
        its expansion cannot reuse, as only its ancestors call them
        (:meth:`Summaries.beyond`): on a recursive path (a conversion
        graph) C holds the path's own functionalities, which would
        otherwise each lower the item's least cost."""
        if not self.task.recursive:
            return {}
        summaries, task = self.summaries, self.task
        beyond = summaries.beyond
        guarded: dict[int, float] = {}
        for item in node.stack:
            if item.label not in methods:
                continue
            names = summaries.reach.names(item.call)
            ancestry = (item.ancestors,)
            total = 0.0
            for p in node.placed:
                if p.call[0] in names and beyond(p.call, ancestry):
                    total += task.costs.functionality(p.schema, p.call)
            if total:
                guarded[item.label] = total
        return guarded


@dataclass(eq=False, repr=False, slots=True)
class Together:
    """One search's use of the together least cost of :meth:`Bound.estimate`.

    It costs a third grouping of the pending items, and on some shapes
    (gateway) it never raises the bound. A search counts it until it has
    failed to raise the bound in ``left`` estimates, then stops, unless it
    raised one before: then it is counted to the end. Stopping changes no
    priority already given (every one was what it is without it), so no open
    node needs pricing again and two nodes of one canonical form still get
    one priority (:mod:`cfgplan.planner.search`)."""

    left: int
    raised: bool = False

    @property
    def counted(self) -> bool:
        return self.raised or self.left > 0

    def met(self, raised: bool) -> None:
        """One estimate counted it; ``raised``: it made the bound larger."""
        if raised:
            self.raised = True
        else:
            self.left -= 1


@dataclass(frozen=True, slots=True)
class Estimator:
    """The first bound as one search prices with it: :meth:`Bound.estimate`
    with the search's :class:`Together`."""

    bound: Bound
    together: Together

    def __call__(self, node: Partial) -> float | None:
        return self.bound.estimate(node, self.together)


@dataclass(eq=False, repr=False, slots=True)
class _Pending:
    """The pending items as parts of the three least costs of
    :meth:`Bound.estimate`: one part per item in each list, the items'
    labels in :attr:`labels`, in the same order."""

    slack: bool
    """Whether the together least cost is counted (0 when not)."""
    labels: list[int] = field(default_factory=list)
    functionalities: list[Part] = field(default_factory=list)
    channels: list[Part] = field(default_factory=list)
    together: list[Part] = field(default_factory=list)

    def least(
        self, waiting: list[Part], leave_out: Set[int] = frozenset()
    ) -> tuple[float, float, float]:
        """The three least costs, the items ``leave_out`` left out (any subset
        of the pending items gives a lower bound)."""
        functionalities, channels, together = self.functionalities, self.channels, self.together
        if leave_out:
            kept = [label not in leave_out for label in self.labels]
            functionalities = list(compress(functionalities, kept))
            channels = list(compress(channels, kept))
            together = list(compress(together, kept))
        whole = least(waiting + together) if self.slack else 0.0
        return least(functionalities), least(waiting + channels), whole


Have = tuple[dict[str, float], dict[str, float]]
"""What C already holds, per name: the cost of its functionalities by
functionality name, and of its resolved channels by data predicate (:func:`_have`)."""


def _have(node: Partial, resolved: set[tuple[str, Ground, Ground, Ground]], task: Task) -> Have:
    """:data:`Have` of ``node``, whose resolved channels are ``resolved``."""
    functionalities: dict[str, float] = {}
    if node.placed:
        cost_of, get = task.costs.functionality, functionalities.get
        for p in node.placed:
            functionalities[p.call[0]] = get(p.call[0], 0.0) + cost_of(p.schema, p.call)
    channels: dict[str, float] = {}
    if resolved:
        channel_cost, get = task.costs.channel, channels.get
        for kind, data, _, _ in resolved:
            channels[data[0]] = get(data[0], 0.0) + channel_cost(kind)
    return functionalities, channels


def _within(costs: dict[str, float], names: Set[str]) -> float:
    """The costs of ``names`` (walking the smaller side: a pending
    functionality reaches one name, C may hold hundreds)."""
    if not costs or not names:
        return 0.0
    if len(names) < len(costs):
        return sum(map(costs.get, names, repeat(0.0)))
    return sum([cost for name, cost in costs.items() if name in names])


def _repeats(node: Partial, methods: dict[int, Ground]) -> set[int]:
    """The labels of pending method items (``methods``) whose ground instance is being
    expanded elsewhere in the node (an ancestor of another item).

    Left out of a least cost, such an item is priced at nothing, which it may
    cost (expanded as the other occurrence is, its functionalities are reused
    and its channels merge, 4.5). Any subset of the pending items gives a
    lower bound: parts that cannot share still add up, and what the left-out
    items add is at least nothing. Counted, the repeat could share with every
    part of the other occurrence's body and join them into one, priced as the
    largest (shared sub-derivations). Ancestors are part of
    the canonical form (:mod:`cfgplan.planner.canonical`), so two nodes of
    one form leave out the same items."""
    if not methods:
        return set()
    above: set[Ground] = set()
    for ancestors in _ancestries(node.stack):
        above |= ancestors
    return {label for label, call in methods.items() if call in above}


def _ancestries(items: Iterable[Item]) -> list[frozenset[Ground]]:
    """The ancestors of ``items`` (stack items), a run of siblings' once:
    they share one set, and lie side by side on the stack."""
    found: list[frozenset[Ground]] = []
    last = None
    for item in items:
        if item.ancestors is not last:
            last = item.ancestors
            found.append(last)
    return found
