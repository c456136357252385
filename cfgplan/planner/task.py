"""The planning task: a domain and a state compiled into plain, fast structures.

Like pyperplan's task model, this is what search works on: tuples and dicts,
no pydantic on the hot path. Built once by :func:`compile_task`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

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
    is_variable,
)

Ground = tuple[str, ...]
"""A ground atom as a tuple: ``("in", "Pippi", "Room1")``."""

Pattern = tuple[str, ...]
"""An atom with variables: ``("in", "?r", "?room")``."""


@dataclass(frozen=True, slots=True)
class Test:
    """One compiled precondition: an atom to match, a negation or an eval."""

    kind: str  # "atom" | "not" | "eval"
    pattern: Pattern = ()
    expr: SExpr = ""
    span: Span | None = None
    text: str = ""


@dataclass(frozen=True, slots=True)
class EffectSpec:
    positive: bool
    pattern: Pattern


@dataclass(frozen=True, slots=True)
class FunctionalitySchema:
    """A functionality operator (3.2) ready for instantiation."""

    name: str
    params: Pattern
    inputs: tuple[Pattern, ...]
    outputs: tuple[Pattern, ...]
    tests: tuple[Test, ...]
    effects: tuple[EffectSpec, ...]
    cost: float | None
    freq: float | None
    span: Span | None


@dataclass(frozen=True, slots=True)
class PortSchema:
    label: str
    data: Pattern
    bandwidth: float | None


@dataclass(frozen=True, slots=True)
class ChannelSchema:
    kind: str  # "local" | "global"
    robots: Pattern
    source: str
    target: str
    data: Pattern
    bandwidth: float | None


@dataclass(frozen=True, slots=True)
class MethodSchema:
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


@dataclass
class Task:
    """Everything the search needs, indexed for lookup."""

    functionalities: dict[tuple[str, int], FunctionalitySchema]
    methods: dict[tuple[str, int], tuple[MethodSchema, ...]]
    facts: tuple[Ground, ...]
    facts_by_predicate: dict[tuple[str, int], tuple[Ground, ...]]
    facts_by_argument: dict[tuple[str, int, int, str], tuple[Ground, ...]]
    """(predicate, arity, position, value) -> the facts with that argument, in state order."""
    fact_set: frozenset[Ground]
    media: tuple[Medium, ...]
    weights: Weights
    state_names: frozenset[str] = field(default_factory=frozenset)
    io: dict[Ground, tuple[tuple[Ground, ...], tuple[Ground, ...]]] = field(default_factory=dict)
    """Memo: a functionality instance's inputs and outputs, instantiated."""
    models: dict[tuple[object, ...], Any] = field(default_factory=dict)
    """Memo: result models (immutable) shared by the configurations built."""
    summaries: dict[Ground, Any] = field(default_factory=dict)
    """Memo of bound.py: what every expansion of a ground instance contains."""
    reach: dict[tuple[str, int], Any] = field(default_factory=dict)
    """Memo of bound.py: the names a signature can reach through method bodies."""


def pattern(atom: Atom) -> Pattern:
    return (atom.predicate, *atom.args)


def show(p: Sequence[str]) -> str:
    """Print an atom tuple as the thesis's s-expression ``(in Pippi Room1)``."""
    return "(" + " ".join(p) + ")"


def _tests(conditions: Sequence[Condition], bound: set[str]) -> tuple[Test, ...]:
    """Order preconditions so every ``not`` and ``eval`` runs once its variables
    are bound by the name or an earlier atom (atoms keep their order)."""
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
            ordered.append(Test("atom", pattern(cond), span=cond.span, text=str(cond)))
            known.update(cond.variables())
            release()
        elif isinstance(cond, Negation):
            test = Test("not", pattern(cond.atom), span=cond.span, text=str(cond))
            waiting.append((set(cond.atom.variables()), test))
            release()
        elif isinstance(cond, Eval):
            test = Test("eval", expr=cond.expr, span=cond.span, text=_eval_text(cond.expr))
            waiting.append((set(cond.variables()), test))
            release()
    ordered.extend(test for _, test in waiting)
    return tuple(ordered)


def _eval_text(expr: SExpr) -> str:
    if isinstance(expr, list):
        return "(" + " ".join(_eval_text(e) for e in expr) + ")"
    return str(expr)


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


def compile_task(domain: Domain, state: State, weights: Weights | None = None) -> Task:
    """Compile a checked domain and a state into a :class:`Task`."""
    functionalities: dict[tuple[str, int], FunctionalitySchema] = {}
    for f in domain.functionalities:
        functionalities.setdefault(f.name.signature, _functionality(f))
    methods: dict[tuple[str, int], list[MethodSchema]] = {}
    for m in domain.methods:
        versions = methods.setdefault(m.name.signature, [])
        versions.append(_method(m, len(versions) + 1))
    facts = tuple(pattern(a) for a in state.facts)
    by_pred: dict[tuple[str, int], list[Ground]] = {}
    for fact in facts:
        by_pred.setdefault((fact[0], len(fact) - 1), []).append(fact)
    by_arg: dict[tuple[str, int, int, str], list[Ground]] = {}
    for fact in facts:
        for position, value in enumerate(fact[1:], 1):
            by_arg.setdefault((fact[0], len(fact) - 1, position, value), []).append(fact)
    names = {t for fact in facts for t in fact}
    return Task(
        functionalities=functionalities,
        methods={k: tuple(v) for k, v in methods.items()},
        facts=facts,
        facts_by_predicate={k: tuple(v) for k, v in by_pred.items()},
        facts_by_argument={k: tuple(v) for k, v in by_arg.items()},
        fact_set=frozenset(facts),
        media=state.media,
        weights=weights or Weights(),
        state_names=frozenset(names),
    )
