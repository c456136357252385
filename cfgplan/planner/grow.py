"""Growing nodes: what every search strategy does to a node it takes.

A :class:`Grower` expands the method on top of a node
(:func:`cfgplan.planner.successors.successors`), *settles* the children
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
from cfgplan.planner import clock
from cfgplan.planner.finish import Models, admissible, build, fingerprint
from cfgplan.planner.graph import graph_of
from cfgplan.planner.ground import Grounder
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.partial import Partial
from cfgplan.planner.pricer import Pricer
from cfgplan.planner.repeats import repeatable
from cfgplan.planner.replay import Replays, deviations, filtered, replay
from cfgplan.planner.report import DeadEnd, Report, Stats
from cfgplan.planner.successors import successors
from cfgplan.planner.task import Ground


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
    """Replay a closed sub-derivation in one step (:mod:`cfgplan.planner.replay`):
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
        node standing for its deviations (:mod:`cfgplan.planner.replay`)."""
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
        make leads to (:func:`cfgplan.planner.replay.filtered`)."""
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
