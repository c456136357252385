"""The static checker's checks of a state and a goal against a domain (4.4,
4.5): facts that no precondition tests but one nearly does (a typo),
preconditions the state writes only in another case, and a goal that names
no method."""

from __future__ import annotations

from cfgplan.check.findings import Findings
from cfgplan.check.messages import alternatives, sig_text
from cfgplan.diagnostics import did_you_mean
from cfgplan.ir.model import Atom, Domain, Goal, Negation, State, is_variable


def _tested(domain: Domain) -> dict[str, Atom]:
    """The predicates the domain's preconditions test (negated or not), each
    with the first atom that tests it."""
    tested: dict[str, Atom] = {}
    for atom in _conditions(domain):
        tested.setdefault(atom.predicate, atom)
    return tested


def check_state(findings: Findings, state: State) -> None:
    """Facts no precondition tests whose predicate is close to one that is
    (a typo: ``(lazer Robby)``), and preconditions whose predicate the state
    writes only in another case (4.4)."""
    tested = _tested(findings.domain)
    stated: dict[str, Atom] = {}
    for fact in state.facts:
        stated.setdefault(fact.predicate, fact)
    for pred, fact in stated.items():
        if pred in tested or pred in PLANNER_FACTS:
            continue
        hint = did_you_mean(pred, tested)
        if hint is not None:
            findings.report(
                "warning",
                f"no precondition tests ({pred} ...), so the fact {fact} is never used",
                fact.span,
                hint,
            )
    for pred, atom in tested.items():
        close = sorted(s for s in stated if s != pred and s.lower() == pred.lower())
        if pred not in stated and close:
            findings.report(
                "warning",
                f"the state has no ({pred} ...) fact for the precondition {atom}",
                atom.span,
                f"symbols are case-sensitive: the state writes {' and '.join(close)}",
            )
    _check_object_case(findings, state)
    _check_argument_order(findings, state)


def _check_argument_order(findings: Findings, state: State) -> None:
    """A fact whose arguments look the other way round: ``(in Room1 Pippi)``
    where the preconditions test ``(in ?r ?room)`` with ``(robot ?r)``. The
    kinds of an object are the one-argument facts about it (``(robot
    Pippi)``); a precondition ``(P ?x ?y)`` wants, at each place, what the
    one-argument tests of the same list ask of that variable. A fact that no
    such pattern accepts as written, but one does with two arguments
    exchanged, is pointed out (4.5 matches facts by position)."""
    kinds: dict[str, set[str]] = {}
    for fact in state.facts:
        if fact.arity == 1:
            kinds.setdefault(fact.args[0], set()).add(fact.predicate)
    wanted: dict[tuple[str, int], list[tuple[Atom, tuple[frozenset[str], ...]]]] = {}
    lists = [f.precond for f in findings.domain.functionalities]
    lists += [m.precond for m in findings.domain.methods]
    for conds in lists:
        atoms = [c for c in conds if isinstance(c, Atom)]
        unary: dict[str, set[str]] = {}
        for a in atoms:
            if a.arity == 1 and is_variable(a.args[0]):
                unary.setdefault(a.args[0], set()).add(a.predicate)
        for a in atoms:
            if a.arity >= 2:
                need = tuple(
                    frozenset(unary.get(t, ())) if is_variable(t) else frozenset() for t in a.args
                )
                wanted.setdefault(a.signature, []).append((a, need))

    def fits(args: tuple[str, ...], atom: Atom, need: tuple[frozenset[str], ...]) -> bool:
        return all(
            (t == arg if not is_variable(t) else n <= kinds.get(arg, set()))
            for arg, t, n in zip(args, atom.args, need, strict=True)
        )

    for fact in state.facts:
        patterns = [p for p in wanted.get(fact.signature, ()) if any(p[1])]
        if not patterns or any(fits(fact.args, a, n) for a, n in patterns):
            continue
        for i in range(fact.arity):
            for j in range(i + 1, fact.arity):
                swapped = list(fact.args)
                swapped[i], swapped[j] = swapped[j], swapped[i]
                found = next((p for p in patterns if fits(tuple(swapped), *p)), None)
                if found is not None:
                    atom, need = found
                    tests = [
                        f"({k} {t})"
                        for t, n in zip(atom.args, need, strict=True)
                        for k in sorted(n)
                    ]
                    better = Atom(predicate=fact.predicate, args=tuple(swapped))
                    findings.report(
                        "warning",
                        f"no precondition accepts the fact {fact} as written: "
                        "its arguments may be the other way round",
                        fact.span,
                        f"the preconditions test {atom} with {', '.join(tests)}; "
                        f"did you mean {better}?",
                    )
                    break
            else:
                continue
            break


