"""A goal's independent parts, and their configurations listed cheapest first.

The independent parts of a goal: choices that share nothing.

The planner of 4.5 expands the pending items top first, so the choices of a
derivation come in the depth-first order of the goal's tree. Where many
choices are independent (the rooms of a convoy: each room's members take
their poses from that room's cameras), a search over whole derivations
meets every combination of them, and lists each next configuration by
diving again through everything below the choice it changes. Here instead:

1. :func:`unroll` does every *forced* step first, whatever its place on
   the stack: a method with one expansion, a functionality with one binding
   or already in C. What is left on the stack are the *choice items*. An
   item keeps its *address*, the body positions from the goal down to it:
   the order of addresses is the thesis's depth-first order;
2. :func:`divide` ties two choice items when the derivations of one may
   bring what the other's may: a functionality instance, an agent not yet
   used, a robot pair both may send global channels over (the media carry
   each pair apart, 4.6), or a channel between the two. Each set of tied
   items is a *part*; the parts' costs add up (the forced steps' cost is
   common to all), and their configurations combine freely, but for
   cycles through the forced functionalities, which the combined
   configuration's own check of 4.5 step 4 still rejects;
3. :func:`segments` reads a part's derivation as the choices each of its
   items made, and :func:`replay` derives the goal in the thesis's order
   with the choices of one configuration of each part: its labels, channel
   order and cost are then exactly those of 4.5.

:class:`Combined` lists the combinations cheapest first.

Configurations of independent parts, listed cheapest first.

When the choices of a goal fall into independent parts, each part is searched on its own, best
first (:class:`cfgplan.planner.search.BestFirst` from the part's start,
listing the complete nodes step 4 admits: only their choices are combined,
so no part's configuration is built), and the configurations of the goal
are the combinations of one configuration per part: the cost of the forced
steps plus what each part adds. They are listed as the k cheapest sums are
(:func:`cfgplan.planner.search.merge`: taking a combination offers each
part's next configuration in its place), each part's list grown only as far
as the merge needs it.

At equal cost the thesis lists derivations in their depth-first order: the
first choice item (by address) where two combinations differ decides, by
the choices made below it. So a combination's place is its cost, then the
choices below every choice item in address order; a part's own search lists
its configurations in that same order, so a successor never comes before the
combination it was offered by, and the merge lists in the thesis's order
(:mod:`cfgplan.planner.search`).

Each combination listed is derived again from the goal in the thesis's
order (:func:`cfgplan.planner.combine.replay`, resumed from the last
derivation at the first choice the two make differently): labels, channel
order and cost are exactly the plain search's, and the check of 4.5 step 4 rejects
a combination with a cycle through the forced functionalities. Should a
derivation break off, or cost other than its parts' sum, or a part meet a
derivation it listed already (the plain search would number the
configurations after it differently), the plain search takes over and lists
what remains after those already listed.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Container, Hashable, Iterator, Mapping
from dataclasses import dataclass, field, replace
from typing import NamedTuple

from cfgplan.configuration.model import Configuration
from cfgplan.planner import clock
from cfgplan.planner.ground import Grounder
from cfgplan.planner.grow import Completion, Grower, successors
from cfgplan.planner.partial import Item, Partial, root
from cfgplan.planner.partition import Partition
from cfgplan.planner.pricer import Pricer
from cfgplan.planner.report import Report, Stats, Status
from cfgplan.planner.search import BestFirst, Progress, merge
from cfgplan.planner.task import Ground

Address = tuple[int, ...]
"""Where an item stands in the goal's tree: the body positions from the
goal down. The thesis's depth-first order is the order of addresses."""

Choices = Mapping[Address, tuple[int, ...]]
"""The choices a derivation makes below each choice item, in order."""


