"""Sequences of configurations: plans whose steps are configurations.

The thesis plans one configuration for one step and names sequences as a
limitation (7.2): "a configuration for removing that box would have to
precede the configuration for getting the first box through the door". Its
own experiment is one (6.2.2: Pippi crosses, then Emil, the operator editing
the state in between); Lundh et al. (ECAI 2008) later planned them.

Goals G1..Gn are reached in order. Step i is planned in the state step i-1's
configuration leaves: its postconditions P applied (4.5) — every ``(not
ATOM)`` deletes, then every atom adds (a configuration that both deletes and
adds an atom keeps it). A functionality's postconditions are instantiated
under the binding it was placed with, so P names what its preconditions
bound. The cost of a sequence is the sum of its steps' costs plus, with
``switch`` weight W (default 0), W times the functionality instances and
channels started or stopped between consecutive configurations.

Different configurations of step i can leave different states, so the
cheapest sequence is not the cheapest step after cheapest step: this is a
best-first search over sequences, each step's configurations coming from the
per-step planner in cost order, lazily. Its queue holds *offers*: "the j-th
configuration of step i after this prefix", priced at the prefix's cost plus
that configuration's (a lower bound, as a switch costs nothing or more); an
offer taken becomes the sequence it offers, priced in full, and makes the
next offer. So sequences come out cheapest first; at equal cost, the one
whose steps rank earlier, step 1 first. The per-step planner for a (step,
state) met again is reused.
"""

from __future__ import annotations

import heapq
import math
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import cast

from cfgplan.configuration.model import Configuration
from cfgplan.ir.model import is_variable
from cfgplan.notation import atom_text
from cfgplan.planner import clock
from cfgplan.planner.combine import Combined
from cfgplan.planner.costs import Levels
from cfgplan.planner.graph import graph_of
from cfgplan.planner.ground import Effects
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.plan import Run, analysis, growing, in_parts
from cfgplan.planner.report import Report, Status
from cfgplan.planner.search import BestFirst, Prefix, merge
from cfgplan.planner.task import EffectSpec, Ground, Pattern, Task, Test, derive

Facts = tuple[Ground, ...]


@dataclass(frozen=True)
class Step:
    """One step of a sequence: its goal, its configuration, and the changes its
    postconditions make to the state (which the next step is planned in)."""

    goal: Ground
    configuration: Configuration
    changes: tuple[str, ...]  # "(not (in Pippi Room1))", "(in Pippi Room2)"


@dataclass(frozen=True)
class PlannedSequence:
    """A sequence of configurations, one a goal, and what it costs in all."""

    steps: tuple[Step, ...]
    total: float


def apply(facts: Facts, effects: Sequence[tuple[bool, Ground]]) -> tuple[Facts, tuple[str, ...]]:
    """The state after P, and the changes it made (as the thesis prints them):
    deletions first, then additions; facts keep their order, new ones last."""
    deleted = {atom for positive, atom in effects if not positive}
    kept = [f for f in facts if f not in deleted]
    present = set(kept)
    changes = [f"(not {atom_text(f)})" for f in facts if f in deleted]
    for positive, atom in effects:
        if positive and atom not in present:
            kept.append(atom)
            present.add(atom)
            if atom not in deleted:
                changes.append(atom_text(atom))
    return tuple(kept), tuple(changes)


ANY = "?"
"""In a :class:`Touched` atom: any value (a variable the goal does not bind)."""


@dataclass(frozen=True)
class Touched:
    """The atoms a goal's expansion can read and write, as patterns whose
    :data:`ANY` stands for any value: read by the preconditions (atoms and
    negations) of every method version and functionality the expansion can
    reach through method bodies (4.5), written by their postconditions; each
    instantiated with what the goal binds (its arguments, passed down the
    bodies), every other variable :data:`ANY`."""

    reads: frozenset[Pattern]
    writes: frozenset[Pattern]


AGENTS: frozenset[Pattern] = frozenset({("robot", ANY), ("device", ANY)})
"""Read by every plan whatever its tests: who may run a part, and how it is weighed."""


