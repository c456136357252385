"""Matching preconditions against the world state (thesis 4.5, step 2b).

:func:`bindings` yields every binding of a schema's preconditions, facts taken
in state order: the backtrack points of the planner. Identical bindings are
one binding (the state is a set). When none exists, :func:`why_not` names the
first condition that failed and the bindings it failed under, for the "why
nothing was found" report.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import NamedTuple

from cfgplan.check.evaluate import EvalFailure, holds
from cfgplan.diagnostics import did_you_mean
from cfgplan.ir.model import Span, is_variable
from cfgplan.notation import atom_text
from cfgplan.planner import clock
from cfgplan.planner.join import join
from cfgplan.planner.task import Ground, Pattern, Task, Test, TestKind
from cfgplan.planner.unify import Bindings, substitute, unify


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
    :func:`~cfgplan.planner.join.join` picks; if that is not the written one,
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
