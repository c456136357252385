"""The planning task: a domain and a state compiled into plain, fast structures,
and the compiler that makes it from the checked IR.

The planning task: a domain and a state compiled into plain, fast structures.

Like pyperplan's task model, this is what search works on: tuples and dicts,
no pydantic on the hot path. Built once from the IR
(:func:`cfgplan.planner.task.compile_task`), derived in one way
(:func:`derive`), and frozen: no field of it ever changes. What is worked out
from those fields is kept with the task, so that it goes when the task goes
(a running society plans on one derived task after another): its own derived
values as cached properties (:attr:`Task.recursive`, :attr:`Task.levels`,
:attr:`Task.positions`, ...), and what the planner makes once per task in two
slots: its analysis (:attr:`Task.analyses`: the grounding memo, the bounds, the
goal's independent parts and the replays' rules, :func:`cfgplan.planner.plan.analysis`)
and the matching orders (:attr:`Task.joins`, :mod:`cfgplan.planner.ground`). Nothing kept there ever
changes what the task says. (A table beside the task, keyed weakly by it,
would never let it go: what the planner keeps refers to the task.)

The world state is a *set* of facts (4.4): a fact written twice is one fact,
so it gives one binding, one derivation. State order (first occurrence) is
kept: it orders the bindings, hence the derivations at equal cost (6.3.2).

From the checked IR to the planning task (:class:`cfgplan.planner.task.Task`).

Compiled once per problem: domain schemas become plain tuples (patterns,
ordered precondition tests, effect specs), the state's facts become a set in
state order with its two indexes, and the media their link reliabilities.
Everything the search reads afterwards is in the task; nothing here runs on
the hot path.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from enum import Enum
from functools import cached_property
from types import MappingProxyType
from typing import Any, NamedTuple

from cfgplan.configuration.cost import Weights
from cfgplan.ir.model import (
    Atom,
    Condition,
    Domain,
    Effect,
    Eval,
    Functionality,
    Medium,
    Method,
    Negation,
    SExpr,
    Span,
    State,
    expr_variables,
    is_variable,
)
from cfgplan.notation import sexpr_text
from cfgplan.planner.costs import Costs, Levels

Ground = tuple[str, ...]
"""A ground atom or call as a tuple: ``("in", "Pippi", "Room1")``."""

Pattern = tuple[str, ...]
"""An atom with variables: ``("in", "?r", "?room")``."""

Signature = tuple[str, int]
"""Name and arity: what identifies a method or functionality (4.5)."""


class TestKind(Enum):
    """What a compiled precondition does."""

    ATOM = "atom"  # match a fact, binding free variables
    NOT = "not"  # no fact matches
    EVAL = "eval"  # the safe (eval ...) subset holds


@dataclass(frozen=True, slots=True)
class Test:
    """One compiled precondition: an atom to match, a negation or an eval."""

    __test__ = False  # not a pytest test class

    kind: TestKind
    pattern: Pattern = ()
    expr: SExpr = ""
    span: Span | None = None
    text: str = ""

    def variables(self) -> list[str]:
        """The variables it mentions, in order of appearance."""
        if self.kind is TestKind.EVAL:
            return expr_variables(self.expr)
        return [t for t in self.pattern[1:] if is_variable(t)]


class EffectSpec(NamedTuple):
    positive: bool
    pattern: Pattern


class FunctionalitySchema(NamedTuple):
    """A functionality operator (3.2) ready for instantiation."""

    name: str
    params: Pattern
    inputs: tuple[Pattern, ...]
    outputs: tuple[Pattern, ...]
    tests: tuple[Test, ...]
    effects: tuple[EffectSpec, ...]
    cost: float | None
    freq: float | None
    reliability: float | None
    span: Span | None


class PortSchema(NamedTuple):
    label: str
    data: Pattern
    bandwidth: float | None


class Join(NamedTuple):
    """A schema's preconditions in the order they are matched
    (:func:`cfgplan.planner.ground.join`); ``atoms``, the atoms in written order,
    give the bindings' sort key when ``reordered``."""

    tests: tuple[Test, ...]
    atoms: tuple[Pattern, ...]
    reordered: bool


class ChannelSchema(NamedTuple):
    kind: str  # "local" | "global" | "any" (decided when instantiated)
    robots: Pattern
    source: str
    target: str
    data: Pattern
    bandwidth: float | None


class MethodSchema(NamedTuple):
    """One version of a configuration method (4.4)."""

    name: str
    version: int  # 1-based, among the versions with this name and arity
    params: Pattern
    tests: tuple[Test, ...]
    effects: tuple[EffectSpec, ...]
    inputs: tuple[PortSchema, ...]
    outputs: tuple[PortSchema, ...]
    channels: tuple[ChannelSchema, ...]
    body: tuple[tuple[str, Pattern], ...]
    span: Span | None

    @property
    def signature(self) -> Signature:
        return (self.name, len(self.params))


