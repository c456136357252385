"""Deriving the task of a changed situation without reading the domain again (5.5, 7.2)."""

from __future__ import annotations

from cfgplan.planner import plan
from cfgplan.planner.explain import explain
from cfgplan.problem import load
from cfgplan.reconfigure.situation import LOST, OUT_OF_SERVICE, Situation, derive
from tests.backends.support import DOMAINS

CROSS2 = (DOMAINS / "cross-door" / "domain.lisp", DOMAINS / "cross-door" / "state-6.2.2-step2.lisp")
CARRY = (DOMAINS / "carry-bar" / "domain.lisp", DOMAINS / "carry-bar" / "state-6.3.2.lisp")
CARRY_FAILED = (
    DOMAINS / "carry-bar" / "domain.lisp",
    DOMAINS / "carry-bar" / "state-6.3.2-laser-failed.lisp",
)


def test_nothing_changed_is_the_same_task() -> None:
    task = load(*CROSS2).task
    assert derive(task, Situation()) is task
    assert not Situation()


def test_compass_failure_gives_the_camera_configuration_of_step_3() -> None:
    """6.2.2 step 3: with Emil's compass failed only the cost-47 configuration
    of Fig. 6.4 (bottom) remains, and it uses no compass."""
    problem = load(*CROSS2)
    derived = derive(problem.task, Situation().failing(("compass", "Emil")))
    configs, _ = plan(derived, problem.goal_call, limit=None)
    assert [c.cost for c in configs] == [47]
    assert not any(f.name == "compass" for f in configs[0].functionalities)
    assert ("compass", "Emil") not in derived.facts
    assert (OUT_OF_SERVICE, "compass", "Emil") in derived.facts


def test_laser_failure_equals_the_thesis_state_without_laser() -> None:
    """6.3.2: the derived task plans exactly what the state the thesis's
    operator wrote by hand (laser removed) plans: the two 45 configurations."""
    problem = load(*CARRY)
    derived = derive(problem.task, Situation().failing(("laser", "Emil")))
    mine, _ = plan(derived, problem.goal_call, limit=None)
    by_hand = load(*CARRY_FAILED)
    theirs, _ = plan(by_hand.task, by_hand.goal_call, limit=None)
    assert [c.identity() for c in mine] == [c.identity() for c in theirs]
    assert [c.cost for c in mine] == [45, 45]


def test_a_failed_computation_is_kept_out_and_explained() -> None:
    """A failed transform-info withdraws no fact but is never placed again;
    nothing else can do its job, and the planner says why."""
    problem = load(*CROSS2)
    derived = derive(
        problem.task, Situation().failing(("transform-info", "Pippi", "Emil", "Door1"))
    )
    configs, search = plan(derived, problem.goal_call)
    assert configs == []
    text = "\n".join(explain(search.report, "do-cross-door(Emil, Door1)"))
    assert "(:out-of-service transform-info Pippi Emil Door1)" in text


def test_a_lost_robot_takes_everything_on_it() -> None:
    problem = load(*CROSS2)
    derived = derive(problem.task, Situation().losing("Pippi"))
    assert not any("Pippi" in f for f in derived.facts if f[0] != LOST)
    configs, search = plan(derived, problem.goal_call)
    assert configs == []
    text = "\n".join(explain(search.report, "do-cross-door(Emil, Door1)"))
    assert "(not (eql (quote ?r) (quote ?rh1))) with ?r = Emil, ?rh1 = Emil" in text


def test_recovery_and_return_undo_failure_and_loss() -> None:
    s = Situation().failing(("compass", "Emil")).losing("Pippi")
    assert s.recovered(("compass", "Emil")).returning("Pippi") == Situation()


def test_operator_updates_add_and_remove_facts() -> None:
    problem = load(*CROSS2)
    s = Situation().updated(remove=[("compass", "Pippi")])
    derived = derive(problem.task, s)
    assert ("compass", "Pippi") not in derived.facts
    configs, _ = plan(derived, problem.goal_call)
    assert configs[0].cost == 47
    back = s.updated(add=[("compass", "Pippi")])
    assert back.retracted == () and ("compass", "Pippi") in derive(problem.task, back).facts


def test_lowered_reliability_reaches_the_cost() -> None:
    """7.2: failures seen at run time lower an instance's reliability; with
    reliability=W the cost of a configuration using it rises by W·(−ln p)."""
    from cfgplan.configuration.cost import Weights

    problem = load(*CROSS2, None, Weights(reliability=10))
    derived = derive(problem.task, Situation().with_reliability(("compass", "Emil"), 0.5))
    configs, _ = plan(derived, problem.goal_call, limit=None)
    costs = sorted(round(c.cost, 4) for c in configs)
    assert costs == [47, round(44 + 10 * 0.6931471805599453, 4)]
    assert configs[0].cost == 47
