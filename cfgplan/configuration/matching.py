"""Matching preconditions against the facts of a state, for the independent
admissibility checker (:mod:`cfgplan.configuration.admissible`; thesis 3.5,
causal admissibility). It shares no code with the planner's matcher
(:mod:`cfgplan.planner.unify`, :mod:`cfgplan.planner.ground`), so that the two
check each other.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence

from cfgplan.check.evaluate import EvalFailure, holds
from cfgplan.ir.model import Atom, Condition, Eval, Negation

Ground = tuple[str, ...]
Env = dict[str, str]


def is_var(term: str) -> bool:
    """A variable is written ``?name``."""
    return term.startswith("?")


def unify(pattern: Sequence[str], fact: Sequence[str], env: Mapping[str, str]) -> Env | None:
    """``env`` extended so that ``pattern`` equals ``fact`` (both as tuples
    ``(predicate, *args)``), or None."""
    if len(pattern) != len(fact) or pattern[0] != fact[0]:
        return None
    out = dict(env)
    for term, value in zip(pattern[1:], fact[1:], strict=True):
        if is_var(term):
            if out.setdefault(term, value) != value:
                return None
        elif term != value:
            return None
    return out


def atom_of(atom: Atom) -> Ground:
    """An atom as the tuple ``(predicate, *args)`` the matcher works on."""
    return (atom.predicate, *atom.args)


def subst(atom: Ground, env: Mapping[str, str]) -> Ground:
    """``atom`` with the variables ``env`` binds replaced by their values."""
    return tuple(env.get(t, t) for t in atom)


def satisfying(conditions: Sequence[Condition], facts: Sequence[Ground], env: Env) -> Iterator[Env]:
    """Every binding extending ``env`` under which ``conditions`` hold in ``facts``.

    Atoms bind variables against the facts; ``(not ATOM)`` and ``(eval EXPR)``
    are tests on the complete binding: no fact unifies with the negated atom
    (variables still unbound match anything), and the expression evaluates to
    true (an unbound variable or an evaluation error makes it false).
    """
    atoms = [atom_of(c) for c in conditions if isinstance(c, Atom)]
    tests = [c for c in conditions if not isinstance(c, Atom)]

    def passes(current: Env) -> bool:
        for test in tests:
            if isinstance(test, Negation):
                negated = atom_of(test.atom)
                if any(unify(negated, fact, current) is not None for fact in facts):
                    return False
            elif isinstance(test, Eval):
                try:
                    if not holds(test.expr, current):
                        return False
                except EvalFailure:
                    return False
        return True

    if not atoms:
        if passes(env):
            yield env
        return
    # Depth first over the atoms, facts in order; an explicit stack (one entry
    # per atom matched so far), so that a long precondition list needs no recursion.
    stack: list[tuple[Env, Iterator[Ground]]] = [(env, iter(facts))]
    while stack:
        current, remaining = stack[-1]
        atom = atoms[len(stack) - 1]
        bound = next((b for f in remaining if (b := unify(atom, f, current)) is not None), None)
        if bound is None:
            stack.pop()
        elif len(stack) == len(atoms):
            if passes(bound):
                yield bound
        else:
            stack.append((bound, iter(facts)))