@dataclass(frozen=True, eq=False, repr=False)
class Task:
    """Everything the search needs, indexed for lookup; never changed once built."""

    functionalities: Mapping[Signature, FunctionalitySchema]
    methods: Mapping[Signature, tuple[MethodSchema, ...]]
    facts: tuple[Ground, ...]
    """The state's facts, each once, in order of first occurrence."""
    facts_by_predicate: Mapping[Signature, tuple[Ground, ...]]
    facts_by_argument: Mapping[tuple[str, int, int, str], tuple[Ground, ...]]
    """(predicate, arity, position, value) -> the facts with that argument, in state order."""
    media: tuple[Medium, ...]
    weights: Weights
    devices: frozenset[str]
    """Agents the state declares ``(device X)``: weighted as devices, not robots."""
    reliability: Mapping[Ground, float]
    """Reliabilities of functionality instances that replace their schema's
    (e.g. lowered after failures seen at run time)."""
    links: Mapping[tuple[str, str], float]
    """(sender, receiver) -> the most reliable medium's reliability (1 if unsaid)."""
    state_names: frozenset[str]
    """Every symbol of the state: for "differs only in case" hints."""
    analyses: dict[bool, Any] = field(default_factory=dict, init=False, repr=False)
    """The planner's analysis of this task, by :attr:`SearchOptions.media`:
    a :class:`cfgplan.planner.plan.Analysis` (typed there: this lower module
    cannot name it), made by :func:`cfgplan.planner.plan.analysis` at the first
    search. A cache, written after the task is built (see the module's
    docstring); a derived task starts without."""
    joins: dict[tuple[int, frozenset[str]], tuple[tuple[Test, ...], Join]] = field(
        default_factory=dict, init=False, repr=False
    )
    """The matching orders made for this task's schemas
    (:func:`cfgplan.planner.ground.join`), by the tests' identity and the
    variables bound at the start; valid in any state, so a derived task with
    the same schemas starts with them."""

    @cached_property
    def agents(self) -> tuple[str, ...]:
        """The robots and devices the state declares, ``(robot X)`` and
        ``(device X)``, each once, in state order: who may run a part."""
        named = (f[1] for f in self.facts if f[0] in ("robot", "device") and len(f) == 2)
        return tuple(dict.fromkeys(named))

    @cached_property
    def recursive(self) -> frozenset[Signature]:
        """Method signatures that can reach themselves through method bodies:
        only their instances can meet the recursion guard of 4.5. Those of
        a strongly connected component of the call graph with a cycle in it
        (more than one signature, or one that calls itself), found in one
        walk (Tarjan's, without recursion: a hierarchy may be thousands of
        levels deep)."""
        reach: dict[Signature, tuple[Signature, ...]] = {}
        for sig, versions in self.methods.items():
            called = dict.fromkeys((p[0], len(p) - 1) for m in versions for _, p in m.body)
            reach[sig] = tuple(c for c in called if c in self.methods)
        index: dict[Signature, int] = {}  # in the order first met
        low: dict[Signature, int] = {}  # the least index it reaches on the stack
        stack: list[Signature] = []
        on_stack: set[Signature] = set()
        found: set[Signature] = set()
        for start in self.methods:
            if start in index:
                continue
            index[start] = low[start] = len(index)
            stack.append(start)
            on_stack.add(start)
            walk = [(start, iter(reach[start]))]
            while walk:
                sig, calls = walk[-1]
                for callee in calls:
                    if callee not in index:
                        index[callee] = low[callee] = len(index)
                        stack.append(callee)
                        on_stack.add(callee)
                        walk.append((callee, iter(reach[callee])))
                        break
                    if callee in on_stack:
                        low[sig] = min(low[sig], index[callee])
                else:
                    walk.pop()
                    if walk:
                        caller = walk[-1][0]
                        low[caller] = min(low[caller], low[sig])
                    if low[sig] == index[sig]:  # sig is the root of a component
                        component = []
                        while True:
                            member = stack.pop()
                            on_stack.discard(member)
                            component.append(member)
                            if member == sig:
                                break
                        if len(component) > 1 or sig in reach[sig]:
                            found.update(component)
        return frozenset(found)

    @cached_property
    def positions(self) -> Mapping[Ground, int]:
        """Each fact's position in the state: the sort key of bindings (state order)."""
        return {fact: i for i, fact in enumerate(self.facts)}

    @cached_property
    def argument_values(self) -> Mapping[tuple[str, int, int], int]:
        """How many distinct values each argument (predicate, arity, position)
        takes in the state: what a matching order estimates by
        (:mod:`cfgplan.planner.ground`)."""
        found: dict[tuple[str, int, int], int] = {}
        for predicate, arity, position, _ in self.facts_by_argument:
            key = (predicate, arity, position)
            found[key] = found.get(key, 0) + 1
        return found

    @cached_property
    def costs(self) -> Costs:
        """What each part of its configurations costs (:mod:`cfgplan.planner.costs`)."""
        return Costs(
            self.weights,
            self.devices,
            self.links,
            self.reliability,
            tuple(f.cost for f in self.functionalities.values() if f.cost is not None),
        )

    @cached_property
    def levels(self) -> Levels:
        """How its costs are ranked (:meth:`cfgplan.planner.costs.Costs.levels`)."""
        return self.costs.levels()

    @cached_property
    def uncertain(self) -> bool:
        """Some functionality or medium is less than fully reliable (7.2):
        otherwise every configuration's reliability is 1."""
        return (
            any(p != 1.0 for p in self.reliability.values())
            or any(p != 1.0 for p in self.links.values())
            or any(f.reliability not in (None, 1.0) for f in self.functionalities.values())
        )

    def is_method(self, call: Ground) -> bool:
        return (call[0], len(call) - 1) in self.methods

    def functionality(self, call: Ground) -> FunctionalitySchema | None:
        return self.functionalities.get((call[0], len(call) - 1))

    def versions(self, call: Ground) -> tuple[MethodSchema, ...]:
        return self.methods.get((call[0], len(call) - 1), ())

    def functionality_reliability(self, schema: FunctionalitySchema, call: Ground) -> float:
        """:meth:`cfgplan.planner.costs.Costs.reliability_of`."""
        return self.costs.reliability_of(schema, call)


