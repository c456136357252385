"""The independent parts of a goal: choices that share nothing.

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

:mod:`cfgplan.planner.combine` lists the combinations cheapest first.
"""

from __future__ import annotations

from collections.abc import Callable, Container, Hashable, Mapping
from dataclasses import dataclass, field, replace
from typing import NamedTuple

from cfgplan.planner import clock
from cfgplan.planner.ground import Grounder
from cfgplan.planner.partial import Item, Partial, root
from cfgplan.planner.partition import Partition
from cfgplan.planner.successors import successors
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