def touched(task: Task, goal: Ground) -> Touched:
    """What ``goal``'s expansion can read and write (:class:`Touched`); each
    call (its name and what is known of its arguments) visited once,
    recursion included: the calls are finitely many, their arguments being
    the goal's and the domain's symbols or :data:`ANY`."""
    reads: set[Pattern] = set()
    writes: set[Pattern] = set()

    def bound(params: Pattern, call: Pattern) -> dict[str, str] | None:
        known: dict[str, str] = {}
        for param, arg in zip(params, call[1:], strict=True):
            if is_variable(param):
                if arg != ANY:
                    known[param] = arg
            elif arg not in (ANY, param):
                return None  # a symbol that cannot match this version's
        return known

    def put(pattern: Pattern, known: dict[str, str]) -> Pattern:
        return (pattern[0], *(known.get(t, ANY) if is_variable(t) else t for t in pattern[1:]))

    def note(tests: Sequence[Test], effects: Sequence[EffectSpec], known: dict[str, str]) -> None:
        reads.update(put(t.pattern, known) for t in tests if t.pattern)
        writes.update(put(e.pattern, known) for e in effects)

    todo: list[Pattern] = [goal]
    seen = set(todo)
    while todo:
        call = todo.pop()
        schema = task.functionality(call)
        if schema is not None and (known := bound(schema.params, call)) is not None:
            note(schema.tests, schema.effects, known)
        for version in task.versions(call):
            known = bound(version.params, call)
            if known is None:
                continue
            note(version.tests, version.effects, known)
            for _, body in version.body:
                called = put(body, known)
                if called not in seen:
                    seen.add(called)
                    todo.append(called)
    return Touched(frozenset(reads), frozenset(writes))


def overlap(a: Pattern, b: Pattern) -> bool:
    """Some atom is an instance of both (:data:`ANY` matches any value)."""
    return len(a) == len(b) and all(x == y or ANY in (x, y) for x, y in zip(a, b, strict=True))


def unseen(task: Task, goals: Sequence[Ground]) -> tuple[bool, ...]:
    """For each step, whether no configuration of it changes a fact that a
    later step reads (:func:`touched`): then every state it can leave gives
    the later steps the same configurations, in the same order (the facts
    they read keep their order, :func:`apply`), at the same costs."""
    found = [touched(task, goal) for goal in goals]
    later: set[Pattern] = set(AGENTS)
    inert = []
    for step in reversed(found):
        inert.append(not any(overlap(w, r) for w in step.writes for r in later))
        later |= step.reads
    return tuple(reversed(inert))


def fixed_effects(task: Task, goal: Ground, options: SearchOptions) -> Effects | None:
    """The postconditions every configuration of ``goal`` in ``task``'s state
    has, when that is one and the same list (a robot that moves, whichever
    way it is helped); else None. So it is when the expansion can reach (over
    the graph of ground instances) at most one functionality instance with a
    postcondition, it is in every feasible expansion of the goal (its
    summary's, :mod:`cfgplan.planner.bound`), it has one binding of its
    preconditions, and no method version it can reach has a postcondition."""
    analysed = analysis(task, options.media)
    grounder, bound = analysed.grounder, analysed.bound
    summary = bound.summaries.summary(goal)
    if not summary.feasible:
        return None
    graph = graph_of(grounder, options.media)
    found: Ground | None = None
    todo: list[Ground] = []
    seen: set[Ground] = set()

    def meet(call: Ground) -> bool:
        """Note ``call``; False when it makes the postconditions differ."""
        nonlocal found
        seen.add(call)
        schema = task.functionality(call)
        if schema is None:
            todo.append(call)
        elif schema.effects:
            if found is not None or call not in summary.functionalities:
                return False
            found = call
        return True

    if not meet(goal):
        return None
    while todo:
        clock.check()
        for option in graph.instance(todo.pop()).options:
            if option.expansion.effects:
                return None
            for child in option.children:
                if child not in seen and not meet(child):
                    return None
    if found is None:
        return ()
    schema = task.functionality(found)
    assert schema is not None
    instances = grounder.instances(schema, found)
    return instances[0].effects if len(instances) == 1 else None


