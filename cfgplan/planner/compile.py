"""From the checked IR to the planning task (:class:`cfgplan.planner.task.Task`).

Compiled once per problem: domain schemas become plain tuples (patterns,
ordered precondition tests, effect specs), the state's facts become a set in
state order with its two indexes, and the media their link reliabilities.
Everything the search reads afterwards is in the task; nothing here runs on
the hot path.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from types import MappingProxyType

from cfgplan.configuration.cost import Weights
from cfgplan.ir.model import (
    Atom,
    Condition,
    Domain,
    Effect,
    Eval,
    Functionality,
    Method,
    Negation,
    State,
    is_variable,
)
from cfgplan.notation import sexpr_text
from cfgplan.planner.task import (
    ChannelSchema,
    EffectSpec,
    FunctionalitySchema,
    Ground,
    MethodSchema,
    Pattern,
    PortSchema,
    Signature,
    Task,
    Test,
    TestKind,
    devices_of,
    index_facts,
    links_of,
)


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
