"""A partial configuration, the search node of thesis 4.5, and the steps that
grow it: its channels (re-wired at an expansion, settled once both ends are
placed), the media's room for them, what it remembers of the sub-derivations
it closed, and its canonical form.

The channels of a partial configuration (thesis 4.5): how a method's
expansion re-wires those at the expanded instance (step 3d, :func:`rewire`),
and how they settle once both their ends are placed (step 2a,
:func:`settle`): their location checked, an identical one merged, the
media's room for the global ones checked early (4.6), as step 4 would.
The node they belong to, and the steps that call these, are
below in this module (:class:`Partial`).

What the media still have room for: a node-level test of communication
admissibility (4.6) that the partitioned bound applies to every expansion
it prices (:mod:`cfgplan.planner.partition`).

A global channel is declared between two robots, ``(global S R)``, when
its method is expanded, and it keeps them whatever it is re-wired to later
(a channel placed elsewhere is a dead end, 4.5 step 4). So every global
channel of a node between two different robots will, in every completion,
load the media from S to R by at least its bandwidth (0 while unknown: a
channel sent from a method gets its bandwidth from that method's ``:out``
when it is expanded). Channels are merged only when they are identical
(same kind, ends and data), and a merge keeps the larger bandwidth; so the
channels of one *group* — robot pair, kind and data — load the pair by at
least the largest bandwidth among them, and different groups add up.

An expansion whose own global channels would, on top of that load, need
more from a pair than all its media together carry (or more than its
largest medium for one channel, or a medium where there is none) has no
admissible completion below this node: the bound prices it as impossible.
That is what makes a member that takes a raw image stream (40) from a
camera host over a medium of 40 unable to take its pose (5) from the same
host too, before either is placed.

What a search node remembers of the sub-derivations it closed, for
replays (:mod:`cfgplan.planner.grow`, which has the rules): the records of
closed sub-derivations and the expansions still open. A node carries its
:class:`Memory` (:attr:`cfgplan.planner.partial.Partial.memory`); none of
it is ever written once made.

A partial configuration: the search node of the planner (thesis 4.5).

It holds the method stack, the functionalities added so far (C), the channels
(Ch), the collected postconditions (P) and the label counter. The two steps of
4.5 that grow it are here: :func:`expand_method` (step 3) and
:func:`place_functionality` / :func:`reuse_functionality` (step 2a); how they
re-wire and settle its channels is this module. Every step
returns a new node or a :class:`DeadEnd` with its reason; nodes are never
mutated once built, so the search can keep many of them.

Labels: the goal is label 1 and every instance a method body creates takes
the next number, in body order, when the method is expanded. A reused
functionality keeps the label of its first instance.

The canonical form of a search node: the node up to labels, as a short
digest (thesis 4.5 builds the same partial configuration along different
orders of choices; the search expands each form once, :mod:`cfgplan.planner.search`).

Nodes share most of their items, placed instances and channels: each one is
numbered when it is made (:class:`cfgplan.planner.ground.Expansion` carries
the numbers), so these functions only read nodes, never write them. The root
item, an item below a recursive method (its number depends on those
ancestors, and most children made are never taken), and items or channels
built by hand (tests) have none (-1): it is looked up here each time.
"""

from __future__ import annotations

import hashlib
from array import array
from collections.abc import Callable, Hashable, Iterable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any, NamedTuple, Protocol

from cfgplan.configuration.media import Demand, assign
from cfgplan.ir.model import Span
from cfgplan.notation import atom_text, call_text
from cfgplan.planner import clock
from cfgplan.planner.ground import (
    ChannelSpec,
    Expansion,
    FunctionalityInstance,
    Grounder,
    Numbering,
)
from cfgplan.planner.report import Condition, DeadEnd
from cfgplan.planner.task import FunctionalitySchema, Ground, Task


class Located(Protocol):
    """What settling a channel reads of a functionality placed at one end
    (:class:`cfgplan.planner.partial.Placed`): its call and its robot."""

    @property
    def call(self) -> Ground: ...
    @property
    def robot(self) -> str: ...


ChannelKey = tuple[str, int, int, Ground]
"""A resolved channel's identity: kind, sender label, receiver label, data."""


@dataclass(slots=True)  # not frozen: cheaper to build; never mutated
class Channel:
    """A channel between two labels; resolved once both are functionalities."""

    kind: str
    robots: Ground
    source: int
    target: int
    data: Ground
    bandwidth: float | None
    number: int = -1  # (kind, robots, data, bandwidth) numbered when made