def switching(before: Configuration, after: Configuration) -> int:
    """Functionality instances and channels started or stopped between two
    configurations (labels ignored)."""
    f1, c1, _ = before.identity()
    f2, c2, _ = after.identity()
    return len(f1 ^ f2) + len({c[:4] for c in c1} ^ {c[:4] for c in c2})


@dataclass
class Ranked:
    """The configurations of one goal in one state, in cost order, planned as
    far as they are asked for (best-first search continued, never restarted),
    assembled as a run's ``-k`` is (:func:`cfgplan.planner.plan.in_parts`:
    children priced from splits, sub-derivations replayed, independent parts
    searched apart)."""

    task: Task
    goal: Ground
    options: SearchOptions = field(default_factory=SearchOptions)
    found: list[Configuration] = field(default_factory=list)
    search: BestFirst | Combined = field(init=False)
    _more: Iterator[Configuration] = field(init=False)

    def __post_init__(self) -> None:
        plain = BestFirst(*growing(self.task, self.options, replays=True), self.goal)
        self.search = in_parts(plain, self.task, self.options)
        self._more = iter(self.search)

    def get(self, j: int) -> Configuration | None:
        while len(self.found) <= j:
            config = next(self._more, None)
            if self.search.status.stopped:
                raise clock.OutOfTime  # a step's search was stopped: so is the sequence
            if config is None:
                return None
            self.found.append(config)
        return self.found[j]


@dataclass(order=True)
class _Entry:
    """A sequence (complete or not) or an offer, at its place: price, then
    the ranks of its steps' configurations (:mod:`cfgplan.planner.search`)."""

    priority: float
    order: tuple[int, ...]  # the rank of each step's configuration: ties by earlier steps
    offer: bool  # an offer (False sorts first: a sequence at the same price and order)
    prefix: tuple[int, ...] = field(compare=False)
    cost: float = field(compare=False)  # of the prefix (for an offer) or the sequence


