"""The compiled task's own derived facts (cfgplan/planner/task.py)."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from tests.planner.problems import PROPERTY, load_text

Calls = dict[int, frozenset[int]]


@st.composite
def call_graphs(draw: st.DrawFn) -> Calls:
    """Which of up to seven methods each method's body calls."""
    size = draw(st.integers(1, 7))
    callee = st.integers(0, size - 1)
    return {i: draw(st.frozensets(callee, max_size=3)) for i in range(size)}


def domain_of(calls: Calls) -> str:
    lines = ["(make-functionality :name '(f ?r) :out '((d ?r)))"]
    for i, called in calls.items():
        body = " ".join(f"(?c{j} (m{j} ?r))" for j in sorted(called))
        lines.append(f"(make-config-method :name '(m{i} ?r) :body '((?x (f ?r)) {body}))")
    return "\n".join(lines) + "\n"


def reaches_itself(calls: Calls, start: int) -> bool:
    seen: set[int] = set()
    todo = list(calls[start])
    while todo:
        current = todo.pop()
        if current == start:
            return True
        if current not in seen:
            seen.add(current)
            todo.extend(calls[current])
    return False


@pytest.mark.quick(30)
@PROPERTY
@given(call_graphs())
def test_the_recursive_signatures_are_those_that_reach_themselves(calls: Calls) -> None:
    """Task.recursive finds the call graph's cycles in one walk (strongly
    connected components): a signature is in it exactly when its method
    bodies lead back to it, as a walk from each signature finds."""
    problem = load_text(domain_of(calls), "(state (robot R))\n(goal (m0 R))\n")
    expected = {(f"m{i}", 1) for i in calls if reaches_itself(calls, i)}
    assert problem.task.recursive == expected


def test_a_hierarchy_deeper_than_the_recursion_limit_has_no_recursive_signature() -> None:
    """The walk keeps its own stack: 1,500 levels (Python's recursion limit
    is 1,000), then the last calling the first."""
    depth = 1500
    calls = {i: frozenset({i + 1}) for i in range(depth - 1)} | {depth - 1: frozenset()}
    problem = load_text(domain_of(calls), "(state (robot R))\n(goal (m0 R))\n")
    assert problem.task.recursive == frozenset()
    calls[depth - 1] = frozenset({0})
    problem = load_text(domain_of(calls), "(state (robot R))\n(goal (m0 R))\n")
    assert len(problem.task.recursive) == depth
