"""Ground instances of the domain's schemas (thesis 4.5, steps 2b and 3): the
order preconditions are matched in, their bindings against the state, where an
instance can send its outputs from, and the instances, made on demand and
remembered.

Small whole numbers for the values search nodes are made of.

A node's canonical form (:func:`cfgplan.planner.partial.canonical`) and a
configuration's fingerprint (:func:`cfgplan.planner.finish.fingerprint`) are
sets of instances, channels and postconditions. Numbering each distinct value
once per task lets both be written as a short run of integers — equal values
(Python's ``==``: a bandwidth 1 is 1.0), equal numbers; different values,
different numbers — instead of texts made anew for every node. The table
lives as long as the task's grounding memo and grows with the distinct
values its searches meet. It is the task's one numbering: the partitioned
bound numbers its keys (instances, agents, channels as it prices them) from
it too (:attr:`cfgplan.planner.partition.Partition.number`).

The order a schema's preconditions are matched in (thesis 4.5, step 2b).

Written order can be a poor join: ``(robot ?a) (robot ?b) (robot ?c) (in ?a
?x) (in ?b ?x) (in ?c ?x) (in ?t ?x)`` with ``?t`` known enumerates every
triple of robots before the rooms filter them. :func:`join` matches instead,
among the atoms left, the one expected to match the fewest facts given what
is bound so far (the facts of its predicate, narrowed by a constant, divided
by the distinct values of each bound argument), written order among equals;
each ``not`` and ``eval`` runs as soon as its variables are bound.

The order of the bindings stays the thesis's (6.3.2): that of the written
order, facts in state order, i.e. by the state positions of the facts the
atoms, as written, match. :func:`cfgplan.planner.ground.bindings` sorts them
back by that key (:attr:`Join.atoms`) when the join was reordered.

Matching preconditions against the world state (thesis 4.5, step 2b).

:func:`bindings` yields every binding of a schema's preconditions, facts taken
in state order: the backtrack points of the planner. Identical bindings are
one binding (the state is a set). When none exists, :func:`why_not` names the
first condition that failed and the bindings it failed under, for the "why
nothing was found" report.

Where each ground method instance can send its outputs from (thesis 4.5,
step 3d): the expansions whose channels can never get their sending end onto
the robot they declare.

A channel declared ``(local ?r)`` must run from a functionality on ``?r``, one
declared ``(global ?a ?b)`` from one on ``?a`` (step 4; the search checks it
when both ends are placed, :func:`cfgplan.planner.partial.resolve`). When the
sending end is a method instance, it is re-wired through that instance's
``:out`` to the item that produces the data (step 3d), and again until it
reaches a functionality; its robot is the functionality's first argument. So
each ground method instance has, for each data descriptor it can send, the
set of robots its producer can end up on: its *senders*. They are the least
fixpoint of

    senders(m)[d] = the union, over the expansions e of m that can be placed,
                    of {r} when e's ``:out`` entry for d is a functionality on r,
                    or senders(c)[d] when it is a method instance c,

where an expansion can be placed when every item of its body can (a
functionality under some binding of its preconditions, a method instance
when it has an expansion that can be placed) and every channel of it from a
body item has its declared sending robot among that item's senders of its
data. An instance with no such expansion has no senders and cannot be placed.

The fixpoint is the least one, computed by chaotic iteration from "nothing
can be placed" up (every change re-evaluates the callers), so that a
recursive method claims only what some finite derivation gives it. That is
sound for the search: a derivation is a finite tree, built from the bottom
up out of expansions that can be placed, and the recursion guard of 4.5 only
removes derivations.

An expansion with a channel from a method instance that can send the
channel's data, but never from the robot the channel declares, is therefore
a dead end wherever it is met, though the search would find it out only at
the end of every derivation below it (a delegation chain that ends on
another robot: :func:`benchmarks.families.any_delegation`). The grounder
gives it as one (:meth:`cfgplan.planner.ground.Grounder.expansions`), with
its reason, and neither the search nor the bounds expand it. Nothing that
can complete is lost, and the order of what is listed does not change (the
expansion keeps its number among the method's choices). Other expansions
that cannot be placed are left to the search, which says why where it meets
the cause (:meth:`Placement.misplaced`).

Only sending ends are followed: the receiving end of a channel into a method
is re-wired to every item its ``:in`` names, a condition on all of them,
left to the search. A channel declared ``any`` is checked as the local or
global channel its robots made it when the expansion was instantiated
(:func:`cfgplan.planner.ground.channel_kind`); an expansion's robots are
ground (an unbound one is a dead end of its own, :func:`~cfgplan.planner.ground.instantiate`).

Ground instances of the domain's schemas, made on demand and remembered.

The planner grounds lazily (pyperplan grounds everything up front; here the
method hierarchy decides what is reachable). What it grounds depends only on
the task, so it is computed once per task and shared by every search of it:

- the bindings of a schema's preconditions for a call (4.5, step 2b);
- a method version instantiated for a call under each binding: its
  :class:`Expansion` with labels as offsets (4.5, step 3a);
- a functionality call's inputs, outputs and postconditions under each binding.

Each memo is keyed by everything its value depends on: the call (which names
the schema: name and arity) and, for a method, the version.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, NamedTuple, Protocol

from cfgplan.check.evaluate import EvalFailure, holds
from cfgplan.diagnostics import did_you_mean
from cfgplan.ir.model import Span, is_variable
from cfgplan.notation import atom_text, call_text
from cfgplan.planner import clock
from cfgplan.planner.report import Condition, DeadEnd
from cfgplan.planner.task import (
    FunctionalitySchema,
    Ground,
    Join,
    MethodSchema,
    Pattern,
    Signature,
    Task,
    Test,
    TestKind,
)
from cfgplan.planner.unify import Bindings, bind_name, is_ground, substitute, unify


@dataclass(eq=False, repr=False)
class Numbering:
    """Numbers 0, 1, 2, ... for values, in the order they are first asked for."""

    numbers: dict[Hashable, int] = field(default_factory=dict)
    _written: dict[Callable[[Any], str], dict[Hashable, int]] = field(default_factory=dict)

    def __call__(self, value: Hashable) -> int:
        found = self.numbers.get(value)
        if found is None:
            found = self.numbers[value] = len(self.numbers)
        return found

    def text(self, value: Hashable, write: Callable[[Any], str]) -> int:
        """The number of ``write(value)``: values written alike share it
        (``write`` is called once per value)."""
        memo = self._written.get(write)
        if memo is None:
            memo = self._written[write] = {}
        found = memo.get(value)
        if found is None:
            found = memo[value] = self(write(value))
        return found


def join(task: Task, tests: tuple[Test, ...], bound: frozenset[str]) -> Join:
    """The matching order of ``tests`` when ``bound`` are bound at the start,
    made once per tests and bound variables. A task in another state
    (:func:`~cfgplan.planner.task.derive`) keeps the orders made for
    the one it comes from: an order changes how fast bindings are found,
    never which, nor in what order they are given."""
    joins = task.joins
    found = joins.get((id(tests), bound))
    if found is not None and found[0] is tests:
        return found[1]
    made = _plan(task, tests, bound)
    joins[(id(tests), bound)] = (tests, made)  # the tests kept: their id stays theirs
    return made


def _plan(task: Task, tests: tuple[Test, ...], bound: frozenset[str]) -> Join:
    atoms = [t for t in tests if t.kind is TestKind.ATOM]
    if len(atoms) < 2:
        return Join(tests, (), False)  # compiled tests run each filter once it can
    filters = [(set(t.variables()), t) for t in tests if t.kind is not TestKind.ATOM]
    known = set(bound)
    ordered: list[Test] = []

    def release() -> None:
        for need, test in list(filters):
            if need <= known:
                ordered.append(test)
                filters.remove((need, test))

    release()
    left = list(atoms)
    while left:
        best = min(left, key=lambda atom: _estimate(task, atom.pattern, known))
        left.remove(best)
        ordered.append(best)
        known.update(best.variables())
        release()
    ordered.extend(test for _, test in filters)  # never bound: last, as written
    picked = [t for t in ordered if t.kind is TestKind.ATOM]
    reordered = any(a is not b for a, b in zip(picked, atoms, strict=True))
    if not reordered:
        return Join(tests, (), False)
    return Join(tuple(ordered), tuple(a.pattern for a in atoms), True)


def _estimate(task: Task, p: Pattern, known: set[str]) -> float:
    """How many facts ``p`` may match once ``known`` are bound."""
    arity = len(p) - 1
    count = float(len(task.facts_by_predicate.get((p[0], arity), ())))
    distinct = task.argument_values
    for position, term in enumerate(p[1:], 1):
        if not is_variable(term):
            count = min(count, len(task.facts_by_argument.get((p[0], arity, position, term), ())))
        elif term in known:
            count /= distinct.get((p[0], arity, position), 1)
    return count


def candidates(task: Task, p: Pattern, env: Bindings | None = None) -> tuple[Ground, ...]:
    """The facts that may match ``p``: those of its predicate, narrowed by the
    argument (constant or bound variable) with the fewest facts, in state order."""
    arity = len(p) - 1
    best = task.facts_by_predicate.get((p[0], arity), ())
    for position, term in enumerate(p[1:], 1):
        value = (env.get(term) if env is not None else None) if term[:1] == "?" else term
        if value is not None and len(best) > 1:
            narrowed = task.facts_by_argument.get((p[0], arity, position, value), ())
            if len(narrowed) < len(best):
                best = narrowed
    return best


def passes(task: Task, test: Test, env: Bindings) -> bool:
    """A ``not`` or ``eval`` test under ``env`` (an eval that cannot be
    evaluated, e.g. ``<`` on a symbol, is false)."""
    if test.kind is TestKind.NOT:
        return not any(
            unify(test.pattern, f, env) is not None for f in candidates(task, test.pattern, env)
        )
    try:
        return holds(test.expr, env)
    except EvalFailure:
        return False


def _walk(task: Task, tests: tuple[Test, ...], env: Bindings) -> Iterator[tuple[int, Bindings]]:
    """Depth-first over the tests, facts in state order: every (number of tests
    passed, bindings) reached; the complete ones have ``len(tests)``."""
    stack: list[tuple[int, Bindings]] = [(0, env)]
    steps = 0
    while stack:
        steps += 1
        if not steps & 1023:
            clock.check()  # a join of many facts may take long: the time limit holds
        index, current = stack.pop()
        yield index, current
        if index == len(tests):
            continue
        test = tests[index]
        if test.kind is TestKind.ATOM:
            matches = [
                m
                for f in candidates(task, test.pattern, current)
                if (m := unify(test.pattern, f, current)) is not None
            ]
            stack.extend((index + 1, m) for m in reversed(matches))
        elif passes(task, test, current):
            stack.append((index + 1, current))


def bindings(task: Task, tests: tuple[Test, ...], env: Bindings) -> Iterator[Bindings]:
    """Every extension of ``env`` satisfying ``tests``, in the order of a
    depth-first match of the tests as written, facts in state order. Distinct
    facts give distinct bindings (every variable of an atom is bound by it),
    so no binding is repeated. The atoms are matched in the order
    :func:`~cfgplan.planner.ground.join` picks; if that is not the written one,
    the bindings are sorted back by the state positions of the facts the
    written atoms match."""
    if not tests:
        yield env
        return
    done = len(tests)
    plan = join(task, tests, frozenset(env))
    if not plan.reordered:
        for index, current in _walk(task, tests, env):
            if index == done:
                yield current
        return
    found = [current for index, current in _walk(task, plan.tests, env) if index == done]
    position = task.positions
    found.sort(key=lambda b: tuple(position[substitute(atom, b)] for atom in plan.atoms))
    yield from found


def exists(task: Task, tests: tuple[Test, ...], env: Bindings) -> bool:
    """Whether some extension of ``env`` satisfies ``tests``: the first
    binding the join finds, none sorted."""
    done = len(tests)
    plan = join(task, tests, frozenset(env))
    return any(index == done for index, _ in _walk(task, plan.tests, env))


class Failure(NamedTuple):
    """The first precondition that no binding got past."""

    condition: str
    span: Span | None
    bindings: tuple[tuple[str, str], ...]
    detail: str = ""
    hint: str = ""
    """A likely slip: a fact that differs from the condition by one near
    spelling (:func:`_near_miss`)."""

    def describe(self) -> str:
        shown = [f"{k} = {v}" for k, v in self.bindings]
        where = f" with {', '.join(shown)}" if shown else ""
        hint = f": {self.hint}" if self.hint else ""
        return f"{self.detail or 'no fact matches'} {self.condition}{where}{hint}"


_DETAIL = {
    TestKind.ATOM: "no fact matches",
    TestKind.NOT: "a fact matches the negated",
    TestKind.EVAL: "false:",
}


def why_not(task: Task, tests: tuple[Test, ...], env: Bindings, params: Pattern) -> Failure:
    """Explain why :func:`bindings` yields nothing: the deepest test reached
    and the first binding it failed under (variables of the name omitted)."""
    best: tuple[int, Bindings] = (0, env)
    for index, current in _walk(task, tests, env):
        if index > best[0]:
            best = (index, current)
    index, current = best
    test = tests[min(index, len(tests) - 1)]
    named = {k: v for k, v in current.items() if k in params}
    if test.kind is TestKind.EVAL:
        # An eval is shown as written, with every variable it mentions.
        condition = test.text
        shown = tuple((k, v) for k, v in current.items() if _mentions(test, k))
    else:
        # An atom is shown with the name's variables filled in, the others listed.
        condition = atom_text(substitute(test.pattern, named))
        shown = tuple((k, v) for k, v in current.items() if k not in params and _mentions(test, k))
    near = ""
    if test.kind is TestKind.ATOM:
        near = _near_miss(task, test.pattern, current) or _case_hint(task, test.pattern, current)
    return Failure(condition, test.span, shown, _DETAIL[test.kind], near)


def _mentions(test: Test, var: str) -> bool:
    if test.kind is not TestKind.EVAL:
        return var in test.pattern
    return var in test.text.replace("(", " ").replace(")", " ").split()


def _near_miss(task: Task, p: Pattern, env: Bindings) -> str:
    """``did you mean Living? the state has (in Vacu Living)``: the first fact
    (in state order) that would match the condition but for one constant the
    state names nowhere (``Livng``: a slip; ``Room2``, a room of the state, is
    a real other place), a likely slip for the fact's by the rule of
    :func:`cfgplan.diagnostics.did_you_mean`; '' when there is none. Made
    once per failed call (the grounder keeps it): a condition whose
    constants the state all names, the common case, costs one look-up each."""
    ground = substitute(p, env)
    unknown = [
        i for i, t in enumerate(ground[1:], 1) if not is_variable(t) and t not in task.state_names
    ]
    if len(unknown) != 1:
        return ""
    (i,) = unknown
    for fact in task.facts_by_predicate.get((ground[0], len(ground) - 1), ()):
        if unify((*ground[:i], fact[i], *ground[i + 1 :]), fact, env) is None:
            continue  # differs elsewhere too
        hint = did_you_mean(ground[i], [fact[i]])
        if hint is not None:
            return f"{hint} the state has {atom_text(fact)}"
    return ""


def _case_hint(task: Task, p: Pattern, env: Bindings) -> str:
    """``symbols are case-sensitive: did you mean Pippi?`` when a symbol of the
    condition differs only in case from one the state names (and no single
    fact is a near miss, :func:`_near_miss`, which says which); '' else."""
    ground = substitute(p, env)
    folded = {n.lower(): n for n in task.state_names}
    for term in ground:
        if not is_variable(term) and term not in task.state_names and term.lower() in folded:
            return did_you_mean(term, [folded[term.lower()]]) or ""
    return ""


Senders = Mapping[Ground, frozenset[str]]
"""Data descriptor -> the robots its producer can be on."""

Spec = tuple[str, Ground, int, int, Ground, float | None]
"""A channel of an expansion: (kind, robots, source offset, target offset, data, bandwidth)."""


class Body(Protocol):
    """What the analysis reads of one expansion (the grounder's ``Expansion``)."""

    @property
    def channels(self) -> tuple[Spec, ...]: ...
    @property
    def body(self) -> tuple[Ground, ...]: ...
    @property
    def outputs(self) -> Mapping[Ground, tuple[int, float | None]]: ...


Value = dict[Ground, frozenset[str]] | None
"""A method instance's senders; None: it cannot be placed."""

Known = Callable[[Ground], Value]
"""The senders known of a method instance (while solving: the current guess)."""


Expansions = Callable[[Ground], Iterable[Body | DeadEnd]]
"""A method call's expansions, every version's in order (dead ends included)."""


@dataclass(eq=False, repr=False)
class Placement:
    """The senders of one task's ground method instances, computed over the
    part of the graph of ground instances below each call first asked for."""

    task: Task
    expansions: Expansions
    """Every expansion of a method call, unfiltered (the grounder's)."""
    placeable: Callable[[Ground], bool]
    """Whether a functionality call has a binding of its preconditions."""
    _senders: dict[Ground, Value] = field(default_factory=dict)
    """Method call -> its senders: the least fixpoint, final once set (a
    search stopped while solving leaves none of its guesses here)."""

    def senders(self, call: Ground) -> Senders | None:
        """The senders of method instance ``call`` (None: it cannot be placed)."""
        if call not in self._senders:
            self._solve(call)
        return self._senders[call]

    def misplaced(self, body: Body) -> DeadEnd | None:
        """Why ``body``'s expansion can never be placed, or None, given that
        what is below it is analysed (:meth:`senders` of its caller): a
        channel from a method instance that can send the channel's data, but
        never from the robot the channel declares. (Other expansions that
        cannot be placed are left to the search, which says why where it
        meets the cause: a functionality on the wrong robot as soon as both
        ends are placed, a precondition no binding satisfies, an ``:out``
        that does not produce the data.)"""
        for kind, robots, source, _, data, _ in self._checked(body):
            sender = body.body[source]
            if self.task.is_method(sender):
                # (not analysed: the expansion is ruled out by a functionality
                # of its body, left to the search to say)
                value = self._senders.get(sender)
                senders = frozenset() if value is None else value.get(data, frozenset())
                if senders and robots[0] not in senders:
                    return _unsendable(kind, robots, sender, data, senders)
        return None

    def _solve(self, root: Ground) -> None:
        """The least fixpoint over the method instances below ``root`` not yet
        analysed (those already analysed are final: what is below them was)."""
        found: dict[Ground, list[_Step]] = {}
        callers: dict[Ground, set[Ground]] = {}
        todo = [root]
        while todo:
            clock.check()
            call = todo.pop()
            if call in found:
                continue
            steps = found[call] = []
            for body in self.expansions(call):
                if isinstance(body, DeadEnd):
                    continue
                step = self._step(body)
                if step is None:
                    continue
                steps.append(step)
                for child in step.methods:
                    if child not in self._senders:
                        callers.setdefault(child, set()).add(call)
                        if child not in found:
                            todo.append(child)
        values: dict[Ground, Value] = dict.fromkeys(found)

        def known(call: Ground) -> Value:
            return values[call] if call in values else self._senders[call]

        queue = list(found)
        waiting = set(queue)
        while queue:
            clock.check()
            call = queue.pop()
            waiting.discard(call)
            value = _value(found[call], known)
            if value != values[call]:
                values[call] = value
                for caller in callers.get(call, ()):
                    if caller not in waiting:
                        waiting.add(caller)
                        queue.append(caller)
        self._senders.update(values)

    def _step(self, body: Body) -> _Step | None:
        """What the fixpoint reads of an expansion, worked out once; None when
        it can never be placed whatever the methods below it send (a
        functionality of its body without a binding, or on another robot
        than a channel from it declares)."""
        task = self.task
        methods: list[Ground] = []
        for child in body.body:
            if task.is_method(child):
                methods.append(child)
            elif task.functionality(child) is not None and not self.placeable(child):
                return None
        checks: list[tuple[str, Ground, Ground]] = []
        for _, robots, source, _, data, _ in self._checked(body):
            sender = body.body[source]
            if task.is_method(sender):
                checks.append((robots[0], sender, data))
            elif len(sender) < 2 or sender[1] != robots[0]:
                return None
        outputs: list[tuple[Ground, Ground | None, frozenset[str]]] = []
        for data, (offset, _) in body.outputs.items():
            producer = body.body[offset]
            if task.is_method(producer):
                outputs.append((data, producer, frozenset()))
            elif len(producer) > 1:
                outputs.append((data, None, frozenset({producer[1]})))
        return _Step(tuple(dict.fromkeys(methods)), tuple(checks), tuple(outputs))

    @staticmethod
    def _checked(body: Body) -> Iterator[Spec]:
        """The channels whose sending robot is checked: local and global ones
        (an ``any`` channel is one of them once instantiated)."""
        for spec in body.channels:
            if spec[0] in ("local", "global") and spec[1]:
                yield spec


class _Step(NamedTuple):
    """An expansion as the fixpoint reads it (:meth:`Placement._step`)."""

    methods: tuple[Ground, ...]
    """The method instances of its body: each must be placeable."""
    checks: tuple[tuple[str, Ground, Ground], ...]
    """(robot, method instance, data): a channel from it must start on robot."""
    outputs: tuple[tuple[Ground, Ground | None, frozenset[str]], ...]
    """(data, the method instance producing it, or None and the robot of the
    functionality that does)."""


def _value(steps: list[_Step], known: Known) -> Value:
    """A method instance's senders from its expansions, given ``known``."""
    value: dict[Ground, set[str]] | None = None
    for step in steps:
        if not all(known(m) is not None for m in step.methods):
            continue
        if not all(robot in _sent(known, m, d) for robot, m, d in step.checks):
            continue
        if value is None:
            value = {}
        for data, producer, robots in step.outputs:
            sent = robots if producer is None else _sent(known, producer, data)
            if sent:
                value.setdefault(data, set()).update(sent)
    return None if value is None else {d: frozenset(r) for d, r in value.items()}


def _sent(known: Known, call: Ground, data: Ground) -> frozenset[str]:
    """The robots method instance ``call`` can send ``data`` from, given ``known``."""
    senders = known(call)
    return frozenset() if senders is None else senders.get(data, frozenset())


def _unsendable(
    kind: str, robots: Ground, sender: Ground, data: Ground, senders: frozenset[str]
) -> DeadEnd:
    where = ", ".join(sorted(senders)) if senders else "no robot"
    return DeadEnd(
        f"{kind} channel {atom_text(data)}",
        f"declared ({kind} {' '.join(robots)}) but {call_text(sender)} can send "
        f"{atom_text(data)} only from {where}",
        condition=Condition.LOCATION,
    )


Effects = tuple[tuple[bool, Ground], ...]
"""Postconditions P: (positive, atom); ``(not ATOM)`` is ``(False, atom)``."""

IO = tuple[tuple[Ground, ...], tuple[Ground, ...]]
"""A functionality instance's inputs and outputs."""

ChannelSpec = tuple[str, Ground, int, int, Ground, float | None]
"""(kind, robots, source offset, target offset, data, bandwidth)."""


class Expansion(NamedTuple):
    """A method version instantiated with one binding, labels as offsets from
    the first fresh label; the same for every node that expands it.

    It carries the numbers the canonical form names what it creates by
    (:mod:`cfgplan.planner.partial`), so that items and channels are
    numbered when they are made, never afterwards: each channel's kind, robots,
    data and bandwidth, and each body item's call with no recursive ancestor
    (an item below a recursive method is numbered with those ancestors by
    :func:`~cfgplan.planner.partial.canonical`). ``number`` numbers a
    channel whose bandwidth its re-wiring sets."""

    size: int
    channels: tuple[ChannelSpec, ...]
    body: tuple[Ground, ...]
    outputs: dict[Ground, tuple[int, float | None]]  # data -> (offset, bandwidth)
    inputs: dict[Ground, tuple[int, ...]]  # data -> offsets
    effects: Effects
    where: str = ""  # "CALL, version N": where a dead end met expanding it is
    channel_numbers: tuple[int, ...] = ()  # per channel: (kind, robots, data, bandwidth), numbered
    body_numbers: tuple[int, ...] = ()  # per body item: (call, frozenset()), numbered
    recursive: bool = False  # the method can recur: it is a relevant ancestor of its body
    number: Numbering | None = None  # the numbering all of these come from


class FunctionalityInstance(NamedTuple):
    """A functionality call under one binding of its preconditions, with the
    numbers canonical forms name it by (:class:`Numbering`): ``number`` for
    the call with its inputs and outputs, ``name`` for the call alone."""

    io: IO
    effects: Effects
    number: int
    name: int


def _instance(
    schema: FunctionalitySchema, call: Ground, env: Bindings, number: Numbering
) -> FunctionalityInstance:
    io = (
        tuple(substitute(i, env) for i in schema.inputs),
        tuple(substitute(o, env) for o in schema.outputs),
    )
    effects = tuple((e.positive, substitute(e.pattern, env)) for e in schema.effects)
    return FunctionalityInstance(io, effects, number((call, *io)), number(call))


def _ground(p: Pattern, env: Bindings, where: str) -> Ground | DeadEnd:
    ground = substitute(p, env)
    if not is_ground(ground):
        free = next(t for t in ground[1:] if t[:1] == "?")
        return DeadEnd(
            where, f"{free} in {atom_text(p)} is bound by nothing", None, Condition.BINDING
        )
    return ground


def channel_kind(declared: str, robots: Ground) -> tuple[str, Ground]:
    """What a channel is once its robots are known: ``(any A B)`` is
    ``(local A)`` when A is B and ``(global A B)`` otherwise (an extension
    beyond the thesis); ``local`` and ``global`` stay what they say, so a
    declared global channel between ends on one robot stays global (6.4's 53)."""
    if declared != "any":
        return declared, robots
    return ("local", robots[:1]) if robots[0] == robots[1] else ("global", robots)


def instantiate(
    method: MethodSchema, env: Bindings, where: str, number: Numbering, recursive: bool
) -> Expansion | DeadEnd:
    """Instantiate a method version under ``env`` (step 3a of 4.5), numbered
    by ``number``; ``recursive``: whether the method's signature can recur
    (:attr:`Task.recursive`)."""
    offset = {body_label: i for i, (body_label, _) in enumerate(method.body)}
    channels: list[ChannelSpec] = []
    for spec in method.channels:
        data = _ground(spec.data, env, where)
        if isinstance(data, DeadEnd):
            return data
        robots = _ground(("robots", *spec.robots), env, where)
        if isinstance(robots, DeadEnd):
            return robots
        kind, ends = channel_kind(spec.kind, robots[1:])
        channels.append(
            (kind, ends, offset[spec.source], offset[spec.target], data, spec.bandwidth)
        )
    body = []
    for _, call in method.body:
        ground = _ground(call, env, where)
        if isinstance(ground, DeadEnd):
            return ground
        body.append(ground)
    outputs: dict[Ground, tuple[int, float | None]] = {}
    for port in method.outputs:
        outputs.setdefault(substitute(port.data, env), (offset[port.label], port.bandwidth))
    inputs: dict[Ground, tuple[int, ...]] = {}
    for port in method.inputs:
        data = substitute(port.data, env)
        inputs[data] = (*inputs.get(data, ()), offset[port.label])
    effects = tuple((eff.positive, substitute(eff.pattern, env)) for eff in method.effects)
    return Expansion(
        len(method.body),
        tuple(channels),
        tuple(body),
        outputs,
        inputs,
        effects,
        where,
        tuple(number((kind, ends, data, bw)) for kind, ends, _, _, data, bw in channels),
        tuple(number((call, frozenset())) for call in body),
        recursive,
        number,
    )


@dataclass(eq=False, repr=False)
class Grounder:
    """The memo of ground instances for one task."""

    task: Task
    _method_bindings: dict[tuple[Ground, int], tuple[Bindings, ...]] = field(default_factory=dict)
    _functionality_bindings: dict[Ground, tuple[Bindings, ...]] = field(default_factory=dict)
    _expansions: dict[tuple[Ground, int], tuple[Expansion | DeadEnd, ...]] = field(
        default_factory=dict
    )
    _raw: dict[tuple[Ground, int], tuple[Expansion | DeadEnd, ...]] = field(default_factory=dict)
    _instances: dict[Ground, tuple[FunctionalityInstance, ...]] = field(default_factory=dict)
    _failures: dict[tuple[Signature, int, Ground], Failure] = field(default_factory=dict)
    numbering: Numbering = field(default_factory=Numbering)
    """Numbers for the values of the task's search nodes (canonical forms, fingerprints)."""
    graphs: dict[bool, object] = field(default_factory=dict)
    """The AND/OR graphs of these expansions, one each way of noting the
    media: :func:`cfgplan.planner.graph.graph_of` makes and keeps them here,
    so that they go with the grounder (this module knows nothing of them)."""

    def method_bindings(self, method: MethodSchema, call: Ground) -> tuple[Bindings, ...]:
        """Every binding of a method version's preconditions for ``call``
        (none when its name does not match), facts in state order."""
        memo = (call, method.version)
        found = self._method_bindings.get(memo)
        if found is None:
            found = self._method_bindings[memo] = self._bindings(method.params, method.tests, call)
        return found

    def functionality_bindings(
        self, schema: FunctionalitySchema, call: Ground
    ) -> tuple[Bindings, ...]:
        """Every binding of a functionality's preconditions for ``call``."""
        found = self._functionality_bindings.get(call)
        if found is None:
            found = self._functionality_bindings[call] = self._bindings(
                schema.params, schema.tests, call
            )
        return found

    def _bindings(
        self, params: Pattern, tests: tuple[Test, ...], call: Ground
    ) -> tuple[Bindings, ...]:
        env = bind_name(params, call[1:])
        return () if env is None else tuple(bindings(self.task, tests, env))

    def expansions(self, method: MethodSchema, call: Ground) -> tuple[Expansion | DeadEnd, ...]:
        """A method version instantiated for ``call`` under each binding of its
        preconditions (state order), made once: the same for every node that
        expands ``call``, whatever its ancestors. An expansion that can never
        be placed (:class:`Placement`: a channel whose sending end
        can never be on the robot it declares) is given as a dead end, in its
        place."""
        memo = (call, method.version)
        found = self._expansions.get(memo)
        if found is None:
            self.placement.senders(call)  # what is below call, analysed once
            found = self._expansions[memo] = tuple(
                self._placed(e) for e in self._instantiated(method, call)
            )
        return found

    def _placed(self, expansion: Expansion | DeadEnd) -> Expansion | DeadEnd:
        if isinstance(expansion, DeadEnd):
            return expansion
        dead = self.placement.misplaced(expansion)
        if dead is None:
            return expansion
        return DeadEnd(expansion.where, dead.describe(), condition=dead.condition)

    def _instantiated(self, method: MethodSchema, call: Ground) -> tuple[Expansion | DeadEnd, ...]:
        """:meth:`expansions` before :class:`Placement` has its say."""
        memo = (call, method.version)
        found = self._raw.get(memo)
        if found is None:
            where = f"{call_text(call)}, version {method.version}"
            recursive = (method.name, len(method.params)) in self.task.recursive
            found = self._raw[memo] = tuple(
                instantiate(method, env, where, self.numbering, recursive)
                for env in self.method_bindings(method, call)
            )
        return found

    @cached_property
    def placement(self) -> Placement:
        """Where each method instance can send its outputs from (made once)."""
        task = self.task

        def every(call: Ground) -> Iterator[Expansion | DeadEnd]:
            for method in task.versions(call):
                yield from self._instantiated(method, call)

        known: dict[Ground, bool] = {}

        def placeable(call: Ground) -> bool:
            """Some binding of its preconditions exists (found, not all listed)."""
            found = known.get(call)
            if found is None:
                schema = task.functionality(call)
                env = None if schema is None else bind_name(schema.params, call[1:])
                found = known[call] = (
                    schema is not None and env is not None and exists(task, schema.tests, env)
                )
            return found

        return Placement(task, every, placeable)

    def instances(
        self, schema: FunctionalitySchema, call: Ground
    ) -> tuple[FunctionalityInstance, ...]:
        """The inputs, outputs and postconditions of a functionality call under
        each binding of its preconditions (state order), made once: they may
        use variables the preconditions bind (``(loc ?r) :precond ((in ?r
        ?room)) :out ((pos ?r ?room))``)."""
        found = self._instances.get(call)
        if found is None:
            found = self._instances[call] = tuple(
                _instance(schema, call, env, self.numbering)
                for env in self.functionality_bindings(schema, call)
            )
        return found

    def failure(
        self,
        schema: MethodSchema | FunctionalitySchema,
        call: Ground,
        explain: Callable[[], Failure],
    ) -> Failure:
        """Why ``schema`` has no binding for ``call``: ``explain()``, made once."""
        version = schema.version if isinstance(schema, MethodSchema) else 0
        memo = ((schema.name, len(schema.params)), version, call)
        found = self._failures.get(memo)
        if found is None:
            found = self._failures[memo] = explain()
        return found
