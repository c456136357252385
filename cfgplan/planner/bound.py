"""The first admissible bound: what every completion of a node must still add,
from the static summaries of what every expansion of a ground instance
contains, the names its derivations can reach, the parts that may share, and
the channels that wait for an end.

Parts that may share: the least a set of pending items (or of one
expansion's body items) can cost together, when each is known only by the
names it can reach and its own least cost.

What an instance can reach through method bodies, by its signature: the
functionality names and the data predicates of the channels its
derivations can contain. The first bound names the parts that may share by
them (:func:`cfgplan.planner.bound.least`): parts that reach no common name
cannot share an instance or merge a channel.

A signature reaches what the signatures its methods' bodies call reach
(every version, every binding: a superset, which only weakens the bound);
where no signature reaches itself this is made children first, each from
its children's, else by a walk of its own.

What every feasible expansion of a ground instance contains: the static
summaries the bound of a node is made of.

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

The channels of a node that wait for an end, as the first bound prices
them (:meth:`cfgplan.planner.bound.Bound.estimate`): which end each will
have where that is known already (:func:`sort_channels`), and the parts of
the least costs they make (:func:`waiting_parts`), named by their data
predicates, apart where they can merge with nothing a pending item makes.

An admissible lower bound on what a partial configuration still costs.

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

The pending items are read through their static summaries, which depend only on the task, so one
:class:`Bound` serves every search of a task.
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Hashable, Iterable, Sequence, Set
from dataclasses import dataclass, field, replace
from itertools import compress, repeat
from typing import NamedTuple

from cfgplan.planner import clock
from cfgplan.planner.graph import graph_of
from cfgplan.planner.ground import Expansion, Grounder, exists
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.partial import Item, Partial
from cfgplan.planner.task import Ground, Signature, Task
from cfgplan.planner.unify import bind_name, substitute

Part = tuple[Set[Hashable], float]
"""A part of :func:`least`: the names it can reach, its least cost."""


def own_part(thing: Hashable) -> frozenset[Hashable]:
    """The names of a part that shares with no other in :func:`least`: a name
    no functionality or data predicate has (those are strings)."""
    return frozenset({("own", thing)})


WIDE = 64
"""A part reaching more names than this is *wide* (a method deep in a
hierarchy reaches every name below it): :func:`least` does not file its names
one by one, but meets it with the others as sets; the first :data:`MOST_WIDE`
such parts only, as every part is met with each of them."""

MOST_WIDE = 8

GROUPS = 16
"""While the parts met so far make at most this many groups, the next part is
met with each group (:func:`_grouped`: a few set intersections, done in C);
past it, as on a deep recursive path with hundreds of parts of their own,
the groups are found again by filing every name (:func:`_many`). On the
dag family, whose parts mostly join one group, meeting the groups takes a
third of the time filing the names does (dag D=30's estimates);
on fusion, whose groups stay apart, filing is the cheaper."""


def least(parts: list[Part]) -> float:
    """The least a set of parts can cost together, each part given by the
    names it can reach (functionality names, or channel data predicates) and
    its own least cost: parts whose names are disjoint cannot share an
    instance, so their costs add; parts that may share count as the largest
    of them. The groups' costs are added up in order of size, so that how
    the groups were found (:func:`_grouped` or :func:`_many`) makes no
    difference, float for float."""
    found = _grouped(parts, GROUPS)
    return _many(parts) if found is None else found


def _grouped(parts: list[Part], most: int) -> float | None:
    """:func:`least`, each part met with the groups found so far (groups
    have disjoint names: a part joins every group it shares a name with);
    None once more than ``most`` groups are apart."""
    alone = 0.0  # parts that reach no name: they share with nothing
    groups: list[tuple[Set[Hashable], float]] = []  # names, the dearest part's cost
    for names, part_cost in parts:
        if not names:
            alone += part_cost
            continue
        kept: list[tuple[Set[Hashable], float]] | None = None  # (most often: all join)
        for group in groups:
            if group[0].isdisjoint(names):
                if kept is None:
                    kept = []
                kept.append(group)
            else:
                names = names | group[0]
                if group[1] > part_cost:
                    part_cost = group[1]
        if kept is None:
            groups = [(names, part_cost)]
        else:
            kept.append((names, part_cost))
            groups = kept
            if len(groups) > most:
                return None
    if len(groups) == 1:
        return alone + groups[0][1]
    return alone + sum(sorted([cost for _, cost in groups]))


def _many(parts: list[Part]) -> float:
    """:func:`least` by a union-find over the parts (a deep recursive path
    has hundreds of parts of their own, each a group). A narrow part's names are filed
    (name -> a part reaching it); a wide one is met with the filed names and
    with the other wide parts by set intersections, so that the work grows
    with the narrow names, not the wide ones (a chain of D levels: D names a
    level, D levels)."""
    owner: dict[Hashable, int] = {}  # a narrow part's name -> a part that reaches it
    wide: list[tuple[int, Set[Hashable]]] = []
    parent: list[int] = []
    cost: list[float] = []

    def root(part: int) -> int:
        while parent[part] != part:
            parent[part] = parent[parent[part]]
            part = parent[part]
        return part

    def join(a: int, b: int) -> None:
        a, b = root(a), root(b)
        if a != b:
            parent[b] = a
            cost[a] = max(cost[a], cost[b])

    alone = 0.0  # parts that reach no name: they share with nothing
    for names, part_cost in parts:
        if not names:
            alone += part_cost
            continue
        part = len(parent)
        parent.append(part)
        cost.append(part_cost)
        for other, reached in wide:
            if not reached.isdisjoint(names):
                join(other, part)
        if len(names) > WIDE and len(wide) < MOST_WIDE:
            for name in owner.keys() & names:
                join(owner[name], part)
            wide.append((part, names))
            continue
        # The hot loop: join() and root() written out, this part's root kept
        # as it changes (not found again for every name it reaches).
        mine = root(part)
        for name in names:
            a = owner.setdefault(name, part)
            if a == part:
                continue
            while parent[a] != a:
                parent[a] = parent[parent[a]]
                a = parent[a]
            if a != mine:
                parent[mine] = a
                cost[a] = max(cost[a], cost[mine])
                mine = a
    # Which part ends up a group's root depends on the order names are met
    # in (a set's, which differs from one process to the next): summed in
    # order of size, the groups' costs give one float whatever it was.
    return alone + sum(sorted(c for i, c in enumerate(cost) if parent[i] == i))


Reached = tuple[frozenset[str], frozenset[str], frozenset[str]]
"""The functionality names, the channels' data predicates, and the two together."""


@dataclass(eq=False, repr=False)
class Reach:
    """What each signature of one task can reach, memoised."""

    task: Task
    _reached: dict[Signature, Reached] = field(default_factory=dict)
    _by_call: dict[Ground, Reached] = field(default_factory=dict)

    def names(self, call: Ground) -> frozenset[str]:
        """The functionality names an instance can reach through method bodies."""
        return self.of(call)[0]

    def of(self, call: Ground) -> Reached:
        """:meth:`names`; the data predicates of the channels its expansions
        can create; and the two together."""
        found = self._by_call.get(call)
        if found is None:
            found = self._by_call[call] = self._signature((call[0], len(call) - 1))
        return found

    def _signature(self, sig: Signature) -> Reached:
        found = self._reached.get(sig)
        if found is not None:
            return found
        if not self.task.recursive:
            return self._below(sig)
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
        result = self._reached[sig] = (frozenset(names), frozenset(data), frozenset(names | data))
        return result

    def _below(self, sig: Signature) -> Reached:
        """:meth:`_signature` where no signature reaches itself: each
        from the signatures its bodies call, children first (no walk below
        every level of a deep hierarchy again)."""
        task, reached = self.task, self._reached
        stack: list[tuple[Signature, bool]] = [(sig, False)]
        while stack:
            current, ready = stack.pop()
            if current in reached:
                continue
            if current in task.functionalities:
                reached[current] = (frozenset({current[0]}), frozenset(), frozenset({current[0]}))
                continue
            versions = task.methods.get(current, ())
            # Each signature once: on a chain every version calls the level
            # below, whose sets (every name below it) are then joined once.
            children = list(dict.fromkeys((p[0], len(p) - 1) for m in versions for _, p in m.body))
            if not ready:
                stack.append((current, True))
                stack.extend((child, False) for child in children if child not in reached)
                continue
            names: list[frozenset[str]] = []
            data = [frozenset(c.data[0] for m in versions for c in m.channels)]
            for child in children:
                below = reached.get(child)
                if below is not None:  # None: a name neither method nor functionality
                    names.append(below[0])
                    data.append(below[1])
            # Each set made once (no set copied into a frozenset).
            reached_names, reached_data = frozenset().union(*names), frozenset().union(*data)
            reached[current] = (reached_names, reached_data, reached_names | reached_data)
        return reached[sig]


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
        keeps (:mod:`cfgplan.planner.partial`), so two nodes of one form
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


Resolved = tuple[str, Ground, Ground, Ground]
"""A channel whose two ends are placed: kind, data, sender, receiver."""

APART = own_part("channels")
"""The part of the channels waiting for an end that merge with nothing pending."""


def sort_channels(
    node: Partial,
    pending: dict[int, tuple[Ground, Summary]],
    methods: dict[int, Ground],
    future: set[ChannelId],
) -> set[Resolved]:
    """The node's channels whose two ends are placed; the others go to
    ``future``, each with the ends it is certain to have: a placed
    functionality, a pending one, or the certain producer of its data behind
    a pending method (None where not known). ``pending``: the pending items
    by label, with their summaries; ``methods``: the method items among them."""
    located = node.located.get
    resolved: set[Resolved] = set()
    for ch in node.channels:
        source, target = located(ch.source), located(ch.target)
        if source is not None and target is not None:
            resolved.add((ch.kind, ch.data, source.call, target.call))
            continue
        if source is not None:
            src: Ground | None = source.call
        else:
            src = _pending_end(pending, methods, ch.source, ch.data)
        dst: Ground | None = None
        if target is not None:
            dst = target.call
        elif ch.target not in methods:
            entry = pending.get(ch.target)  # a pending functionality: what it will be
            dst = entry[0] if entry is not None else None
        future.add((ch.kind, ch.data, src, dst))
    return resolved


def unreached_by(
    reach: Callable[[Ground], frozenset[str]], names: Set[str], methods: Iterable[Ground]
) -> set[str]:
    """The functionality ``names`` none of the method instances ``methods``
    can ``reach`` (:meth:`cfgplan.planner.bound.Reach.names`)."""
    left = set(names)
    for call in methods:
        if not left:
            break  # (most often at once: one item reaches every name waiting)
        left.difference_update(reach(call))
    return left


def waiting_parts(
    channel_cost: Callable[[str], float],
    future: set[ChannelId],
    resolved: set[Resolved],
    alone: frozenset[Ground],
    unreached: Set[str],
) -> list[Part]:
    """The channels waiting for an end (``future``) as parts of
    :func:`~cfgplan.planner.bound.least`, in the channels' and the together
    least costs of :meth:`~cfgplan.planner.bound.Bound.estimate`: named
    by their data predicates (parts whose data predicates differ cannot
    merge, so they add up). A channel from or into a functionality in
    ``alone`` can merge with none a pending item makes (those have both
    ends inside its expansion): they are a part of their own. So is a
    channel into a functionality whose name no pending method item can
    reach (``unreached``): a channel an item makes ends at a body item
    of its expansion, which has a name it reaches (on the
    ``dag`` family the channels into the fusers waiting on the stack
    were joined with every level below, by their data)."""
    names: set[str] = set()  # the data predicates of the channels not apart
    full = [0.0, 0.0]  # fully known channels not in C: not apart, apart
    covered: tuple[set[tuple[str, Ground, Ground]], ...] = (set(), set())
    open_ends: tuple[set[tuple[str, Ground, Ground]], ...] = (set(), set())
    apart = bool(alone or unreached)  # (seldom: most nodes have no channel apart)
    for channel in future:
        kind, data, sender, receiver = channel
        side = int(
            apart
            and (
                sender in alone
                or receiver in alone
                or (receiver is not None and receiver[0] in unreached)
            )
        )
        if not side:
            names.add(data[0])
        if receiver is None:
            continue
        if sender is None:
            open_ends[side].add((kind, data, receiver))
        elif channel not in resolved:
            full[side] += channel_cost(kind)
            covered[side].add((kind, data, receiver))
    # Channels certain to be new: fully known ones not in C, plus one per
    # (kind, data, receiver) of those whose sender is unknown and that
    # nothing known could be.
    costs = list(full)
    if open_ends[0] or open_ends[1]:
        known = {(k, d, r) for k, d, _, r in resolved}
        for side in (0, 1):
            for kind, data, receiver in open_ends[side]:
                end = (kind, data, receiver)
                if end not in covered[side] and end not in known:
                    costs[side] += channel_cost(kind)
    parts: list[Part] = [(frozenset(names), costs[0])]
    if costs[1]:
        parts.append((APART, costs[1]))
    return parts


def _pending_end(
    pending: dict[int, tuple[Ground, Summary]], methods: dict[int, Ground], label: int, data: Ground
) -> Ground | None:
    """The certain producer of ``data`` behind a pending label, if there is one."""
    entry = pending.get(label)
    if entry is None:
        return None
    call, sub = entry
    if label not in methods:
        return call
    return sub.producer(data)


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
    the canonical form (:mod:`cfgplan.planner.partial`), so two nodes of
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
