"""A sub-derivation done again in one step (issue 35: shared sub-derivations).

4.5 expands every occurrence of a method instance on its own: where one ground
instance occurs many times in a derivation (a level of the ``dag`` family
is used by the next two, so level k occurs a Fibonacci number of times), the
cheapest derivation is often the one that expands each later occurrence
exactly as the first: everything it creates is then reused (4.5 step 2a),
its channels merge with the first's, and it adds only the channels at its
own boundary. Walked step by step, that *replay* takes as many nodes as the
occurrence's sub-derivation has method expansions, and each leaves its other
choices in the queue.

Here a node remembers each sub-derivation it *closed* (a method instance
whose body has been expanded down to its functionalities, its choices a
contiguous run of the node's path, as the stack is last in, first out): a
:class:`Record`, which shares the records of the sub-derivations it
contains. When the same ground instance is on top again, :func:`replay`
makes in one step the node the walk with the same choices would reach: the
same stack, C, channels (each channel at the instance re-wired through the
record's ``:out``/``:in`` down to the functionalities already in C, then
settled: checked, merged or added), postconditions, labels (the counter
moves by every body item of the walk) and path (the walk's choices). Where
the walk would meet a dead end (a port missing for this occurrence's data, a
local channel on the wrong robot, a recursion guard), or where settling in
one step could merge channels in another order than the walk, there is no
replay and the occurrence is expanded as usual.

Every other derivation of the occurrence still exists: the *deviations*, a
node like the one the occurrence was on top of, that must not follow the
record's choices to their end (:attr:`cfgplan.planner.partial.Partial.forbidden`);
it is expanded as usual, step by step, and a child that has followed them
to the end is dropped (it is the replay). Its *floor* — a lower bound on
every derivation below it — is the least price of the nodes that make one
other choice somewhere in the record (:func:`deviations`): each of its
derivations makes one, first at some expansion of the record, and costs at
least what the node making just that choice, without the rest of the walk,
is priced at (fewer items, fewer channels: a relaxation). Where a deviation
costs more than the replay, the deviating node is never taken.

The best-first search uses it (:attr:`cfgplan.planner.grow.Grower.replays`);
``--all``'s depth-first walks do not (they meet derivations in path order,
and a replay's path lies inside its deviations' span).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field

from cfgplan.planner.graph import Graph, Option
from cfgplan.planner.ground import Grounder
from cfgplan.planner.partial import Channel, Item, Partial, expand_method, settle
from cfgplan.planner.report import DeadEnd
from cfgplan.planner.task import Ground


@dataclass(eq=False, slots=True)
class Record:
    """A closed sub-derivation: the method instance ``call`` expanded by
    ``option``, and the records of its body's method items, in body order
    (a record is shared by every sub-derivation that replayed it)."""

    call: Ground
    option: Option
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
            flat = [self.option.choice]
            for child in self.children:
                flat.extend(child.flat)
            self._flat = tuple(flat)
        return self._flat

    @property
    def size(self) -> int:
        """The labels the walk takes: every body item of every expansion."""
        if self._size < 0:
            self._size = self.option.expansion.size + sum(c.size for c in self.children)
        return self._size

    @property
    def effects(self) -> tuple[tuple[bool, Ground], ...]:
        """The postconditions the walk's expansions add, in their order."""
        if self._effects is None:
            effects = list(self.option.expansion.effects)
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

    def source(
        self, data: Ground, kind: str, bandwidth: float | None
    ) -> tuple[Ground, float | None] | None:
        """Where a channel of ``data`` sent from this instance starts once the
        walk re-wired it through each ``:out`` (4.5 step 3d): the functionality
        call, and its bandwidth (a global one without takes the first
        ``:out``'s that has one); None when a ``:out`` is missing."""
        record = self
        while True:
            expansion = record.option.expansion
            port = expansion.outputs.get(data)
            if port is None:
                return None
            if bandwidth is None and kind == "global" and port[1] is not None:
                bandwidth = port[1]
            child = record.at.get(port[0])
            if child is None:
                return expansion.body[port[0]], bandwidth
            record = child

    def targets(self, data: Ground) -> tuple[Ground, ...] | None:
        """Where a channel of ``data`` received by this instance ends once
        re-wired through each ``:in`` (an ``:in`` may feed several): the
        functionality calls in channel order; None when an ``:in`` is missing."""
        expansion = self.option.expansion
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


@dataclass(frozen=True, slots=True)
class Opening:
    """A method instance expanded whose sub-derivation is not closed yet."""

    call: Ground
    option: Option
    depth: int
    """The stack's length once it is closed (its item's stack, less it)."""
    children: tuple[Record, ...] = ()
    pure: bool = True
    """No functionality binding was chosen in it (those are not replayed:
    the instance reused would take no choice there)."""