@dataclass
class SequenceSearch:
    """An iterator over sequences, cheapest first; see the module docstring."""

    goals: tuple[Ground, ...]
    task: Task
    """The task of the first step's state; later steps' are made from it."""
    switch: float = 0.0
    time_limit: float | None = None
    limit: int | None = None
    """List at most this many sequences (None: every one)."""
    ahead: bool = False
    """Once :attr:`limit` are listed, look for one more with bounded work
    (:mod:`cfgplan.planner.search`), to say whether more exist (:attr:`status`)."""
    options: SearchOptions = field(default_factory=SearchOptions)
    """The settings of every step's search, and the look-ahead's least work."""
    status: Status = field(init=False, default=Status.COMPLETE)
    """How the search ended: stopped, or as the prefix it listed
    (:attr:`cfgplan.planner.search.Prefix.status`)."""
    _ranked: dict[tuple[int, Facts], Ranked] = field(default_factory=dict)
    _states: dict[tuple[int, ...], tuple[Facts, tuple[str, ...]]] = field(default_factory=dict)
    _remaining: dict[tuple[int, Facts], float] = field(default_factory=dict)

    _one: dict[tuple[int, Facts], bool] = field(default_factory=dict)

    @cached_property
    def _unseen(self) -> tuple[bool, ...]:
        """For each step, whether what it changes is unseen by the later steps
        (:func:`unseen`)."""
        return unseen(self.task, self.goals)

    def _one_state(self, step: int, facts: Facts) -> bool:
        """Whether every configuration of ``step`` in state ``facts`` leaves the
        later steps one state to be planned in: what it changes they do not
        see (:attr:`_unseen`), or it changes the same for all
        (:func:`fixed_effects`)."""
        key = (step, facts)
        found = self._one.get(key)
        if found is None:
            found = self._unseen[step] or (
                fixed_effects(self.ranked(step, facts).task, self.goals[step], self.options)
                is not None
            )
            self._one[key] = found
        return found

    def ranked(self, step: int, facts: Facts) -> Ranked:
        """Step ``step``'s configurations in a state, planned once per state."""
        key = (step, facts)
        found = self._ranked.get(key)
        if found is None:
            task = self.task if facts == self.task.facts else derive(self.task, facts)
            found = self._ranked[key] = Ranked(task, self.goals[step], self.options)
        return found

    def state_after(self, prefix: tuple[int, ...]) -> tuple[Facts, tuple[str, ...]]:
        """The facts after the steps of ``prefix``, and the last step's changes."""
        found = self._states.get(prefix)
        if found is None:
            if not prefix:
                found = (self.task.facts, ())
            else:
                facts, _ = self.state_after(prefix[:-1])
                config = self.configuration(prefix)
                found = apply(facts, config.effects)
            self._states[prefix] = found
        return found

    def configuration(self, prefix: tuple[int, ...]) -> Configuration:
        facts, _ = self.state_after(prefix[:-1])
        config = self.ranked(len(prefix) - 1, facts).get(prefix[-1])
        assert config is not None
        return config

    def __iter__(self) -> Iterator[PlannedSequence]:
        deadline = None if self.time_limit is None else time.perf_counter() + self.time_limit
        prefix: Prefix[PlannedSequence] = Prefix(self.limit, self.ahead, self.options.ahead_least)
        try:
            with clock.limit(deadline):
                yield from prefix.take(self._search())
            self.status = prefix.status
        except clock.OutOfTime:
            self.status = Status.TIME_LIMIT
        except KeyboardInterrupt:
            self.status = Status.INTERRUPTED

    def remaining(self, step: int, facts: Facts) -> float:
        """The least the steps from ``step`` on can cost from a state (switches
        not counted; infinite when they cannot all be reached): the search's
        bound. Worked out over the states the steps can leave, each (step,
        state) once, a step's configurations taken cheapest first only while
        one could still beat the best (every later step costs 0 or more).

        A step whose changes the later steps do not see, or whose
        configurations all change the same (:meth:`_one_state`), leaves
        them the same least whatever its configuration, so its
        cheapest configuration is the only one that can give the least:
        there, one configuration is planned, and a sequence of such steps
        (independent goals, or goals whose postconditions no later step
        reads) costs the planning of each step alone. Otherwise the work is
        bounded by the configurations of step i that cost less than the least
        of the steps from i on (they may leave other states: each is planned,
        and each new state once)."""
        done = self._remaining
        frames: list[list[object]] = [[step, facts, 0, math.inf]]
        while frames:
            clock.check()
            frame = frames[-1]
            i, here, j, best = frame
            assert isinstance(i, int) and isinstance(j, int) and isinstance(best, float)
            here = cast(Facts, here)
            if (i, here) in done:
                frames.pop()
                continue
            last = i == len(self.goals) or (j > 0 and self._one_state(i, here))
            config = None if last else self.ranked(i, here).get(j)
            if config is None or config.cost >= best:
                done[(i, here)] = 0.0 if i == len(self.goals) else best
                frames.pop()
                continue
            after = (i + 1, apply(here, config.effects)[0])
            rest = done.get(after)
            if rest is None:
                frames.append([after[0], after[1], 0, math.inf])
                continue
            frame[2], frame[3] = j + 1, min(best, config.cost + rest)
        return done[(step, facts)]

    def _search(self) -> Iterator[PlannedSequence]:
        """Best-first over sequences (:func:`cfgplan.planner.search.merge`);
        a prefix is priced with :meth:`remaining` (exact without switches),
        an offer at the prefix's cost plus its configuration's alone (less
        or equal to what it turns out)."""
        first = self._offered((), 0, 0.0) if self.remaining(0, self.task.facts) < math.inf else ()
        steps = len(self.goals)
        whole = merge(first, self._offers, lambda e: not e.offer and len(e.prefix) == steps)
        for entry in whole:
            yield self._planned(entry.prefix, entry.cost)

    def _offers(self, entry: _Entry) -> Iterator[_Entry]:
        """What ``entry`` offers: a sequence not yet complete, its next
        step's first configuration; an offer, the sequence it offers, priced
        in full, and the next configuration of its step."""
        if not entry.offer:
            if len(entry.prefix) < len(self.goals):
                yield from self._offered(entry.prefix, 0, entry.cost)
            return
        prefix, j = entry.prefix, entry.order[-1]
        whole = (*prefix, j)
        config = self.configuration(whole)
        cost = entry.cost + config.cost
        if prefix and self.switch:
            cost += self.switch * switching(self.configuration(prefix), config)
        rest = self.remaining(len(whole), self.state_after(whole)[0])
        if rest < math.inf:
            done, levels = len(whole) == len(self.goals), self._levels
            price = levels.cost(cost) if done else levels.bound(cost + rest)
            yield _Entry(price, whole, False, whole, cost)
        yield from self._offered(prefix, j + 1, entry.cost)

    def _offered(self, prefix: tuple[int, ...], j: int, cost: float) -> tuple[_Entry, ...]:
        """The j-th configuration of the step after ``prefix``, offered, if
        there is one, priced at the prefix's cost plus its own, plus the
        least the later steps cost where that is known for every
        configuration of the step from j on: after a step that leaves the
        later steps one state (:meth:`_one_state`), from the state its first
        configuration leaves (any other of the step's gives the same, or the
        same least: one state is planned from).
        (Priced without it, every configuration of the step cheaper than the
        best whole sequence is planned before that sequence is listed.)"""
        facts, _ = self.state_after(prefix)
        step = len(prefix)
        config = self.ranked(step, facts).get(j)
        if config is None:
            return ()
        rest = 0.0
        if self._one_state(step, facts):  # from the state its first configuration leaves
            rest = self.remaining(step + 1, self.state_after((*prefix, 0))[0])
        if rest == math.inf:
            return ()
        price = self._levels.bound(cost + config.cost + rest)
        return (_Entry(price, (*prefix, j), True, prefix, cost),)

    def _deepest(self) -> tuple[int, ...]:
        """The cheapest prefix among those that get furthest, found cheapest
        first over (step, state), each once."""
        queue: list[tuple[float, tuple[int, ...]]] = [(0.0, ())]
        seen: set[tuple[int, Facts]] = set()
        deepest: tuple[int, ...] = ()
        while queue:
            clock.check()
            cost, prefix = heapq.heappop(queue)
            facts = self.state_after(prefix)[0]
            if (len(prefix), facts) in seen:
                continue
            seen.add((len(prefix), facts))
            if len(prefix) > len(deepest):
                deepest = prefix
            if len(prefix) == len(self.goals):
                continue
            ranked, j = self.ranked(len(prefix), facts), 0
            while (config := ranked.get(j)) is not None:
                heapq.heappush(queue, (cost + config.cost, (*prefix, j)))
                j += 1
        return deepest

    def _planned(self, prefix: tuple[int, ...], total: float) -> PlannedSequence:
        steps = []
        for i in range(1, len(prefix) + 1):
            changes = self.state_after(prefix[:i])[1]
            steps.append(Step(self.goals[i - 1], self.configuration(prefix[:i]), changes))
        return PlannedSequence(tuple(steps), self._levels.cost(total))

    @cached_property
    def _levels(self) -> Levels:
        """How totals are ranked: as the steps' costs are, the switch weight
        counted in (:mod:`cfgplan.planner.costs`; a sum of floats in another
        order may differ in the last bit)."""
        return self.task.costs.levels(self.switch)

    def blocked(self) -> tuple[int, Task, Report] | None:
        """When no sequence exists (the search ran to its end): the step (0-based)
        that has no admissible configuration in any state the steps before it
        reach, the task of the state the cheapest prefix reaching it leaves, and
        why nothing is admissible there, as ``plan`` says it."""
        if not self.status.exhausted or self.remaining(0, self.task.facts) < math.inf:
            return None
        prefix = self._deepest()
        facts, _ = self.state_after(prefix)
        ranked = self.ranked(len(prefix), facts)
        run = Run(ranked.task, ranked.goal, limit=1, time_limit=5.0)
        list(run)
        return len(prefix), ranked.task, run.report
