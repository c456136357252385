"""The matching order of preconditions (cfgplan.planner.ground; 4.5, step 2b):
most selective atom first, the bindings still in the written order's
(6.3.2) — checked against a depth-first match of the tests as written."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from cfgplan.planner.ground import _walk, bindings, exists, join
from cfgplan.planner.task import Task
from cfgplan.planner.task import TestKind as Kind
from cfgplan.planner.unify import Bindings
from tests.planner.problems import PROPERTY, load_text

# weak.triangulate's precondition: three distinct observers in the target's room.
DOMAIN = """\
(make-functionality :name '(fix ?t ?a ?b ?c) :out '((pos ?t)))
(make-config-method :name '(locate ?t)
  :precond '((robot ?a) (robot ?b) (robot ?c) (in ?a ?x) (in ?b ?x) (in ?c ?x) (in ?t ?x)
             (eval (not (eql '?a '?b))) (eval (not (eql '?a '?c))) (eval (not (eql '?b '?c)))
             (not (busy ?b)))
  :body '((?f (fix ?t ?a ?b ?c))))
"""


def task(facts: list[str]) -> Task:
    return load_text(DOMAIN, f"(state {' '.join(facts)}) (goal (locate R0))").task


def as_written(t: Task, env: Bindings) -> list[Bindings]:
    """The bindings of a depth-first match of the tests in written order."""
    (method,) = t.methods[("locate", 1)]
    done = len(method.tests)
    return [b for index, b in _walk(t, method.tests, env) if index == done]


def test_the_target_s_room_is_matched_first_and_the_order_kept() -> None:
    robots = [f"R{i}" for i in range(9)]
    facts = [f"(robot {r})" for r in robots]
    facts += [f"(in {r} Room{i % 3})" for i, r in enumerate(reversed(robots))]
    facts += ["(busy R6)"]
    t = task(facts)
    (method,) = t.methods[("locate", 1)]
    plan = join(t, method.tests, frozenset({"?t"}))
    assert plan.reordered
    atoms = [test.pattern for test in plan.tests if test.kind is Kind.ATOM]
    assert atoms[0] == ("in", "?t", "?x")  # ?t is known: one fact
    found = list(bindings(t, method.tests, {"?t": "R0"}))
    assert found == as_written(t, {"?t": "R0"})
    # R0's room (Room2 from the end): R0, R3, R6; R6 is busy, so never ?b.
    assert [(b["?a"], b["?b"], b["?c"]) for b in found] == [
        ("R0", "R3", "R6"),
        ("R3", "R0", "R6"),
        ("R6", "R0", "R3"),
        ("R6", "R3", "R0"),
    ]


def test_an_order_already_best_is_kept_as_written() -> None:
    t = load_text(
        "(make-functionality :name '(f ?r) :out '((done ?r)))\n"
        "(make-config-method :name '(m ?r) :precond '((in ?r ?x) (camera ?x))"
        " :body '((?f (f ?r))))",
        "(state (in A Room1) (camera Room1)) (goal (m A))",
    ).task
    (method,) = t.methods[("m", 1)]
    assert not join(t, method.tests, frozenset({"?r"})).reordered


@PROPERTY
@given(
    rooms=st.lists(st.integers(0, 2), min_size=1, max_size=7),
    order=st.randoms(use_true_random=False),
    busy=st.sets(st.integers(0, 6)),
    repeats=st.integers(0, 3),
)
def test_bindings_are_those_of_the_written_order(
    rooms: list[int], order: object, busy: set[int], repeats: int
) -> None:
    facts = [f"(robot R{i})" for i in range(len(rooms))]
    facts += [f"(in R{i} Room{room})" for i, room in enumerate(rooms)]
    facts += [f"(busy R{i})" for i in sorted(busy)]
    order.shuffle(facts)  # type: ignore[attr-defined]
    facts += facts[:repeats]  # a fact written twice is one fact
    t = task(facts)
    env = {"?t": "R0"}
    tests = t.methods[("locate", 1)][0].tests
    found = list(bindings(t, tests, env))
    assert found == as_written(t, env)
    assert exists(t, tests, env) == bool(found)