Port = tuple[int, float | None]
"""Where a channel's sending end goes once re-wired: a label, and the bandwidth
of the ``:out`` entry it went through (None: it has none)."""


class Unwired(NamedTuple):
    """A channel that cannot be re-wired: no ``end`` entry (``:out`` or ``:in``) for ``data``."""

    end: str
    data: Ground


def rewire(
    channels: Sequence[Channel],
    label: int,
    out: Callable[[Ground], Port | None],
    into: Callable[[Ground], Sequence[int] | None],
    number: Callable[[Hashable], int] | None,
) -> tuple[list[Channel], list[int]] | Unwired:
    """Step 3d of 4.5: every channel at ``label`` re-wired in place, its
    sending end through ``out`` (a global channel without a bandwidth takes
    the ``:out`` entry's, numbered by ``number``) and its receiving end
    through ``into`` (an ``:in`` may feed several: one channel each), both
    ends when it runs from the instance to itself. The channels, and the
    indices of those re-wired; or the first end that cannot be. One
    expansion's ports (:func:`cfgplan.planner.partial.expand_method`) or a
    replayed walk's, port after port (:func:`cfgplan.planner.grow.replay`)."""
    rewired: list[Channel] = []
    touching: list[int] = []
    for ch in channels:
        at_source, at_target = ch.source == label, ch.target == label
        if not (at_source or at_target):
            rewired.append(ch)
            continue
        source, bandwidth, numbered = ch.source, ch.bandwidth, ch.number
        if at_source:
            port = out(ch.data)
            if port is None:
                return Unwired(":out", ch.data)
            source = port[0]
            if bandwidth is None and ch.kind == "global" and port[1] is not None:
                bandwidth = port[1]  # a global channel allocates the :out's bandwidth
                assert number is not None  # the grounder numbers what it makes
                numbered = number((ch.kind, ch.robots, ch.data, bandwidth))
        targets: Sequence[int] = (ch.target,)
        if at_target:
            found = into(ch.data)
            if not found:
                return Unwired(":in", ch.data)
            targets = found
        for target in targets:
            touching.append(len(rewired))
            rewired.append(
                Channel(ch.kind, ch.robots, source, target, ch.data, bandwidth, numbered)
            )
    return rewired, touching


def settle(
    channels: tuple[Channel, ...],
    located: Mapping[int, Located],
    touching: list[int],
    resolved: frozenset[ChannelKey],
    task: Task,
) -> tuple[tuple[Channel, ...], float, frozenset[ChannelKey]] | DeadEnd:
    """The channels at ``touching`` (indices) may just have got both ends
    placed: check their location, merge each with an identical channel already
    resolved (same kind, ends and data; the larger bandwidth is kept), and
    return the channels, the cost the newly resolved ones add, and the
    identities of all resolved channels."""
    if not touching:
        return channels, 0.0, resolved
    out = list(channels)
    new: set[ChannelKey] = set()
    dropped: list[int] = []
    added = 0.0
    new_global = False  # a global channel newly resolved: the media may overflow
    for i in touching:
        ch = channels[i]
        src, dst = located.get(ch.source), located.get(ch.target)
        if src is None or dst is None:
            continue
        wanted = (ch.robots[0], ch.robots[0]) if ch.kind == "local" else ch.robots
        if (src.robot, dst.robot) != wanted:
            return _misplaced(ch, src, dst)
        ident = (ch.kind, ch.source, ch.target, ch.data)
        if ident not in resolved and ident not in new:
            new.add(ident)
            added += task.costs.channel(ch.kind)
            if ch.kind == "global":
                added += task.costs.link(src.robot, dst.robot)
                new_global = True
            continue
        # An identical channel is already there (rare): keep it, drop this one.
        j = next(
            j
            for j, c in enumerate(out)
            if j != i
            and j not in dropped
            and (c.kind, c.source, c.target, c.data) == ident
            and c.source in located
            and c.target in located
        )
        kept = out[j]
        if ch.bandwidth is not None and (kept.bandwidth is None or ch.bandwidth > kept.bandwidth):
            out[j] = Channel(
                kept.kind,
                kept.robots,
                kept.source,
                kept.target,
                kept.data,
                ch.bandwidth,
                ch.number,  # the number of (kind, robots, data) with ch's bandwidth
            )
        dropped.append(i)
    if dropped:
        out = [c for i, c in enumerate(out) if i not in dropped]
    if new_global and task.media:
        overflow = _media(out, located, task)
        if overflow is not None:
            return overflow
    return tuple(out), added, resolved | new if new else resolved