class Parts(NamedTuple):
    """The goal with its forced steps done, its choice items in parts."""

    node: Partial
    """Every forced step done; on the stack, the choice items by address."""
    address: dict[int, Address]
    """The address of each choice item, by its label in :attr:`node`."""
    parts: tuple[tuple[Item, ...], ...]
    """The choice items of each part, by address; the parts in the order of
    their first items."""

    def start(self, part: int) -> Partial:
        """The node a part's search starts from: :attr:`node` with only the
        part's items pending, and only the channels the part can resolve."""
        node = self.node
        items = self.parts[part]
        mine = {item.label for item in items}
        ends = mine | node.located.keys()
        channels = tuple(ch for ch in node.channels if ch.source in ends and ch.target in ends)
        return replace(node, stack=items, channels=channels)

    def owners(self, part: int) -> dict[int, Address]:
        """Label -> address of the part's choice items."""
        return {item.label: self.address[item.label] for item in self.parts[part]}


def _live(grounder: Grounder, node: Partial) -> list[Partial]:
    """The children of ``node`` that are not dead ends, in 4.5's order."""
    return [c for c in successors(grounder, node) if isinstance(c, Partial)]


def unroll(grounder: Grounder, goal: Ground) -> tuple[Partial, dict[int, Address]] | None:
    """The goal's node with every forced step done (the stack in address
    order), and the address of every item left; None when a forced step has
    no child at all (no configuration: the search will say why)."""
    node = root(goal)
    address: dict[int, Address] = {1: ()}
    choice: set[int] = set()  # methods found to be choices: they stay so (a
    # functionality with several bindings is one until it is placed: then reused)
    while True:
        clock.check()
        forced = None
        for index, item in enumerate(node.stack):
            if item.label in choice:
                continue
            rotated = replace(node, stack=(item, *node.stack[:index], *node.stack[index + 1 :]))
            live = _live(grounder, rotated)
            if not live:
                return None
            if len(live) == 1:
                forced = item, live[0]
                break
            if grounder.task.is_method(item.call):
                choice.add(item.label)
        if forced is None:
            return replace(node, path=()), address
        item, child = forced
        first = node.next_label
        for label in range(first, child.next_label):
            address[label] = (*address[item.label], label - first)
        stack = tuple(sorted(child.stack, key=lambda it: address[it.label]))
        node = replace(child, stack=stack)


def divide(
    grounder: Grounder, partition: Partition, node: Partial, address: dict[int, Address]
) -> Parts | None:
    """The choice items of an unrolled ``node`` in parts; None when there are
    not two, or the partitioned bound's graph of ground instances does not
    reach below one (an instance below itself: what it may bring has no
    finite list)."""
    items = node.stack
    parent = list(range(len(items)))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    holder: dict[Hashable, int] = {}

    def claim(i: int, resource: Hashable) -> None:
        j = holder.setdefault(resource, i)
        a, b = find(i), find(j)
        if a != b:
            parent[max(a, b)] = min(a, b)

    if len(items) < 2:
        return None
    room = partition.room
    index = {item.label: i for i, item in enumerate(items)}
    for i, item in enumerate(items):
        clock.check()
        below = partition.graph.reach(item.call)
        if below is None:
            return None
        for instance in below:
            if instance.functionality:
                claim(i, ("f", instance.call))
                agent = instance.call[1]
                if agent not in node.robots:
                    claim(i, ("@", agent))
                continue
            for option in instance.options:
                for need in option.needs:
                    claim(i, ("<>", need.pair))
    for ch in node.channels:
        ends = [index[e] for e in (ch.source, ch.target) if e in index]
        pair = room.pair(ch.kind, ch.robots) if room.active else None
        for i in ends:
            claim(i, ("ch", ch.source, ch.target))
            if pair is not None:
                claim(i, ("<>", pair))
    if not _fed(node, holder):
        return None
    groups: dict[int, list[Item]] = {}
    for i, item in enumerate(items):
        groups.setdefault(find(i), []).append(item)
    return Parts(
        node,
        {item.label: address[item.label] for item in items},
        tuple(tuple(group) for group in groups.values()),
    )


