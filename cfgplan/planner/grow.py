"""Growing nodes (thesis 4.5): one step of the planner (the children of a node),
sub-derivations done again in one step, and what every search strategy does to
a node it takes.

A sub-derivation done again in one step (shared sub-derivations).

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
least that long, are remembered (:func:`cfgplan.planner.graph.repeatable`):
elsewhere a node's memory stays None and costs nothing.

The step of the planner (thesis 4.5): the children of a partial configuration.

:func:`successors` takes the item on top of the stack and yields what 4.5 does
with it, in the thesis's order:

- a method instance (step 2b, 3): one child per version (domain order) and per
  binding of its preconditions (state order): the backtrack points;
- a functionality instance (step 2a): reused if it already exists in C, else
  added, once per binding of its own preconditions (several bindings branch
  like a method's: they may give different outputs or postconditions).

Each branch that cannot go on is yielded as a :class:`DeadEnd` with its
reason. The best-first search, the greedy dive and the naive baseline
(``benchmarks/naive.py``) all grow nodes with this one function.

Growing nodes: what every search strategy does to a node it takes.

A :class:`Grower` expands the method on top of a node
(:func:`cfgplan.planner.grow.successors`), *settles* the children
(places the functionalities on top of their stacks, so every node it hands
back has a method on top or is complete), has them priced by the search's
:class:`~cfgplan.planner.pricer.Pricer`, and finishes complete nodes (4.5
step 4). It keeps what the strategies share: the statistics, the dead ends
met (:class:`Report`), the configurations already listed (distinct mode) and
the result models. It owns no bound: which bounds price a node, and when the
stronger one is given up, is the pricer's business.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import NamedTuple

from cfgplan.configuration.model import Assignment, Configuration
from cfgplan.notation import call_text
from cfgplan.planner import clock
from cfgplan.planner.finish import Models, admissible, build, fingerprint
from cfgplan.planner.graph import Graph, graph_of, repeatable
from cfgplan.planner.ground import Expansion, Grounder, why_not
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.partial import (
    Item,
    Memory,
    Opening,
    Partial,
    Port,
    Record,
    Unwired,
    expand_method,
    place_functionality,
    reuse_functionality,
    rewire,
    settle,
)
from cfgplan.planner.pricer import Pricer
from cfgplan.planner.report import Condition, DeadEnd, Report, Stats
from cfgplan.planner.task import FunctionalitySchema, Ground, MethodSchema
from cfgplan.planner.unify import bind_name


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


Child = Partial | DeadEnd


def successors(
    grounder: Grounder, node: Partial, remember: Replays | None = None
) -> Iterator[Child]:
    """The children of ``node`` (whose stack is not empty), in 4.5's order;
    ``remember``: the search's replay rules, which give each child its
    memory (None: none is kept)."""
    item = node.stack[0]
    versions = grounder.task.versions(item.call)
    if versions:
        yield from _expand(grounder, node, item, versions, remember)
    else:
        yield from _place(grounder, node, item, remember)


def _expand(
    grounder: Grounder,
    node: Partial,
    item: Item,
    versions: tuple[MethodSchema, ...],
    remember: Replays | None,
) -> Iterator[Child]:
    if item.call in item.ancestors:
        yield DeadEnd(
            call_text(item.call),
            "it recurs on its own expansion path",
            condition=Condition.RECURSION,
        )
        return
    choice = 0
    for method in versions:
        options = grounder.expansions(method, item.call)
        if not options:
            where = f"{call_text(item.call)}, version {method.version}"
            yield _no_binding(grounder, method, item.call, where)
            continue
        for expansion in options:
            if isinstance(expansion, DeadEnd):
                yield expansion
            else:
                memory = (
                    None if remember is None else remember.expanding(node, item, expansion, choice)
                )
                yield expand_method(node, item, expansion, method.span, choice, memory)
            choice += 1


def _place(
    grounder: Grounder, node: Partial, item: Item, remember: Replays | None
) -> Iterator[Child]:
    task = grounder.task
    schema = task.functionality(item.call)
    if schema is None:
        yield DeadEnd(
            call_text(item.call),
            "is neither a method nor a functionality",
            condition=Condition.DOMAIN,
        )
        return
    existing = node.labels.get(item.call)
    if existing is not None:
        memory = None if remember is None else remember.placing(node, False)
        yield reuse_functionality(node, item, existing, task, memory)
        return
    options = grounder.instances(schema, item.call)
    if not options:
        yield _no_binding(grounder, schema, item.call, call_text(item.call))
        return
    memory = None if remember is None else remember.placing(node, len(options) > 1)
    for index, instance in enumerate(options):
        choice = index if len(options) > 1 else None
        yield place_functionality(node, item, schema, instance, choice, task, memory)


def _no_binding(
    grounder: Grounder, schema: MethodSchema | FunctionalitySchema, call: Ground, where: str
) -> DeadEnd:
    """Why a schema does not apply to ``call``: its name does not match, or the
    first precondition no binding got past."""
    env = bind_name(schema.params, call[1:])
    if env is None:
        if isinstance(schema, MethodSchema):
            reason = f"its name ({schema.name} {' '.join(schema.params)}) does not match"
            return DeadEnd(where, reason, schema.span, Condition.BINDING)
        reason = f"does not match the functionality ({schema.name} {' '.join(schema.params)})"
        return DeadEnd(where, reason, schema.span, Condition.DOMAIN)
    failure = grounder.failure(
        schema, call, lambda: why_not(grounder.task, schema.tests, env, schema.params)
    )
    return DeadEnd(
        where,
        failure.describe(),
        failure.span or schema.span,
        Condition.PRECONDITION,
        failure.condition,
        failure.bindings,
    )


class Completion(NamedTuple):
    """A complete node that passed step 4 (:meth:`Grower.admit`): its
    cost, its media assignment, and its number among the derivations."""

    node: Partial
    total: float
    media: tuple[Assignment, ...]
    derivation: int


ReplayKey = tuple[tuple[Ground, ...], int, int]
"""A search's roots, :attr:`SearchOptions.replay_least` and
:attr:`SearchOptions.replay_worth`: what the replays' rules are made for."""