def demands(channels: Sequence[Channel], located: Mapping[int, Located]) -> list[Demand | None]:
    """What each channel needs of the media, in order: a global channel whose
    two ends are placed on different robots needs its bandwidth; any other
    needs nothing (None)."""
    out: list[Demand | None] = []
    for ch in channels:
        src, dst = located.get(ch.source), located.get(ch.target)
        if ch.kind == "global" and src is not None and dst is not None and src.robot != dst.robot:
            out.append(Demand(src.robot, dst.robot, ch.bandwidth or 0.0))
        else:
            out.append(None)
    return out


def _media(channels: list[Channel], located: Mapping[int, Located], task: Task) -> DeadEnd | None:
    """Communication admissibility (4.6) of the global channels whose two ends
    are placed: they are final (a merge only raises a bandwidth), so if they
    overflow the media now, every completion does (step 4 would reject it)."""
    result = assign(demands(channels, located), task.media, clock.check)
    if result.ok:
        return None
    return DeadEnd("configuration", result.problem, None, Condition.COMMUNICATION)


def _misplaced(ch: Channel, src: Located, dst: Located) -> DeadEnd:
    return DeadEnd(
        f"{ch.kind} channel {atom_text(ch.data)}",
        f"declared ({ch.kind} {' '.join(ch.robots)}) but it runs from "
        f"{call_text(src.call)} on {src.robot} to "
        f"{call_text(dst.call)} on {dst.robot}",
        condition=Condition.LOCATION,
    )


class Need(NamedTuple):
    """An expansion's own global channels of one group: the group's number,
    its robot pair's number and the largest bandwidth among them."""

    group: int
    pair: int
    bandwidth: float


Load = dict[int, float]
"""The least load of a node by group number, and by ``-1 - pair`` for each
pair's sum over its groups."""


@dataclass(eq=False, repr=False)
class Room:
    """The media of one task, by robot pair: what they carry together and
    the largest of them (a channel is never split over two media)."""

    task: Task
    number: Callable[[Hashable], int]
    media: bool = True
    """False: ask nothing of the media (:attr:`SearchOptions.media
    <cfgplan.planner.options.SearchOptions.media>`)."""

    def __post_init__(self) -> None:
        self._groups: dict[tuple[str, tuple[str, ...], object], tuple[int, int] | None] = {}
        self.total: dict[int, float] = {}
        self.largest: dict[int, float] = {}
        for medium in self.task.media:
            pair = self.number(("<>", medium.sender, medium.receiver))
            self.total[pair] = self.total.get(pair, 0.0) + medium.capacity
            self.largest[pair] = max(self.largest.get(pair, 0.0), medium.capacity)

    @property
    def active(self) -> bool:
        """Without media every channel fits (4.6 applies only when declared)."""
        return self.media and bool(self.task.media)

    def pair(self, kind: str, robots: Sequence[str]) -> int | None:
        """The number of the robot pair a channel of ``kind`` declared
        between ``robots`` loads; None when it needs no medium."""
        if kind != "global" or len(robots) != 2 or robots[0] == robots[1]:
            return None
        return self.number(("<>", robots[0], robots[1]))

    def _group(self, kind: str, robots: Sequence[str], data: object) -> tuple[int, int] | None:
        """The numbers of a channel's group and robot pair (None: it needs no
        medium), made once per (kind, robots, data)."""
        ident = (kind, tuple(robots), data)
        try:
            return self._groups[ident]
        except KeyError:
            pass
        pair = self.pair(kind, robots)
        found = None
        if pair is not None:
            found = self.number(("<>", robots[0], robots[1], kind, data)), pair
        self._groups[ident] = found
        return found

    def needs(self, specs: Sequence[ChannelSpec]) -> tuple[Need, ...]:
        """The needs of an expansion's own channels, one per group."""
        if not self.active:
            return ()
        largest: dict[tuple[int, int], float] = {}
        for kind, robots, _, _, data, bandwidth in specs:
            found = self._group(kind, robots, data)
            if found is not None:
                largest[found] = max(largest.get(found, 0.0), bandwidth or 0.0)
        return tuple(Need(group, pair, b) for (group, pair), b in largest.items())

    def load(self, channels: Iterable[Channel]) -> Load:
        """The least load every completion of a node with ``channels`` (resolved
        or waiting for an end) puts on the media."""
        load: Load = {}
        if not self.active:
            return load
        for ch in channels:
            found = self._group(ch.kind, ch.robots, ch.data)
            if found is None:
                continue
            group, pair = found
            b = ch.bandwidth or 0.0
            before = load.get(group, 0.0)
            if b > before or group not in load:
                load[group] = max(b, before)
                load[-1 - pair] = load.get(-1 - pair, 0.0) + max(b - before, 0.0)
        return load

    def fits(self, needs: tuple[Need, ...], load: Load) -> bool:
        """Whether the media can carry ``needs`` on top of ``load``."""
        added: dict[int, float] = {}
        for need in needs:
            largest = self.largest.get(need.pair)
            if largest is None or need.bandwidth > largest:
                return False
            more = need.bandwidth - load.get(need.group, 0.0)
            if more > 0:
                added[need.pair] = added.get(need.pair, 0.0) + more
        for pair, more in added.items():
            if load.get(-1 - pair, 0.0) + more > self.total[pair] + 1e-9:
                return False
        return True