def _fed(node: Partial, claimed: Container[Hashable]) -> bool:
    """Whether every input of every forced functionality has a channel that
    may feed it: one in C already, or one a choice item's derivation may add
    by reusing it. If not, no completion is admissible, and the plain search
    says why (rather than the parts being combined in vain)."""
    fed = {(ch.target, ch.data) for ch in node.channels}
    return all(
        ("f", p.call) in claimed or all((p.label, need) in fed for need in p.inputs)
        for p in node.placed
    )


def segments(
    grounder: Grounder, start: Partial, path: tuple[int, ...], owners: dict[int, Address]
) -> dict[Address, tuple[int, ...]] | None:
    """The choices the derivation ``path`` from ``start`` makes below each of
    the choice items ``owners`` names (label -> address); None if the path
    does not lead through (it always does for a path a search took)."""
    made: dict[Address, list[int]] = {a: [] for a in owners.values()}
    rest = iter(path)

    def take(mine: Address) -> int | None:
        want = next(rest, None)
        if want is not None:
            made[mine].append(want)
        return want

    def adopt(parent: int, mine: Address | None, new: int, index: int) -> Address | None:
        return mine

    owner: dict[int, Address | None] = dict(owners)
    if _derive(grounder, start, owner, take, adopt) is None:
        return None
    return {a: tuple(c) for a, c in made.items()}


@dataclass(eq=False, repr=False)
class Trail:
    """Where a replay made each choice, for the next replay to resume from
    the last choice both make alike (replays of one listing share long
    beginnings: the thesis's order puts the parts' cheapest first)."""

    choices: Choices = field(default_factory=dict)
    marks: list[tuple[Partial, Address, int]] = field(default_factory=list)
    """Before each choice: the node, the choice item, the choice's index."""
    address: dict[int, Address] = field(default_factory=lambda: {1: ()})
    owner: dict[int, Address | None] = field(default_factory=dict)
    """By label: an item's address and its choice item (entries of labels
    not yet made again are stale but never read: labels are made in order)."""


def replay(
    grounder: Grounder, goal: Ground, choices: Choices, trail: Trail | None = None
) -> Partial | None:
    """The goal derived in the thesis's order, each choice item (by address)
    making ``choices``, the forced steps their one: the complete node, or
    None when that derivation breaks off (the parts were not independent).
    With a ``trail`` of the last replay, from its last choice made alike."""
    trail = Trail() if trail is None else trail
    marks, before = trail.marks, trail.choices
    taken: dict[Address, int] = dict.fromkeys(choices, 0)
    resume = len(marks) - 1  # all alike (never: two listings differ): its last
    for k, (_, mine, at) in enumerate(marks):
        made, old = choices[mine], before[mine]
        if at >= len(made) or at >= len(old) or made[at] != old[at]:
            resume = k
            break
        taken[mine] = at + 1
    if resume < 0:
        node = root(goal)
        trail.owner = {1: () if () in choices else None}
    else:
        node, mine, at = marks[resume]
        taken[mine] = at
        del marks[resume:]
    trail.choices = choices
    address = trail.address
    current = [node]

    def take(mine: Address) -> int | None:
        made, at = choices[mine], taken[mine]
        marks.append((current[0], mine, at))
        taken[mine] = at + 1
        return made[at] if at < len(made) else None

    def adopt(parent: int, mine: Address | None, new: int, index: int) -> Address | None:
        where = address[new] = (*address[parent], index)
        return mine if mine is not None else (where if where in choices else None)

    return _derive(grounder, node, trail.owner, take, adopt, current)


