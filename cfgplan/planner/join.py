"""The order a schema's preconditions are matched in (thesis 4.5, step 2b).

Written order can be a poor join: ``(robot ?a) (robot ?b) (robot ?c) (in ?a
?x) (in ?b ?x) (in ?c ?x) (in ?t ?x)`` with ``?t`` known enumerates every
triple of robots before the rooms filter them. :func:`join` matches instead,
among the atoms left, the one expected to match the fewest facts given what
is bound so far (the facts of its predicate, narrowed by a constant, divided
by the distinct values of each bound argument), written order among equals;
each ``not`` and ``eval`` runs as soon as its variables are bound.

The order of the bindings stays the thesis's (6.3.2): that of the written
order, facts in state order, i.e. by the state positions of the facts the
atoms, as written, match. :func:`cfgplan.planner.match.bindings` sorts them
back by that key (:attr:`Join.atoms`) when the join was reordered.
"""

from __future__ import annotations

from cfgplan.ir.model import is_variable
from cfgplan.planner.task import Join, Pattern, Task, Test, TestKind


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
