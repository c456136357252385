"""Planner bugs found by the property tests or by users, kept as small reproducers."""

from __future__ import annotations

import pytest

from cfgplan.configuration.admissible import problems
from cfgplan.configuration.cost import Weights
from cfgplan.planner import plan
from cfgplan.planner.report import Condition
from cfgplan.problem import Problem, load
from tests.backends.support import ROOT
from tests.planner.oracle import depth_first
from tests.planner.problems import load_text, run

REUSED_SENSOR = """\
(make-functionality :name '(sens ?r) :out '((d ?r)))
(make-functionality :name '(p1 ?h ?r) :in '((d ?h)) :out '((need1 ?r)))
(make-functionality :name '(p2 ?h ?r) :in '((d ?h)) :out '((need2 ?r)))
(make-functionality :name '(act ?r) :in '((need1 ?r) (need2 ?r)))
(make-config-method :name '(get-need1 ?h ?r)
  :out '((?f0 (need1 ?r)))
  :channels '(((local ?h) ?f1 ?f0 (d ?h)))
  :body '((?f0 (p1 ?h ?r)) (?f1 (sens ?h))))
(make-config-method :name '(get-need2 ?h ?r)
  :out '((?f0 (need2 ?r)))
  :channels '(((local ?h) ?f1 ?f0 (d ?h)))
  :body '((?f0 (p2 ?h ?r)) (?f1 (sens ?h))))
(make-config-method :name '(do-task ?r)
  :channels '(((local ?r) ?f1 ?f0 (need1 ?r)) ((local ?r) ?f2 ?f0 (need2 ?r)))
  :body '((?f0 (act ?r)) (?f1 (get-need1 ?r ?r)) (?f2 (get-need2 ?r ?r))))
"""


def test_reused_functionality_is_costed_once() -> None:
    """sens(R1) is placed by get-need1 and reused by get-need2 (4.5, step 2a):
    1 robot, 4 functionalities, 4 local channels: 10 + 4 + 4 = 18. Found by
    the properties above: a planner that counts the channels already attached
    to a reused functionality a second time says 19."""
    problem = load_text(REUSED_SENSOR, "(state robot(R1))\n(goal (do-task R1))\n")
    configs = run(problem, distinct=False)
    assert [c.cost for c in configs] == [18]
    assert problems(configs[0], problem.domain, problem.state) == []
    assert [(c.cost, c.identity()) for c in configs] == depth_first(problem, Weights())


CONSTANT_IN_A_METHOD_NAME = """\
(make-functionality :name '(sens ?r) :out '((d ?r)))
(make-functionality :name '(fancy ?r) :out '((d ?r)))
(make-functionality :name '(act ?r) :in '((d ?r)))
(make-config-method :name '(get ?r Fancy) :out '((?f (d ?r))) :body '((?f (fancy ?r))))
(make-config-method :name '(get ?r Plain) :out '((?f (d ?r))) :body '((?f (sens ?r))))
(make-config-method :name '(do-task ?r)
  :channels '(((local ?r) ?f1 ?f0 (d ?r)))
  :body '((?f0 (act ?r)) (?f1 (get ?r Plain))))
"""


def test_planner_bug_constant_in_a_method_name() -> None:
    problem = load_text(CONSTANT_IN_A_METHOD_NAME, "(state robot(R1))\n(goal (do-task R1))\n")
    configs = run(problem, distinct=False)
    assert [(c.cost, c.identity()) for c in configs] == depth_first(problem, Weights())


def test_depth_first_ignores_versions_whose_name_does_not_match() -> None:
    problem = load_text(CONSTANT_IN_A_METHOD_NAME, "(state robot(R1))\n(goal (do-task R1))\n")
    [(cost, (functionalities, _, _))] = depth_first(problem, Weights())
    assert cost == 13
    assert functionalities == {("act", "R1"), ("sens", "R1")}


# -- a channel from a label to itself ----------------------------------------------

SELF_LOOP = """\
(make-functionality :name '(s ?r) :out '((d ?r)))
(make-functionality :name '(flt ?r) :in '((d ?r)) :out '((d ?r)))
(make-functionality :name '(act ?r) :in '((d ?r)))
(make-config-method :name '(m ?r) :in '((?g1 (d ?r))) :out '((?g1 (d ?r))) :body '((?g1 (flt ?r))))
(make-config-method :name '(do ?r)
  :channels '(((local ?r) ?f0 ?f1 (d ?r)) ((local ?r) ?f1 ?f1 (d ?r)) ((local ?r) ?f1 ?f2 (d ?r)))
  :body '((?f0 (s ?r)) (?f1 (m ?r)) (?f2 (act ?r))))
"""