def index_facts(
    facts: Sequence[Ground],
) -> tuple[
    Mapping[Signature, tuple[Ground, ...]], Mapping[tuple[str, int, int, str], tuple[Ground, ...]]
]:
    """The two fact indexes a :class:`Task` keeps: by predicate, and by
    predicate and argument value, each in state order."""
    by_pred: dict[Signature, list[Ground]] = {}
    by_arg: dict[tuple[str, int, int, str], list[Ground]] = {}
    for fact in facts:
        by_pred.setdefault((fact[0], len(fact) - 1), []).append(fact)
        for position, value in enumerate(fact[1:], 1):
            by_arg.setdefault((fact[0], len(fact) - 1, position, value), []).append(fact)
    return (
        MappingProxyType({k: tuple(v) for k, v in by_pred.items()}),
        MappingProxyType({k: tuple(v) for k, v in by_arg.items()}),
    )


def devices_of(facts: Sequence[Ground]) -> frozenset[str]:
    """The agents ``facts`` declare ``(device X)``: weighted as devices (3.5)."""
    return frozenset(f[1] for f in facts if f[0] == "device" and len(f) == 2)


def links_of(media: Sequence[Medium]) -> dict[tuple[str, str], float]:
    """(sender, receiver) -> the most reliable medium's reliability (7.2)."""
    links: dict[tuple[str, str], float] = {}
    for m in media:
        p = m.reliability if m.reliability is not None else 1.0
        key = (m.sender, m.receiver)
        links[key] = max(p, links.get(key, 0.0))
    return links


def derive(
    task: Task,
    facts: Sequence[Ground],
    *,
    functionalities: Mapping[Signature, FunctionalitySchema] | None = None,
    media: tuple[Medium, ...] | None = None,
    reliability: Mapping[Ground, float] | None = None,
) -> Task:
    """``task`` in another world state, the one way a task is derived: the
    same compiled methods and weights, ``facts`` (each once, in order)
    re-indexed, and, where given, other functionality schemas (a running
    society's guards, :mod:`cfgplan.reconfigure.situation`), media and
    reliabilities (7.2). No domain is read, checked or compiled: a sequence's
    later steps, or a running society's changed state, are planned from it.
    What the planner worked out for ``task`` (:attr:`Task.analyses`) is not
    carried, but for the matching orders (:mod:`cfgplan.planner.ground`),
    valid in any state while the schemas are the same."""
    unique = tuple(dict.fromkeys(facts))
    by_pred, by_arg = index_facts(unique)
    changes: dict[str, Any] = {}
    if functionalities is not None:
        changes["functionalities"] = functionalities
    if media is not None:
        changes["media"] = media
        changes["links"] = MappingProxyType(links_of(media))
    if reliability is not None:
        changes["reliability"] = MappingProxyType(dict(reliability))
    derived = dataclasses.replace(
        task,
        facts=unique,
        facts_by_predicate=by_pred,
        facts_by_argument=by_arg,
        devices=devices_of(unique),
        state_names=frozenset(t for fact in unique for t in fact),
        **changes,
    )
    if functionalities is None:
        derived.joins.update(task.joins)
    return derived