def _joined(parts: list[tuple[int, ...]]) -> tuple[int, ...]:
    """The tuples ``parts`` end to end, concatenated two by two: each element
    is copied about log2(len(parts)) times, and a concatenation copies in a
    quarter of the time a list extended then made a tuple does (a dag's walks
    are millions of choices long; a body may have many method items)."""
    while len(parts) > 1:
        pairs = range(0, len(parts) - 1, 2)
        parts = [parts[i] + parts[i + 1] for i in pairs] + parts[len(pairs) * 2 :]
    return parts[0]


@dataclass(eq=False, slots=True)
class Record:
    """A closed sub-derivation: the method instance ``call`` expanded by
    ``expansion``, and the records of its body's method items, in body order
    (a record is shared by every sub-derivation that replayed it)."""

    call: Ground
    choice: int
    """Its expansion's number among the method's (as successors numbers them)."""
    expansion: Expansion
    children: tuple[Record, ...]
    at: dict[int, Record]
    """The children by their body offset."""
    _flat: tuple[int, ...] | None = None
    _size: int = -1
    _effects: tuple[tuple[bool, Ground], ...] | None = None
    _calls: frozenset[Ground] | None = None

    @property
    def flat(self) -> tuple[int, ...]:
        """The choices of the walk, in path order (this expansion's, then each
        child's in body order)."""
        if self._flat is None:
            self._flat = _joined([(self.choice,), *(child.flat for child in self.children)])
        return self._flat

    @property
    def size(self) -> int:
        """The labels the walk takes: every body item of every expansion."""
        if self._size < 0:
            self._size = self.expansion.size + sum(c.size for c in self.children)
        return self._size

    @property
    def effects(self) -> tuple[tuple[bool, Ground], ...]:
        """The postconditions the walk's expansions add, in their order."""
        if self._effects is None:
            effects = list(self.expansion.effects)
            for child in self.children:
                effects.extend(child.effects)
            self._effects = tuple(effects)
        return self._effects

    @property
    def calls(self) -> frozenset[Ground]:
        """The method instances the walk expands (the recursion guard's concern)."""
        if self._calls is None:
            calls = {self.call}
            for child in self.children:
                calls |= child.calls
            self._calls = frozenset(calls)
        return self._calls

    def source(self, data: Ground) -> tuple[Ground, float | None] | None:
        """Where a channel of ``data`` sent from this instance starts once the
        walk re-wired it through each ``:out`` (4.5 step 3d): the functionality
        call, and the bandwidth of the first ``:out`` on the way that has one
        (the one a global channel without takes); None when a ``:out`` is
        missing."""
        record = self
        bandwidth = None
        while True:
            expansion = record.expansion
            port = expansion.outputs.get(data)
            if port is None:
                return None
            if bandwidth is None:
                bandwidth = port[1]
            child = record.at.get(port[0])
            if child is None:
                return expansion.body[port[0]], bandwidth
            record = child

    def targets(self, data: Ground) -> tuple[Ground, ...] | None:
        """Where a channel of ``data`` received by this instance ends once
        re-wired through each ``:in`` (an ``:in`` may feed several): the
        functionality calls in channel order; None when an ``:in`` is missing."""
        expansion = self.expansion
        offsets = expansion.inputs.get(data)
        if not offsets:
            return None
        ends: list[Ground] = []
        for offset in offsets:
            child = self.at.get(offset)
            if child is None:
                ends.append(expansion.body[offset])
                continue
            inner = child.targets(data)
            if inner is None:
                return None
            ends.extend(inner)
        return tuple(ends)