@dataclass(frozen=True, slots=True)
class Memory:
    """What a node remembers for replays: the expansions still open, innermost
    last, and a record for each repeatable instance it closed (the first)."""

    opened: tuple[Opening, ...] = ()
    records: Mapping[Ground, Record] = field(default_factory=dict)


@dataclass
class Replays:
    """The replay rules of one search: which instances may repeat, and how a
    node's memory follows its steps."""

    graph: Graph
    repeatable: frozenset[Ground]
    _options: dict[tuple[Ground, int], Option] = field(default_factory=dict)
    _positions: dict[int, tuple[int, ...]] = field(default_factory=dict)

    def option(self, call: Ground, choice: int) -> Option:
        """The graph's option of ``call`` numbered ``choice``."""
        found = self._options.get((call, choice))
        if found is None:
            for option in self.graph.instance(call).options:
                self._options[(call, option.choice)] = option
            found = self._options[(call, choice)]
        return found

    def expanded(self, node: Partial, child: Partial) -> Partial:
        """``child``, made by expanding ``node``'s top item, remembering it."""
        memory = node.memory
        call = node.stack[0].call
        if call not in self.repeatable and (memory is None or not memory.opened):
            return child
        if memory is None:
            memory = Memory()
        option = self.option(call, child.path[-1])
        opening = Opening(call, option, len(node.stack) - 1)
        return _remember(
            child, self._close(Memory((*memory.opened, opening), memory.records), child)
        )

    def placed(self, node: Partial, child: Partial) -> Partial:
        """``child``, made by placing or reusing ``node``'s top functionality."""
        memory = node.memory
        if memory is None or not memory.opened:
            return child
        if len(child.path) > len(node.path):  # a binding chosen: not replayed
            memory = Memory(tuple(_impure(o) for o in memory.opened), memory.records)
        return _remember(child, self._close(memory, child))

    def replayed(self, child: Partial, record: Record) -> Partial:
        """``child``, a replay of ``record``, remembering it as a closed child."""
        memory = child.memory
        if memory is None or not memory.opened:
            return child
        last = memory.opened[-1]
        opened = (*memory.opened[:-1], _with_child(last, record))
        return _remember(child, self._close(Memory(opened, memory.records), child))

    def _close(self, memory: Memory, node: Partial) -> Memory:
        """Close the open expansions whose sub-derivation ``node`` completed."""
        opened, records = memory.opened, memory.records
        depth = len(node.stack)
        copied = False
        while opened and depth <= opened[-1].depth:
            done = opened[-1]
            opened = opened[:-1]
            record = None
            methods = self._methods(done.option)
            if done.pure and len(methods) == len(done.children):
                record = Record(
                    done.call,
                    done.option,
                    done.children,
                    dict(zip(methods, done.children, strict=True)),
                )
                if done.call in self.repeatable and done.call not in records:
                    if not copied:
                        records, copied = dict(records), True
                    records[done.call] = record  # type: ignore[index]
            if opened:
                parent = opened[-1]
                parent = _with_child(parent, record) if record is not None else _impure(parent)
                opened = (*opened[:-1], parent)
        return Memory(opened, records)

    def _methods(self, option: Option) -> tuple[int, ...]:
        """The body offsets of an option's method items."""
        found = self._positions.get(id(option))
        if found is None:
            is_method = self.graph.grounder.task.is_method
            body = option.expansion.body
            found = tuple(i for i, call in enumerate(body) if is_method(call))
            self._positions[id(option)] = found
        return found


def _with_child(opening: Opening, record: Record) -> Opening:
    return Opening(
        opening.call, opening.option, opening.depth, (*opening.children, record), opening.pure
    )


def _impure(opening: Opening) -> Opening:
    return Opening(opening.call, opening.option, opening.depth, opening.children, False)


def _remember(node: Partial, memory: Memory) -> Partial:
    return node.remembering(memory)