def _check_object_case(findings: Findings, state: State) -> None:
    """A fact's object written in another case than everywhere else
    (``(camera alpha)`` where the other facts and the domain write ``Alpha``):
    the fact is about another object, which no precondition is likely to ask
    for. Of the spellings of one name, the one written most often (in the
    state's facts, its goals and the domain's conditions; ties: the first written) is
    taken as meant; each fact writing another is pointed out (4.4)."""
    counts: dict[str, int] = {}
    for fact in state.facts:
        for arg in fact.args:
            counts[arg] = counts.get(arg, 0) + 1
    goals = [g.call for g in (state.goal, *state.sequence) if g is not None]
    for atom in [*_conditions(findings.domain), *goals]:
        for arg in atom.args:
            if not is_variable(arg):
                counts[arg] = counts.get(arg, 0) + 1
    meant: dict[str, str] = {}
    for name, n in counts.items():  # in the order first written
        best = meant.get(name.lower())
        if best is None or n > counts[best]:
            meant[name.lower()] = name
    for fact in state.facts:
        for arg in dict.fromkeys(fact.args):
            other = meant.get(arg.lower(), arg)
            if other != arg and not _is_number(arg):
                findings.report(
                    "warning",
                    f"the fact {fact} names {arg}, which differs only in case from {other} "
                    "(written elsewhere)",
                    fact.span,
                    f"symbols are case-sensitive: did you mean {other}?",
                )


def _conditions(domain: Domain) -> list[Atom]:
    """The atoms of the domain's preconditions (negated or not)."""
    out: list[Atom] = []
    conds = [c for f in domain.functionalities for c in f.precond]
    conds += [c for m in domain.methods for c in m.precond]
    for cond in conds:
        atom = cond.atom if isinstance(cond, Negation) else cond
        if isinstance(atom, Atom):
            out.append(atom)
    return out


def check_goal(findings: Findings, goal: Goal, state: State | None = None) -> None:
    """The goal names a method by name and arity (4.5), and, with the
    ``state``, each of its objects is one the state's facts name (else no
    precondition about it can hold: ``(do-cross-door Bob Door1)``, or
    ``PIPPI`` for ``Pippi``)."""
    call = goal.call
    if state is not None:
        _check_goal_objects(findings, goal, state)
    if call.signature in findings.versions:
        return
    span = call.span or goal.span
    if call.signature in findings.funcs:
        findings.report(
            "error",
            f"the goal {call} names a functionality, not a method",
            span,
            "a goal is a method instance such as (do-cross-door Pippi Door1)",
        )
        return
    arities = [s[1] for s in findings.versions if s[0] == call.predicate]
    hint = did_you_mean(call.predicate, {s[0] for s in findings.versions})
    if arities:
        hint = f"({call.predicate} ...) takes {alternatives(arities)}, found {call.arity}"
    findings.report(
        "error",
        f"the goal {call} names no method {sig_text(call.signature)}",
        span,
        hint,
    )


def _check_goal_objects(findings: Findings, goal: Goal, state: State) -> None:
    named = {a for fact in state.facts for a in fact.args}
    for arg in dict.fromkeys(goal.call.args):
        if arg in named or is_variable(arg) or _is_number(arg):
            continue
        findings.report(
            "warning",
            f"the goal {goal.call} names {arg}, which no fact of the state names",
            goal.call.span or goal.span,
            did_you_mean(arg, named),
        )


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


PLANNER_FACTS = frozenset({"device"})
"""Fact predicates the planner itself reads (:mod:`cfgplan.configuration.cost`):
used even when no precondition tests them."""