class Opening(NamedTuple):
    """A method instance expanded whose sub-derivation is not closed yet (a
    named tuple: one is made for every expansion remembered)."""

    call: Ground
    choice: int
    expansion: Expansion
    depth: int
    """The stack's length once it is closed (its item's stack, less it)."""
    children: tuple[Record, ...] = ()
    pure: bool = True
    """No functionality binding was chosen in it (those are not replayed:
    the instance reused would take no choice there)."""


class Memory(NamedTuple):
    """What a node remembers for replays: the expansions still open, innermost
    last, and a record for each repeatable instance it closed (the first;
    never written: a close copies it)."""

    opened: tuple[Opening, ...]
    records: Mapping[Ground, Record]


@dataclass(slots=True)  # not frozen: cheaper to build; never mutated
class Item:
    """A method or functionality instance waiting on the stack."""

    label: int
    call: Ground  # (name, *args)
    ancestors: frozenset[Ground]  # method instances above it: the recursion guard
    relevant: frozenset[Ground] = frozenset()  # its ancestors whose method can recur
    number: int = -1  # (call, relevant) numbered when made; -1: canonical() numbers it
    # (the root, and an item with relevant ancestors: numbering every child made costs more)


@dataclass(slots=True)  # not frozen: cheaper to build; never mutated
class Placed:
    """A functionality instance in the configuration, located at ``robot``
    (its first argument), with its inputs and outputs instantiated."""

    label: int
    call: Ground
    schema: FunctionalitySchema
    robot: str
    inputs: tuple[Ground, ...]
    outputs: tuple[Ground, ...]
    number: int  # its part of canonical(): FunctionalityInstance.number
    name: int  # its call, as canonical() names it: FunctionalityInstance.name


@dataclass(slots=True)  # not frozen: cheaper to build; never mutated
class Partial:
    """A node of the search: a configuration under construction."""

    stack: tuple[Item, ...]
    placed: tuple[Placed, ...]  # in the order added
    labels: dict[Ground, int]  # functionality instance -> its label
    located: dict[int, Placed]  # label -> placed functionality
    channels: tuple[Channel, ...]  # in the thesis's list order (newest block first)
    effects: tuple[tuple[bool, Ground], ...]
    next_label: int
    path: tuple[int, ...]  # the choices made: orders equal costs as the thesis does
    cost: float  # of the settled part: placed functionalities, robots, resolved channels
    robots: frozenset[str]  # where the placed functionalities run
    resolved: frozenset[ChannelKey]  # channels whose two ends are placed
    memory: Memory | None = None
    """The sub-derivations it closed, for replays (:mod:`cfgplan.planner.grow`;
    None where the search does not replay)."""
    floor: float = 0.0
    """A lower bound on the cost of each of its derivations, known from an
    ancestor (a replay's deviations, :func:`cfgplan.planner.grow.deviations`)."""
    forbidden: tuple[tuple[int, ...], ...] = ()
    """Runs of choices it must not make next, to their end: the replays
    made beside an ancestor (:func:`cfgplan.planner.grow.filtered`)."""
    deviates: bool = False
    """It stands for a replayed node's other derivations: its top item is
    expanded step by step, not replayed again."""

    @property
    def done(self) -> bool:
        return not self.stack

    def but(self, **changes: Any) -> Partial:
        """A new node like this one but for ``changes`` (this one is kept as it is)."""
        return replace(self, **changes)


def root(goal: Ground) -> Partial:
    """The initial node: the goal alone on the stack, C empty."""
    return Partial(
        stack=(Item(1, goal, frozenset()),),
        placed=(),
        labels={},
        located={},
        channels=(),
        effects=(),
        next_label=2,
        path=(),
        cost=0.0,
        robots=frozenset(),
        resolved=frozenset(),
    )


# -- step 3: expand a method ---------------------------------------------------------