def replay(node: Partial, item: Item, record: Record, grounder: Grounder) -> Partial | None:
    """``node`` with ``item`` (its top) expanded as ``record`` was, in one
    step: the node the walk with the record's choices reaches. None where the
    walk meets a dead end, or merges channels in an order one step would not
    (two channels at the instance that become one)."""
    if record.calls & item.ancestors:
        return None  # the recursion guard prunes the walk somewhere
    labels = node.labels
    label = item.label
    out: list[Channel] = []
    touching: list[int] = []
    idents: set[tuple[str, int, int, Ground]] = set()
    for ch in node.channels:
        at_source, at_target = ch.source == label, ch.target == label
        if not (at_source or at_target):
            out.append(ch)
            continue
        source, bandwidth, number = ch.source, ch.bandwidth, ch.number
        if at_source:
            found = record.source(ch.data, ch.kind, ch.bandwidth)
            if found is None:
                return None
            call, bandwidth = found
            source = labels[call]
            if bandwidth != ch.bandwidth:
                number = grounder.numbering((ch.kind, ch.robots, ch.data, bandwidth))
        targets: Iterable[int] = (ch.target,)
        if at_target:
            ends = record.targets(ch.data)
            if ends is None:
                return None
            targets = [labels[call] for call in ends]
        for target in targets:
            ident = (ch.kind, source, target, ch.data)
            if ident in idents:
                return None  # two become one: which is kept depends on the walk's order
            idents.add(ident)
            touching.append(len(out))
            out.append(Channel(ch.kind, ch.robots, source, target, ch.data, bandwidth, number))
    settled = settle(tuple(out), node.located, touching, node.resolved, grounder.task)
    if isinstance(settled, DeadEnd):
        return None
    channels, added, resolved = settled
    effects = record.effects
    return node.but(
        stack=node.stack[1:],
        channels=channels,
        effects=(*node.effects, *effects) if effects else node.effects,
        next_label=node.next_label + record.size,
        path=(*node.path, *record.flat),
        cost=node.cost + added,
        resolved=resolved,
        forbidden=(),
        deviates=False,
    )


def deviations(node: Partial, item: Item, record: Record, replays: Replays) -> Iterator[Partial]:
    """For each other choice the walk of ``record`` could make at one of its
    expansions (each record and option once), ``node`` with that choice made
    and the rest of the walk left out: its derivations cost at most what the
    deviating ones do (they make the same choice, with more besides)."""
    rest = node.but(
        channels=tuple(ch for ch in node.channels if item.label not in (ch.source, ch.target)),
        path=(),  # priced, never listed: its place in the order does not matter
        memory=None,
        forbidden=(),
        deviates=False,
    )
    inner = item.ancestors | {item.call}
    seen: set[int] = set()
    todo = [record]
    while todo:
        current = todo.pop()
        if id(current) in seen:
            continue
        seen.add(id(current))
        todo.extend(current.children)
        ancestors = item.ancestors if current is record else inner
        stand_in = Item(item.label, current.call, ancestors, item.relevant)
        for option in replays.graph.instance(current.call).options:
            if option.choice == current.option.choice:
                continue
            made = expand_method(rest, stand_in, option.expansion, None, option.choice)
            if isinstance(made, Partial):
                yield made


def filtered(node: Partial, child: Partial) -> Partial | None:
    """``child`` under ``node``'s :attr:`~cfgplan.planner.partial.Partial.forbidden`
    runs of choices: None when it followed one to its end (that derivation is
    a replay's); else with what is left of those it is still following."""
    forbidden = node.forbidden
    if not forbidden:
        return child
    made = child.path[len(node.path) :]
    kept = []
    for run in forbidden:
        common = min(len(run), len(made))
        if run[:common] != made[:common]:
            continue  # it chose otherwise: free of this one
        if len(run) <= len(made):
            return None
        kept.append(run[len(made) :])
    return child.but(forbidden=tuple(kept)) if kept or child.forbidden else child


def repeatable(graph: Graph, roots: Iterable[Ground]) -> frozenset[Ground]:
    """The method instances below ``roots`` that may occur twice in one
    derivation (the recursion guard ignored): below two method items of one
    option's body, or below two roots. Only they are remembered."""
    task = graph.grounder.task
    reach: dict[Ground, frozenset[Ground]] = {}

    def below(call: Ground) -> frozenset[Ground]:
        found = reach.get(call)
        if found is None:
            seen = {call}
            todo = [call]
            while todo:
                current = todo.pop()
                for option in graph.instance(current).options:
                    for child in option.children:
                        if child not in seen and task.is_method(child):
                            seen.add(child)
                            todo.append(child)
            found = reach[call] = frozenset(seen)
        return found

    methods = [call for call in roots if task.is_method(call)]
    found: set[Ground] = set()
    _twice(methods, below, found)
    for call in {c for root in methods for c in below(root)}:
        for option in graph.instance(call).options:
            slots = [child for child in option.children if task.is_method(child)]
            if len(slots) > 1:
                _twice(slots, below, found)
    return frozenset(found)


def _twice(slots: list[Ground], below: object, found: set[Ground]) -> None:
    """Add to ``found`` what is below two of ``slots``."""
    assert callable(below)
    once: set[Ground] = set()
    for slot in slots:
        for call in below(slot):
            if call in once:
                found.add(call)
            else:
                once.add(call)
