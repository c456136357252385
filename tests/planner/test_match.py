"""Matching preconditions against the state (cfgplan.planner.ground; 4.5, step 2b)."""

from __future__ import annotations

from cfgplan.planner.ground import bindings, candidates, why_not
from cfgplan.planner.task import Task
from tests.planner.problems import load_text

DOMAIN = """\
(make-functionality :name '(use ?r) :in '((img ?r)))
(make-functionality :name '(cam ?r) :out '((img ?r)))
(make-config-method :name '(go ?r)
  :precond '((robot ?r) (eval (> ?b 20)) (battery ?r ?b) (in ?r ?room) (not (broken ?r)))
  :channels '(((local ?r) ?a ?c (img ?r))) :body '((?a (cam ?r)) (?c (use ?r))))
"""


def task(facts: str) -> Task:
    return load_text(DOMAIN, f"(state {facts}) (goal (go A))").task


def test_bindings_in_state_order_one_per_distinct_fact() -> None:
    t = task("(robot A) (in A Room2) (battery A 50) (in A Room1) (in A Room2)")
    (method,) = t.methods[("go", 1)]
    found = list(bindings(t, method.tests, {"?r": "A"}))
    assert [b["?room"] for b in found] == ["Room2", "Room1"]  # the repeated fact once
    assert all(b["?b"] == "50" for b in found)


def test_eval_and_not_are_tested_once_their_variables_are_bound() -> None:
    t = task("(robot A) (battery A 5) (in A Room1)")
    (method,) = t.methods[("go", 1)]
    assert list(bindings(t, method.tests, {"?r": "A"})) == []
    kinds = [test.kind.value for test in method.tests]
    assert kinds == ["atom", "atom", "eval", "atom", "not"]  # the eval waits for ?b
    broken = task("(robot A) (battery A 50) (in A Room1) (broken A)")
    assert list(bindings(broken, method.tests, {"?r": "A"})) == []


def test_candidates_narrow_by_the_most_selective_argument() -> None:
    t = task("(robot A) (in A Room1) (in B Room1) (in C Room2)")
    assert candidates(t, ("in", "?r", "?room"), {"?r": "C"}) == (("in", "C", "Room2"),)
    assert candidates(t, ("in", "?r", "Room1")) == (("in", "A", "Room1"), ("in", "B", "Room1"))
    assert candidates(t, ("in", "?r", "?room")) == t.facts_by_predicate[("in", 2)]


def test_why_not_names_the_deepest_condition_and_its_bindings() -> None:
    t = task("(robot A) (battery A 50)")
    (method,) = t.methods[("go", 1)]
    failure = why_not(t, method.tests, {"?r": "A"}, method.params)
    assert failure.describe() == "no fact matches (in A ?room)"
    low = task("(robot A) (battery A 5) (in A Room1)")
    failure = why_not(low, method.tests, {"?r": "A"}, method.params)
    assert failure.describe() == "false: (> ?b 20) with ?b = 5"


def test_why_not_hints_at_a_case_slip() -> None:
    t = task("(robot a) (battery a 50) (in a Room1)")
    (method,) = t.methods[("go", 1)]
    failure = why_not(t, method.tests, {"?r": "A"}, method.params)
    # a newcomer read "no fact matches (the state spells PIPPI as Pippi; ...) (robot PIPPI)"
    assert failure.describe() == (
        "no fact matches (robot A): symbols are case-sensitive: did you mean a? "
        "the state has (robot a)"
    )