@dataclass(eq=False, repr=False)
class Grower:
    """Expands, settles and finishes nodes for one search."""

    grounder: Grounder
    distinct: bool = True
    given: frozenset[int] = frozenset()
    """Functionalities (labels) whose inputs may be fed from outside the
    search: the forced steps' ones in an independent part's search."""
    stats: Stats = field(default_factory=Stats)
    report: Report = field(default_factory=Report)
    seen: set[bytes] = field(default_factory=set)  # fingerprints listed (distinct)
    models: Models = field(default_factory=Models)
    options: SearchOptions = field(default_factory=SearchOptions)
    """The strategies' settings (their pricer is given the same, for its rule)."""
    replays: bool = False
    """Replay a closed sub-derivation in one step:
    the best-first search does (:attr:`SearchOptions.replays`); depth-first
    walks do not, as a replay's path lies inside its deviations' span.
    Turned off for the rest of a search whose replays do not pay
    (:attr:`SearchOptions.replay_trial`)."""
    roots: tuple[Ground, ...] = ()
    """The calls on the stack the search started from (what may repeat is below them)."""
    kept: dict[ReplayKey, Replays] = field(default_factory=dict)
    """Where the replays' rules are kept, made once per search root and
    settings: the task's (:attr:`cfgplan.planner.plan.Analysis.replays`), for
    every search of it; by default this grower's own."""
    _replays: Replays | None = field(default=None, init=False)
    _gave_up: int = field(default=0, init=False)
    """Sub-derivations remembered and not replayed (:meth:`_missed`)."""

    def __post_init__(self) -> None:
        self.levels = self.grounder.task.levels

    def children(self, node: Partial, pricer: Pricer) -> Iterator[tuple[float, Partial]]:
        """Expand the method on top of ``node``; yield its settled children
        with their priorities by ``pricer`` (dead ends go to the report).
        Where the search replays (:attr:`replays`) and ``node``'s top item
        closed a sub-derivation before, the children are the replay and the
        node standing for its deviations."""
        self.stats.expansions += 1
        made = self._replayed(node, pricer) if self.replays else None
        if made is not None:
            yield from made
            return
        yield from pricer.expanded(node, self._children(node))

    def _children(self, node: Partial) -> Iterator[Partial]:
        for child in successors(self.grounder, node, self._remember()):
            clock.check()
            if isinstance(child, DeadEnd):
                self.report.note(child)
                continue
            settled = self._settled(child)
            yield from self._kept(node, settled) if node.forbidden else settled

    def _kept(self, node: Partial, children: Iterator[Partial]) -> Iterator[Partial]:
        """``children`` of ``node`` but those a run of choices it must not
        make leads to (:func:`cfgplan.planner.grow.filtered`)."""
        if not node.forbidden:
            yield from children
            return
        for child in children:
            kept = filtered(node, child)
            if kept is not None:
                yield kept

    def _replayed(self, node: Partial, pricer: Pricer) -> list[tuple[float, Partial]] | None:
        """The replay of ``node``'s top item, settled and priced, and the node
        for its deviations priced at their floor; None when there is no
        replay (nothing recorded, or the walk would meet a dead end), or
        when a deviation may cost no more than it: the deviating node would
        be taken at once and walk it all the same (the wall family's equal
        costs)."""
        memory = node.memory
        if memory is None or node.deviates:
            return None
        item = node.stack[0]
        record = memory.records.get(item.call)
        if record is None:
            return None
        remember = self._remember()
        assert remember is not None
        replayed = None
        if item.call not in item.ancestors and len(record.flat) >= self.options.replay_least:
            # (a shorter walk costs less than pricing its deviations)
            memory = remember.replaying(node, record)
            replayed = replay(node, item, record, self.grounder, memory)
        if replayed is None:
            self._missed()
            return None
        again = list(self._kept(node, self._settled(replayed)))
        best = pricer.floor([iter(again)])
        floor = pricer.floor(
            (self._settled(d) for d in deviations(node, item, record, remember)), best
        )
        if floor is not None and best is not None and floor <= best:
            self._missed()
            return None
        made = list(pricer.expanded(node, iter(again)))
        if floor is not None:
            deviating = node.but(
                forbidden=(*node.forbidden, record.flat),
                deviates=True,
                floor=max(node.floor, floor),
            )
            priority = pricer.again(deviating)
            if priority is not None:
                made.append((priority, deviating))
        self.stats.replays += 1
        return made

    def _missed(self) -> None:
        """A sub-derivation remembered was not replayed (too short, a dead end
        on the walk, or a deviation costing no more): after
        :attr:`SearchOptions.replay_trial` of them and no replay, the search
        stops replaying, and remembering."""
        self._gave_up += 1
        if self._gave_up >= self.options.replay_trial and not self.stats.replays:
            self.replays = False
            self._replays = None

    def _remember(self) -> Replays | None:
        """The replay rules of this search (made at its first expansion)."""
        if not self.replays:
            return None
        if self._replays is None:
            graph = graph_of(self.grounder, self.options.media)
            memo = self.kept
            key = (self.roots, self.options.replay_least, self.options.replay_worth)
            found = memo.get(key)
            if found is None:
                remembered = repeatable(graph, *key)
                found = memo[key] = Replays(graph, remembered)
            if not found.repeatable:
                self.replays = False  # nothing worth remembering here
                return None
            self._replays = found
        return self._replays

    def settle(self, node: Partial, pricer: Pricer) -> Iterator[tuple[float, Partial]]:
        """``node`` settled (:meth:`_settled`), each node priced by ``pricer``."""
        if self.replays and not self.roots:
            self.roots = tuple(item.call for item in node.stack)
        for settled in self._settled(node):
            priority = pricer.price(settled)
            if priority is not None:
                yield priority, settled

    def _settled(self, node: Partial) -> Iterator[Partial]:
        """Place the functionalities on top of the stack (one child per binding
        when one has several); yield each node that has a method on top, or
        is complete."""
        task = self.grounder.task
        remember = self._replays
        todo = [node]
        while todo:
            current = todo.pop()
            stack = current.stack
            if not stack or task.is_method(stack[0].call):
                yield current
                continue
            placed: list[Partial] = []
            for child in successors(self.grounder, current, remember):
                if isinstance(child, DeadEnd):
                    self.report.note(child)
                else:
                    placed.append(child)
            todo.extend(reversed(placed))

    def admit(self, node: Partial, total: float) -> Completion | None:
        """Step 4 for a complete node, in the order configurations are listed:
        what its configuration is built from (:meth:`build`), numbered among
        the derivations (a repeat counts, an inadmissible one does not), or
        None (a repeat in distinct mode, or inadmissible). An independent
        part's search uses no more (:mod:`cfgplan.planner.combine`: it takes
        the part's choices from the node and derives the combinations)."""
        ident = fingerprint(node, self.grounder.numbering) if self.distinct else None
        if ident is not None and ident in self.seen:
            self.stats.derivations += 1
            self.stats.duplicates += 1
            return None
        media = self.admissible(node)
        if media is None:
            return None
        self.stats.derivations += 1
        if ident is not None:
            self.seen.add(ident)
        return Completion(node, total, media, self.stats.derivations)

    def build(self, admitted: Completion) -> Configuration:
        """The configuration of a node :meth:`admit` admitted."""
        node, total, media, derivation = admitted
        return build(node, total, self.grounder.task, self.models, media, derivation)

    def finish(self, node: Partial, total: float, derivation: int = 0) -> Configuration | None:
        """The admissible configuration of a complete node, or None (rejection reported)."""
        media = self.admissible(node)
        if media is None:
            return None
        return self.build(Completion(node, total, media, derivation))

    def admissible(self, node: Partial) -> tuple[Assignment, ...] | None:
        """Step 4's checks: the media assignment of a complete node, or None
        (rejection reported)."""
        result = admissible(node, self.grounder.task, self.given)
        if isinstance(result, DeadEnd):
            self.stats.rejected += 1
            self.report.reject(result)
            return None
        return result
