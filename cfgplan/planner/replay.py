"""A sub-derivation done again in one step (shared sub-derivations).

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
and a replay's path lies inside its deviations' span). Where a deviation may
cost no more than the replay, the occurrence is expanded as usual (the
deviating node would be taken at once and walk it all the same); so is a walk
shorter than :attr:`~cfgplan.planner.options.SearchOptions.replay_least`,
and a search that met :attr:`~cfgplan.planner.options.SearchOptions.replay_trial`
such misses before any replay stops remembering (:class:`cfgplan.planner.grow.Grower`).
Only instances that may occur twice in one derivation, with a derivation at
least that long, are remembered (:func:`cfgplan.planner.repeats.repeatable`):
elsewhere a node's memory stays None and costs nothing.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

from cfgplan.planner.graph import Graph
from cfgplan.planner.ground import Expansion, Grounder
from cfgplan.planner.memory import Memory, Opening, Record
from cfgplan.planner.partial import Item, Partial, expand_method
from cfgplan.planner.report import DeadEnd
from cfgplan.planner.task import Ground
from cfgplan.planner.wiring import Port, Unwired, rewire, settle


@dataclass(eq=False, repr=False)
class Replays:
    """The replay rules of one search: which instances may repeat, and how a
    node's memory follows its steps."""

    graph: Graph
    repeatable: frozenset[Ground]
    _positions: dict[int, tuple[int, ...]] = field(default_factory=dict)

    def expanding(
        self, node: Partial, item: Item, expansion: Expansion, choice: int
    ) -> Memory | None:
        """The memory of the child made by expanding ``item`` (``node``'s top)
        by ``expansion``: the expansion opened, if it is remembered."""
        memory = node.memory
        call = item.call
        if call not in self.repeatable and (memory is None or not memory.opened):
            return memory
        if memory is None:
            memory = Memory((), {})
        depth = len(node.stack) - 1
        made = Memory((*memory.opened, Opening(call, choice, expansion, depth)), memory.records)
        return self._close(made, depth) if not expansion.body else made

    def placing(self, node: Partial, chosen: bool) -> Memory | None:
        """The memory of the child made by placing or reusing ``node``'s top
        functionality (``chosen``: one of several bindings)."""
        memory = node.memory
        if memory is None or not memory.opened:
            return memory
        depth = len(node.stack) - 1
        if chosen:  # not replayed: the instance reused would take no choice there
            memory = Memory(tuple(_impure(o) for o in memory.opened), memory.records)
        elif depth > memory.opened[-1].depth:
            return memory  # nothing closed
        return self._close(memory, depth)

    def replaying(self, node: Partial, record: Record) -> Memory | None:
        """The memory of ``node``'s top item's replay of ``record``: a closed child."""
        memory = node.memory
        if memory is None or not memory.opened:
            return memory
        opened = (*memory.opened[:-1], _with_child(memory.opened[-1], record))
        return self._close(Memory(opened, memory.records), len(node.stack) - 1)

    def _close(self, memory: Memory, depth: int) -> Memory:
        """Close the open expansions a node whose stack is ``depth`` long completed."""
        opened, records = memory.opened, memory.records
        if not opened or depth > opened[-1].depth:
            return memory
        copied = False
        while opened and depth <= opened[-1].depth:
            done = opened[-1]
            opened = opened[:-1]
            record = None
            methods = self._methods(done.expansion)
            if done.pure and len(methods) == len(done.children):
                at = dict(zip(methods, done.children, strict=True))
                record = Record(done.call, done.choice, done.expansion, done.children, at)
                if done.call in self.repeatable and done.call not in records:
                    if not copied:
                        records, copied = dict(records), True
                    records[done.call] = record  # type: ignore[index]
            if opened:
                parent = opened[-1]
                parent = _with_child(parent, record) if record is not None else _impure(parent)
                opened = (*opened[:-1], parent)
        return Memory(opened, records)

    def _methods(self, expansion: Expansion) -> tuple[int, ...]:
        """The body offsets of an expansion's method items."""
        found = self._positions.get(id(expansion))
        if found is None:
            is_method = self.graph.grounder.task.is_method
            found = tuple(i for i, call in enumerate(expansion.body) if is_method(call))
            self._positions[id(expansion)] = found
        return found


def _with_child(opening: Opening, record: Record) -> Opening:
    return Opening(
        opening.call,
        opening.choice,
        opening.expansion,
        opening.depth,
        (*opening.children, record),
        opening.pure,
    )


def _impure(opening: Opening) -> Opening:
    return Opening(
        opening.call, opening.choice, opening.expansion, opening.depth, opening.children, False
    )


def replay(
    node: Partial, item: Item, record: Record, grounder: Grounder, memory: Memory | None = None
) -> Partial | None:
    """``node`` with ``item`` (its top) expanded as ``record`` was, in one
    step: the node the walk with the record's choices reaches. None where the
    walk meets a dead end, or merges channels in an order one step would not
    (two channels at the instance that become one)."""
    if record.calls & item.ancestors:
        return None  # the recursion guard prunes the walk somewhere
    labels = node.labels

    def out(data: Ground) -> Port | None:
        found = record.source(data)
        return None if found is None else (labels[found[0]], found[1])

    def into(data: Ground) -> list[int] | None:
        ends = record.targets(data)
        return None if ends is None else [labels[call] for call in ends]

    done = rewire(node.channels, item.label, out, into, grounder.numbering)
    if isinstance(done, Unwired):
        return None
    rewired, touching = done
    idents = {(c.kind, c.source, c.target, c.data) for c in map(rewired.__getitem__, touching)}
    if len(idents) < len(touching):
        return None  # two become one: which is kept depends on the walk's order
    settled = settle(tuple(rewired), node.located, touching, node.resolved, grounder.task)
    if isinstance(settled, DeadEnd):
        return None
    channels, added, resolved = settled
    effects = record.effects
    return node.but(
        stack=node.stack[1:],
        channels=channels,
        effects=node.effects + effects if effects else node.effects,
        next_label=node.next_label + record.size,
        path=node.path + record.flat,  # (concatenated: both may be millions long)
        cost=node.cost + added,
        resolved=resolved,
        memory=memory,
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
            if option.choice == current.choice:
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