def _derive(
    grounder: Grounder,
    node: Partial,
    owner: dict[int, Address | None],
    take: Callable[[Address], int | None],
    adopt: Callable[[int, Address | None, int, int], Address | None],
    current: list[Partial] | None = None,
) -> Partial | None:
    """``node`` derived to its end: an item under no choice item (``owner``
    None) takes its one child (forced: :func:`unroll`); under one, where
    4.5 branches, the child ``take(owner)`` names. An item a step creates gets the owner
    ``adopt(parent label, parent's owner, new label, body position)``.
    None when a step has not the child it should."""
    while node.stack:
        if current is not None:
            current[0] = node  # the node a choice is made at, for a Trail
        item = node.stack[0]
        mine = owner[item.label]
        # The children are made only up to the one taken: a forced step's
        # first (its only one, as unroll() found), a choice item's chosen one.
        children = (c for c in successors(grounder, node) if isinstance(c, Partial))
        found = next(children, None)
        if mine is not None and found is not None and len(found.path) > len(node.path):
            want = take(mine)
            while found is not None and found.path[-1] != want:
                found = next(children, None)
        if found is None:
            return None
        child = found
        first = node.next_label
        for label in range(first, child.next_label):
            owner[label] = adopt(item.label, mine, label, label - first)
        node = child
    return node


class _Entry(NamedTuple):
    """One configuration of a part: what it adds to the forced steps' cost,
    and the choices below each of the part's items."""

    added: float
    choices: dict[Address, tuple[int, ...]]


_Offer = tuple[float, tuple[tuple[int, ...], ...], tuple[int, ...]]
"""A combination's place — cost, then the choices below each choice item in
address order — and which configuration of each part it takes."""


class _Irregular(Exception):
    """The parts turned out not to combine as assumed: hand over."""