def test_channel_from_a_method_to_itself_is_rewired_at_both_ends() -> None:
    """4.5 step 3d re-wires a channel at the expanded instance through :out at
    its sending end and :in at its receiving end; with both ends there, both
    move: flt(r1) feeds itself, a cycle (5.1), so the only derivation is
    rejected and the report names the functionality on the cycle. (Before:
    only the sending end moved, and building the result raised KeyError.)"""
    problem = load_text(SELF_LOOP, "(state (robot r1)) (goal (do r1))")
    configs, search = plan(problem.task, problem.goal_call, limit=None, distinct=False)
    assert configs == []
    (dead,) = search.report.rejected
    assert dead.condition is Condition.CYCLE
    assert dead.reason == "its channels form a cycle through F5 flt(r1)"
    assert depth_first(problem, Weights()) == []


# -- outputs bound by a functionality's own preconditions ------------------------

LOCALIZER = """\
(make-functionality :name '(loc ?r) :precond '((in ?r ?room)) :out '((pos ?r ?room)))
(make-functionality :name '(act ?r ?room) :in '((pos ?r ?room)))
(make-config-method :name '(do ?r ?room)
  :channels '(((local ?r) ?f1 ?f2 (pos ?r ?room)))
  :body '((?f1 (loc ?r)) (?f2 (act ?r ?room))))
"""


@pytest.mark.parametrize("facts", ["(in r1 room1) (in r1 room2)", "(in r1 room2) (in r1 room1)"])
def test_outputs_follow_the_binding_of_the_preconditions(facts: str) -> None:
    """loc(r1) is placed once per binding of (in ?r ?room); the one with
    ?room = room2 produces (pos r1 room2). Before: its outputs were cached from
    the first binding only, so with room1 first nothing was admissible."""
    problem = load_text(LOCALIZER, f"(state (robot r1) {facts}) (goal (do r1 room2))")
    configs = run(problem, distinct=False)
    assert [c.cost for c in configs] == [10 + 2 + 1]
    assert problems(configs[0], problem.domain, problem.state) == []
    assert [(c.cost, c.identity()) for c in configs] == depth_first(problem, Weights())


# -- the state is a set of facts; evals wait for their variables -------------------

CAMERA = """\
(make-functionality :name '(cam ?r) :precond '((camera ?r)) :out '((img ?r)))
(make-functionality :name '(use ?r) :in '((img ?r)))
(make-config-method :name '(go ?r)
  :precond '((eval (> ?b 20)) (battery ?r ?b))
  :channels '(((local ?r) ?a ?b (img ?r))) :body '((?a (cam ?r)) (?b (use ?r))))
"""


def test_a_fact_written_twice_is_one_fact() -> None:
    """(camera r1) twice is one fact, one binding, one derivation (the world
    state is a set, 4.4; step 2a has no backtrack point for a functionality)."""
    state = "(state (robot r1) (camera r1) (camera r1) (battery r1 50) (battery r1 50))"
    problem = load_text(CAMERA, state + " (goal (go r1))")
    assert problem.task.facts.count(("camera", "r1")) == 1
    assert len(run(problem, distinct=False)) == 1


def test_an_eval_before_the_atom_binding_its_variable_waits_for_it() -> None:
    """(eval (> ?b 20)) is written before (battery ?r ?b): it is tested once
    ?b is bound, so a battery of 50 passes and one of 5 does not."""
    full = load_text(CAMERA, "(state (robot r1) (camera r1) (battery r1 50)) (goal (go r1))")
    assert len(run(full, distinct=True)) == 1
    low = load_text(CAMERA, "(state (robot r1) (camera r1) (battery r1 5)) (goal (go r1))")
    assert run(low, distinct=True) == []


K_NOT_PREFIX = ROOT / "tests" / "data" / "repros" / "k-not-prefix-of-all"


def test_k_best_is_a_prefix_of_all_when_the_partition_bound_was_given_up() -> None:
    """The repro ../shared/repros/k-not-prefix-of-all: ``-k 5`` listed as
    rank 5 the labels of derivation 7 while ``--all`` listed derivation 5's.
    Two partial configurations of one canonical form had been taken out of
    the thesis's depth-first order, and the search started over (without the
    parents' splits) only when a split had lifted a priority; here the
    partition bound had been given up before it lifted anything. Every k is
    now a prefix of all, labels and derivation numbers included, and all is
    the depth-first oracle's list without repeats."""

    def fresh() -> Problem:  # each search from a task read afresh, as the CLI's
        return load(K_NOT_PREFIX / "labels-domain.lisp", K_NOT_PREFIX / "labels-state.lisp")

    everything = run(fresh(), distinct=True)
    assert len(everything) == 6
    for k in range(1, len(everything) + 2):
        assert run(fresh(), limit=k, distinct=True) == everything[:k], k
    problem = fresh()
    oracle: list[tuple[float, object]] = []
    for cost, identity in depth_first(problem, Weights()):
        if identity not in [i for _, i in oracle]:
            oracle.append((cost, identity))
    assert [(c.cost, c.identity()) for c in everything] == oracle