def expand_method(
    node: Partial,
    item: Item,
    expansion: Expansion,
    span: Span | None,
    choice: int,
    memory: Memory | None = None,
) -> Partial | DeadEnd:
    """Step 3 of 4.5: fresh labels (a), add the method's channels (b), push its
    body (c), and re-wire every channel at the expanded instance through
    ``:out`` (its sending end) and ``:in`` (its receiving end) (d). A channel
    with *both* ends at the instance is re-wired at both; if that makes a
    functionality feed itself, the cycle check of step 4 rejects it.
    ``memory``: the child's (:meth:`cfgplan.planner.grow.Replays.expanding`;
    None where the search does not replay)."""
    first = node.next_label
    numbered = expansion.channel_numbers
    block = [
        Channel(kind, robots, first + src, first + dst, data, bandwidth, numbered[i])
        for i, (kind, robots, src, dst, data, bandwidth) in enumerate(expansion.channels)
    ]
    outputs, inputs = expansion.outputs, expansion.inputs

    def out(data: Ground) -> Port | None:
        port = outputs.get(data)
        return None if port is None else (first + port[0], port[1])

    def into(data: Ground) -> tuple[int, ...] | None:
        offsets = inputs.get(data)
        return tuple(first + k for k in offsets) if offsets else None

    done = rewire(node.channels, item.label, out, into, expansion.number)
    if isinstance(done, Unwired):
        verb = "produces" if done.end == ":out" else "consumes"
        missing = f"no {done.end} entry {verb} {atom_text(done.data)}"
        return DeadEnd(expansion.where, missing, span, Condition.INFORMATION)
    rewired = done[0]
    ancestors = item.ancestors | {item.call}
    # The body's relevant ancestors: the item's, and the item when its method
    # can recur; when every ancestor is one (a domain of one recursive
    # method, a conversion graph), they are the ancestors themselves, shared.
    relevant = item.relevant
    if expansion.recursive:
        relevant = ancestors if len(relevant) == len(item.ancestors) else relevant | {item.call}
    if relevant:  # numbered with them by canonical(): cheaper than numbering every child made
        pushed = tuple(
            [Item(first + i, call, ancestors, relevant) for i, call in enumerate(expansion.body)]
        )
    else:
        numbers = expansion.body_numbers
        pushed = tuple(
            [
                Item(first + i, call, ancestors, relevant, numbers[i])
                for i, call in enumerate(expansion.body)
            ]
        )
    # Fresh labels are not placed yet: no channel got resolved, nothing to settle.
    return Partial(
        stack=(*pushed, *node.stack[1:]),
        placed=node.placed,
        labels=node.labels,
        located=node.located,
        channels=(*block, *rewired),
        effects=node.effects + expansion.effects if expansion.effects else node.effects,
        next_label=first + expansion.size,
        # Concatenated, not unpacked (RUF005): it copies in a quarter of the
        # time, and a dag's replayed paths are millions of choices long.
        path=node.path + (choice,),  # noqa: RUF005
        cost=node.cost,
        robots=node.robots,
        resolved=node.resolved,
        memory=memory,
        floor=node.floor,
    )


# -- step 2a: add a functionality, or reuse the one already in C ----------------------


def reuse_functionality(
    node: Partial, item: Item, existing: int, task: Task, memory: Memory | None = None
) -> Partial | DeadEnd:
    """Step 2a of 4.5 when the instance "already exists in the current
    configuration": it is not added again; the channels at the item's label
    move to the existing label (and may now have both ends placed)."""
    old = item.label
    relabelled = list(node.channels)
    touching = []
    for i, ch in enumerate(relabelled):
        if ch.source == old or ch.target == old:
            touching.append(i)
            relabelled[i] = Channel(
                ch.kind,
                ch.robots,
                existing if ch.source == old else ch.source,
                existing if ch.target == old else ch.target,
                ch.data,
                ch.bandwidth,
                ch.number,
            )
    settled = settle(tuple(relabelled), node.located, touching, node.resolved, task)
    if isinstance(settled, DeadEnd):
        return settled
    channels, added, resolved = settled
    return Partial(
        stack=node.stack[1:],
        placed=node.placed,
        labels=node.labels,
        located=node.located,
        channels=channels,
        effects=node.effects,
        next_label=node.next_label,
        path=node.path,
        cost=node.cost + added,
        robots=node.robots,
        resolved=resolved,
        memory=memory,
        floor=node.floor,
    )