def pattern(atom: Atom) -> Pattern:
    """An IR atom as the task holds it: ``("in", "?r", "?room")``."""
    return (atom.predicate, *atom.args)


def _tests(conditions: Sequence[Condition], bound: set[str]) -> tuple[Test, ...]:
    """Order preconditions so every ``not`` and ``eval`` runs once its variables
    are bound by the name or an earlier atom (atoms keep their order): an
    ``eval`` written before the atom that binds its variable is postponed."""
    known = set(bound)
    ordered: list[Test] = []
    waiting: list[tuple[set[str], Test]] = []

    def release() -> None:
        for need, test in list(waiting):
            if need <= known:
                ordered.append(test)
                waiting.remove((need, test))

    for cond in conditions:
        if isinstance(cond, Atom):
            ordered.append(Test(TestKind.ATOM, pattern(cond), span=cond.span, text=str(cond)))
            known.update(cond.variables())
            release()
        elif isinstance(cond, Negation):
            test = Test(TestKind.NOT, pattern(cond.atom), span=cond.span, text=str(cond))
            waiting.append((set(cond.atom.variables()), test))
            release()
        elif isinstance(cond, Eval):
            test = Test(TestKind.EVAL, expr=cond.expr, span=cond.span, text=sexpr_text(cond.expr))
            waiting.append((set(cond.variables()), test))
            release()
    ordered.extend(test for _, test in waiting)
    return tuple(ordered)


def _effects(effects: Sequence[Effect]) -> tuple[EffectSpec, ...]:
    out: list[EffectSpec] = []
    for eff in effects:
        if isinstance(eff, Negation):
            out.append(EffectSpec(False, pattern(eff.atom)))
        else:
            out.append(EffectSpec(True, pattern(eff)))
    return tuple(out)


def _functionality(f: Functionality) -> FunctionalitySchema:
    params = f.name.args
    return FunctionalitySchema(
        name=f.name.predicate,
        params=params,
        inputs=tuple(pattern(a) for a in f.inputs),
        outputs=tuple(pattern(a) for a in f.outputs),
        tests=_tests(f.precond, {p for p in params if is_variable(p)}),
        effects=_effects(f.postcond),
        cost=f.cost,
        freq=f.freq,
        reliability=f.reliability,
        span=f.span,
    )


def _method(m: Method, version: int) -> MethodSchema:
    params = m.name.args
    return MethodSchema(
        name=m.name.predicate,
        version=version,
        params=params,
        tests=_tests(m.precond, {p for p in params if is_variable(p)}),
        effects=_effects(m.postcond),
        inputs=tuple(PortSchema(p.label, pattern(p.data), p.bandwidth) for p in m.inputs),
        outputs=tuple(PortSchema(p.label, pattern(p.data), p.bandwidth) for p in m.outputs),
        channels=tuple(
            ChannelSchema(c.kind, c.robots, c.source, c.target, pattern(c.data), c.bandwidth)
            for c in m.channels
        ),
        body=tuple((b.label, pattern(b.call)) for b in m.body),
        span=m.span,
    )


def compile_task(
    domain: Domain,
    state: State,
    weights: Weights | None = None,
    reliability: Mapping[Ground, float] | None = None,
) -> Task:
    """Compile a checked domain and a state into a :class:`Task`; ``reliability``
    replaces the reliability of some functionality instances."""
    functionalities: dict[Signature, FunctionalitySchema] = {}
    for f in domain.functionalities:
        functionalities.setdefault(f.name.signature, _functionality(f))
    methods: dict[Signature, list[MethodSchema]] = {}
    for m in domain.methods:
        versions = methods.setdefault(m.name.signature, [])
        versions.append(_method(m, len(versions) + 1))
    facts = tuple(dict.fromkeys(pattern(a) for a in state.facts))  # a set, in state order
    by_pred, by_arg = index_facts(facts)
    return Task(
        functionalities=MappingProxyType(functionalities),
        methods=MappingProxyType({k: tuple(v) for k, v in methods.items()}),
        facts=facts,
        facts_by_predicate=by_pred,
        facts_by_argument=by_arg,
        media=state.media,
        weights=weights or Weights(),
        devices=devices_of(facts),
        reliability=MappingProxyType(dict(reliability or {})),
        links=MappingProxyType(links_of(state.media)),
        state_names=frozenset(t for fact in facts for t in fact),
    )