@dataclass(eq=False, repr=False)
class Combined:
    """An iterator over configurations, best first, part by part."""

    plain: Grower
    """The plain search's grower: what the parts hand over to, if they must."""
    plain_pricer: Pricer
    """The plain search's pricer, as :attr:`plain`."""
    goal: Ground
    parts: Parts
    make: Callable[[frozenset[int]], tuple[Grower, Pricer]]
    """A fresh grower and pricer for each part's search, given the labels of
    the functionalities the forced steps placed (:attr:`Grower.given`)."""
    progress: Progress | None = None
    status: Status = Status.COMPLETE
    stats: Stats = field(default_factory=Stats)
    handed_over: bool = False
    """Whether the plain search lists the rest (the parts did not combine)."""
    _searches: list[BestFirst] = field(default_factory=list)
    _streams: list[Iterator[Completion]] = field(default_factory=list)
    _starts: list[tuple[Partial, dict[int, Address]]] = field(default_factory=list)
    """Each part's start node and its choice items' addresses by label."""
    _lists: list[list[_Entry]] = field(default_factory=list)
    """Each part's configurations found so far, in its search's order."""
    _start: float = 0.0
    _trail: Trail = field(default_factory=Trail)
    """The last replay's choices, for the next to resume from."""

    def __post_init__(self) -> None:
        # Every choice item's address, and its part, in the thesis's order.
        parts = self.parts
        self._order = sorted(
            (parts.address[item.label], p) for p, items in enumerate(parts.parts) for item in items
        )
        self._own = self.make(self.plain.given)
        """The combinations' grower and pricer: step 4 for each combination
        (:meth:`_derived`), the greedy dive. Not the plain search's: that one,
        handed over to, derives everything again from the goal, and would
        count what the combinations rejected a second time."""

    @property
    def grower(self) -> Grower:
        """The grower of the search under way, which its report and counts
        are in and a greedy dive goes on with: the combinations' own, or,
        once handed over, the plain search's."""
        return self.plain if self.handed_over else self._own[0]

    @property
    def pricer(self) -> Pricer:
        """The pricer of the search under way, as :attr:`grower`."""
        return self.plain_pricer if self.handed_over else self._own[1]

    @property
    def report(self) -> Report:
        """What the search under way met (:attr:`grower`'s): the combinations'
        rejections and the dive's dead ends, or the plain search's."""
        return self.grower.report

    def __iter__(self) -> Iterator[Configuration]:
        start = self._start = time.perf_counter()
        listed = 0
        try:
            try:
                for config in self._combine():
                    listed += 1
                    self.stats.seconds = time.perf_counter() - start  # the caller may stop here
                    yield config
            except _Irregular:
                for config in self._hand_over(listed):
                    self.stats.seconds = time.perf_counter() - start
                    yield config
        except clock.OutOfTime:
            self.status = Status.TIME_LIMIT
        self.stats.seconds = time.perf_counter() - start

    def _combine(self) -> Iterator[Configuration]:
        parts = self.parts
        for p in range(len(parts.parts)):
            grower, pricer = self.make(frozenset(parts.node.located))
            self._starts.append((parts.start(p), parts.owners(p)))
            search = BestFirst(grower, pricer, self.goal, self._progress, origin=self._starts[p][0])
            self._searches.append(search)
            self._streams.append(search.completions())
            self._lists.append([])
        first = self._offer((0,) * len(parts.parts))
        if first is None:  # some part has no configuration: let the plain search say why
            raise _Irregular
        offered = {first[2]}

        def offers(offer: _Offer) -> Iterator[_Offer]:
            """Each part's next configuration in place of the one ``offer``
            takes: no earlier in the listing (a part lists in that order)."""
            at = offer[2]
            for p in range(len(at)):
                then = (*at[:p], at[p] + 1, *at[p + 1 :])
                if then not in offered:
                    offered.add(then)
                    made = self._offer(then)
                    if made is not None:
                        yield made

        for total, _, at in merge([first], offers, lambda _: True):
            config = self._derived(at, total)
            if config is not None:
                yield config

    def _derived(self, at: tuple[int, ...], total: float) -> Configuration | None:
        """The combination ``at`` derived again from the goal in the thesis's
        order: its configuration, or None when step 4 rejects it (a cycle
        through the forced functionalities)."""
        choices: dict[Address, tuple[int, ...]] = {}
        for p, i in enumerate(at):
            choices.update(self._lists[p][i].choices)
        node = replay(self.grower.grounder, self.goal, choices, self._trail)
        if node is None or self.pricer.cost(node) != total:
            raise _Irregular
        config = self.grower.finish(node, total, self.stats.derivations + 1)
        if config is None:
            self.stats.rejected += 1
            return None
        self.stats.derivations += 1
        return config

    def _offer(self, at: tuple[int, ...]) -> _Offer | None:
        """The combination of the ``at[p]``-th configuration of each part p,
        with its place in the listing; None when a part has no more."""
        chosen = []
        raw = self.parts.node.cost
        for p, i in enumerate(at):
            got = self._entry(p, i)
            if got is None:
                return None
            chosen.append(got)
            raw += got.added
        key = tuple(chosen[p].choices[a] for a, p in self._order)
        return self.grower.levels.cost(raw), key, at

    def _entry(self, p: int, i: int) -> _Entry | None:
        """Part p's ``i``-th configuration (a completion of its search, searched
        as far as needed, not built), or None."""
        found = self._lists[p]
        while len(found) <= i:
            search = self._searches[p]
            admitted = next(self._streams[p], None)
            self._count()
            if search.status.stopped:
                self.status = search.status
                raise clock.OutOfTime
            if search.stats.duplicates:
                raise _Irregular
            if admitted is None:
                return None
            start, owners = self._starts[p]
            made = segments(self.grower.grounder, start, admitted.node.path, owners)
            if made is None:
                raise _Irregular
            found.append(_Entry(admitted.node.cost - start.cost, made))
        return found[i]

    def _progress(self, stats: Stats, elapsed: float) -> None:
        """A part's search reports progress: report this search's."""
        if self.progress is not None:
            self._count()
            self.progress(self.stats, time.perf_counter() - self._start)

    def _count(self) -> None:
        """The parts' statistics, summed into this search's."""
        for name in ("nodes", "expansions", "pruned"):
            setattr(self.stats, name, sum(getattr(s.stats, name) for s in self._searches))

    def _hand_over(self, listed: int) -> Iterator[Configuration]:
        """The plain search, skipping the ``listed`` configurations already listed."""
        plain = BestFirst(self.plain, self.plain_pricer, self.goal, self.progress)
        self.stats, self.handed_over = plain.stats, True
        for config in plain:
            if listed:
                listed -= 1
            else:
                yield config
        self.status = plain.status