def place_functionality(
    node: Partial,
    item: Item,
    schema: FunctionalitySchema,
    instance: FunctionalityInstance,
    choice: int | None,
    task: Task,
    memory: Memory | None = None,
) -> Partial | DeadEnd:
    """Step 2a of 4.5: add the functionality to C at its robot (its first
    argument), with its inputs, outputs and postconditions instantiated under
    one binding of its preconditions (``instance``); ``choice`` is that
    binding's index when there are several."""
    inputs, outputs = instance.io
    new = Placed(
        item.label, item.call, schema, item.call[1], inputs, outputs, instance.number, instance.name
    )
    effects = instance.effects
    located = dict(node.located)
    located[item.label] = new
    label = item.label
    touching = [i for i, ch in enumerate(node.channels) if ch.source == label or ch.target == label]
    settled = settle(node.channels, located, touching, node.resolved, task)
    if isinstance(settled, DeadEnd):
        return settled
    channels, added, resolved = settled
    added += task.costs.functionality(schema, item.call)
    robots = node.robots
    if new.robot not in robots:
        added += task.costs.agent(new.robot)
        robots = robots | {new.robot}
    labels = dict(node.labels)
    labels[item.call] = item.label
    return Partial(
        stack=node.stack[1:],
        placed=node.placed + (new,),  # noqa: RUF005 (faster: see expand_method)
        labels=labels,
        located=located,
        channels=channels,
        effects=node.effects + effects if effects else node.effects,
        next_label=node.next_label,
        path=node.path if choice is None else node.path + (choice,),  # noqa: RUF005
        cost=node.cost + added,
        robots=robots,
        resolved=resolved,
        memory=memory,
        floor=node.floor,
    )


def placed_names(node: Partial) -> dict[int, int]:
    """Each placed instance's call, numbered, by label."""
    return {p.label: p.name for p in node.placed}


def channel_number(channel: Channel, number: Numbering) -> int:
    """The channel's kind, robots, data and bandwidth, numbered: made with
    it (:attr:`cfgplan.planner.partial.Channel.number`) or looked up now."""
    found = channel.number
    if found < 0:
        found = number((channel.kind, channel.robots, channel.data, channel.bandwidth))
    return found


def channel_numbers(node: Partial, names: dict[int, int], number: Numbering) -> list[int]:
    """Each channel with its ends named by ``names``, numbered as a whole
    (one number to sort), in the node's order."""
    get = number.numbers.get
    out = []
    for ch in node.channels:
        numbered = ch.number  # (most are numbered when made: no call then)
        if numbered < 0:
            numbered = channel_number(ch, number)
        key = (numbered, names[ch.source], names[ch.target])
        found = get(key)
        out.append(number(key) if found is None else found)
    return out


def digest(numbers: list[int]) -> bytes:
    """A list of numbers as a 128-bit BLAKE2 digest: two different lists share
    one with odds of about 2^-128 per pair, far below anything a run can meet."""
    return hashlib.blake2b(array("q", numbers).tobytes(), digest_size=16).digest()


def canonical(node: Partial, grounder: Grounder) -> bytes:
    """The node up to labels — placed instances, channels, stack and P — as a
    128-bit :func:`digest`. Two nodes with the same canonical form have the
    same completions (up to labels). An item's ancestors count only where they
    can matter: those whose method can recur (:attr:`Task.recursive`, kept as
    :attr:`cfgplan.planner.partial.Item.relevant`); in a domain without
    recursion the order in which items were reached is forgotten. It takes 16
    bytes where the form takes kilobytes, so every expanded node can be
    remembered."""
    number = grounder.numbering
    names = placed_names(node)
    placed = sorted(p.number for p in node.placed)
    for index, item in enumerate(node.stack):
        names[item.label] = -1 - index
    channels = channel_numbers(node, names, number)
    channels.sort()
    stack = [
        item.number if item.number >= 0 else number((item.call, item.relevant))
        for item in node.stack
    ]
    get = number.numbers.get
    effects = []
    for effect in node.effects:
        found = get(effect)
        effects.append(number(effect) if found is None else found)
    effects.sort()
    # The lengths of the first three parts make the list say where each ends.
    return digest([len(placed), *placed, len(channels), *channels, len(stack), *stack, *effects])
