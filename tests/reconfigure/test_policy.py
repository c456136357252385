"""The reconfigurator's decisions (5.5, 7.2): fallbacks first, a safe stop, hysteresis."""

from __future__ import annotations

from cfgplan.configuration.cost import Weights
from cfgplan.planner import plan
from cfgplan.problem import Problem, load
from cfgplan.reconfigure.decision import Hysteresis
from cfgplan.reconfigure.fallbacks import Resource
from cfgplan.reconfigure.policy import TASKS_KEPT, Reconfigurator
from cfgplan.reconfigure.situation import Situation
from tests.backends.support import DOMAINS

STEP2 = (DOMAINS / "cross-door/domain.lisp", DOMAINS / "cross-door/state-6.2.2-step2.lisp")
CARRY = (DOMAINS / "carry-bar/domain.lisp", DOMAINS / "carry-bar/state-6.3.2.lisp")
COMPASS = Resource("functionality", instance=("compass", "Emil"), text="compass(Emil)")
LASER = Resource("functionality", instance=("laser", "Emil"), text="laser(Emil)")
PIPPI = Resource("robot", robot="Pippi", text="Pippi")


def _start(
    files: tuple[object, object], weights: Weights | None = None
) -> tuple[Problem, Reconfigurator]:
    problem = load(*files, None, weights)  # type: ignore[arg-type]
    configs, _ = plan(problem.task, problem.goal_call)
    return problem, Reconfigurator(problem.task, problem.domain, problem.goal_call, configs[0])


def test_a_failure_uses_the_fallback_computed_ahead_of_time() -> None:
    _, r = _start(STEP2)
    while r.prepare():
        pass
    decision = r.failed(COMPASS)
    assert (decision.action, decision.source, decision.id) == ("switch", "fallback", 1)
    assert decision.config is not None and decision.config.cost == 47
    assert decision.withdrawn == (("compass", "Emil"),)
    kept = {f.key: f.label for f in decision.change.kept}  # type: ignore[union-attr]
    before = {f.key: f.label for f in decision.previous.functionalities}  # type: ignore[union-attr]
    assert all(before[k] == label for k, label in kept.items())  # running labels kept
    fresh = [f.label for f in decision.change.started]  # type: ignore[union-attr]
    assert fresh == ["F15", "F16", "F17", "F18"]  # never used before in the run


def test_without_fallbacks_it_searches_the_derived_task() -> None:
    _, r = _start(STEP2)
    decision = r.failed(COMPASS)
    assert decision.source == "search" and decision.config is not None
    assert decision.config.cost == 47


def test_a_failure_of_something_unused_changes_the_state_only() -> None:
    _, r = _start(STEP2)
    r.failed(COMPASS)
    again = r.failed(Resource("functionality", instance=("compass", "Pippi"), text="x"))
    assert again.action == "stay" and again.withdrawn == (("compass", "Pippi"),)
    assert ("compass", "Pippi") in r.situation.failed


def test_nothing_admissible_stops_with_the_planners_explanation() -> None:
    _, r = _start(STEP2)
    r.failed(COMPASS)
    decision = r.failed(PIPPI)
    assert (decision.action, decision.config, r.running) == ("stop", None, None)
    assert decision.why[0] == "no admissible configuration for do-cross-door(Emil, Door1):"
    assert "(not (eql (quote ?r) (quote ?rh1))) with ?r = Emil, ?rh1 = Emil" in decision.why[1]
    assert {f.name for f in decision.change.stopped} >= {"cross-door"}  # type: ignore[union-attr]
    back = r.recovered(PIPPI)
    assert back.action == "switch" and back.config is not None and back.config.cost == 47


def test_a_small_gain_does_not_switch_back() -> None:
    """The compass returns: 44 is 3 cheaper than 47, under the 10 % margin."""
    _, r = _start(STEP2)
    r.failed(COMPASS)
    assert r.recovered(COMPASS).action == "stay"
    assert r.running is not None and r.running.cost == 47
    _problem, eager = _start(STEP2)
    eager.hysteresis = Hysteresis(margin=0.0)  # any gain of at least 1 is worth it
    eager.failed(COMPASS)
    back = eager.recovered(COMPASS)
    assert back.action == "switch" and back.config is not None and back.config.cost == 44


def test_a_recovery_that_causes_no_switch_finds_the_fallbacks_ready() -> None:
    """Fallbacks are kept by situation: a recovery that switched nothing (a
    small gain, a robot back that nothing needs) left the new situation with
    none, and the next failure was planned by search (38-154 ms at 40-50
    robots instead of 0.03 ms); then they were queued again, but a failure
    before they were computed was still searched. Now, while the compass is
    out, the situation its return leads to is planned ahead: 47 would stay
    there, so its fallbacks there are computed too, and ready the moment
    the compass returns."""
    _, r = _start(STEP2)
    while r.prepare():
        pass
    assert r.failed(COMPASS).source == "fallback"
    while r.prepare():
        pass
    assert r.recovered(COMPASS).action == "stay"
    assert r.next_fallback() is None  # nothing left to compute: ready
    running = r.running
    assert running is not None
    camera = next(f for f in running.functionalities if f.name == "camera")
    used = Resource("functionality", instance=(camera.name, *camera.args), text="camera")
    assert r.failed(used).source == "fallback"


Decided = tuple[str, object]
"""A decision's action and what it runs (its identity and cost)."""


def _decisions(
    files: tuple[object, object], ahead: bool, *changes: tuple[str, Resource]
) -> list[Decided]:
    """The decisions after each change, with every fallback and look ahead
    computed before it (``ahead``) or none."""
    _, r = _start(files, Weights(reliability=10))
    out: list[Decided] = []
    for what, resource in changes:
        while ahead and r.prepare():
            pass
        decision = r.failed(resource) if what == "fail" else r.recovered(resource)
        config = decision.config
        out.append((decision.action, None if config is None else (config.identity(), config.cost)))
    return out


def test_looking_ahead_changes_no_decision() -> None:
    """The cheapest configuration of a situation a recovery returns to,
    planned ahead, is what the recovery decides by: the decisions are those
    of searching at each change (carry-bar 6.3.2 with reliability weights:
    the laser back is worth the switch to 33 once, not after a second
    failure; cross-door: the compass back is not worth it)."""
    carry = [("fail", LASER), ("recover", LASER), ("fail", LASER), ("recover", LASER)]
    assert _decisions(CARRY, True, *carry) == _decisions(CARRY, False, *carry)
    assert [action for action, _ in _decisions(CARRY, True, *carry)] == [
        "switch",
        "switch",
        "switch",
        "stay",
    ]
    step2 = [("fail", COMPASS), ("recover", COMPASS), ("fail", PIPPI), ("recover", PIPPI)]
    assert _decisions(STEP2, True, *step2) == _decisions(STEP2, False, *step2)


def test_the_laser_returning_is_worth_the_switch_back_to_33() -> None:
    _, r = _start(CARRY)
    assert r.failed(LASER).config.cost == 45  # type: ignore[union-attr]
    back = r.recovered(LASER)
    assert back.action == "switch" and back.config is not None and back.config.cost == 33


def test_failures_lower_reliability_so_a_flaky_laser_is_not_chosen_back() -> None:
    """7.2: with reliability=10 each failure of the laser adds 10·ln 2 to the
    configurations that use it; after two failures 33 + 13.9 > 45."""
    _, r = _start(CARRY, Weights(reliability=10))
    r.failed(LASER)
    first = r.recovered(LASER)
    assert first.action == "switch" and first.config is not None
    assert round(first.config.cost, 2) == 39.93  # 33 + 10·ln 2
    r.failed(LASER)
    assert r.recovered(LASER).action == "stay"
    assert r.running is not None and r.running.cost == 45


def test_an_operator_update_that_removes_what_runs_forces_a_switch() -> None:
    _, r = _start(STEP2)
    decision = r.updated((), (("compass", "Pippi"),))
    assert decision.action == "switch" and decision.config is not None
    assert decision.config.cost == 47
    same = r.updated((("door", "Door2"),), ())
    assert same.action == "stay"


def test_achieved_plays_the_configuration_out_and_applies_postconditions() -> None:
    _problem, r = _start(STEP2)
    assert r.running is not None
    r.running = r.running.model_copy(
        update={"postconditions": ("(in Emil Room2)", "(not (in Emil Room1))")}
    )
    decision = r.achieved()
    assert decision.action == "stop" and r.running is None
    assert ("in", "Emil", "Room2") in r.situation.asserted
    assert ("in", "Emil", "Room1") in r.situation.retracted


def test_breaks_knows_functionalities_robots_and_media() -> None:
    _, r = _start(STEP2)
    assert r.running is not None
    assert COMPASS.fail(Situation()).breaks(r.running)
    assert PIPPI.fail(Situation()).breaks(r.running)
    assert not Resource("medium", medium=0, text="m").fail(Situation()).breaks(r.running)
    r.running = None  # nothing runs: nothing to leave
    assert r.failed(COMPASS).action == "stay"


def test_parts_give_every_robot_of_both_configurations_a_part() -> None:
    _, r = _start(STEP2)
    r.failed(COMPASS)
    decision = r.failed(PIPPI)
    parts = r.parts(decision.previous)
    assert sorted(parts) == ["Emil", "Pippi"]
    assert all(p.calls == () and p.channels == () for p in parts.values())


def test_fallbacks_ahead_are_computed_on_a_thread_and_used() -> None:
    from cfgplan.reconfigure.ahead import Ahead

    _, r = _start(STEP2)
    ahead = Ahead(r)
    try:
        assert ahead.idle.wait(60), "the fallbacks were not computed in a minute"
    finally:
        ahead.close()
    assert r.next_fallback() is None  # nothing left to compute
    decision = r.failed(COMPASS)
    assert decision.source == "fallback" and decision.config is not None
    assert decision.config.cost == 47


def test_a_search_cut_by_its_time_limit_keeps_no_fallback() -> None:
    _, r = _start(STEP2)
    assert r.running is not None
    r.compute(r.situation, r.running, COMPASS, time_limit=0.0)  # cut: a dive's guess
    assert r.fallback(r.situation, COMPASS) == (False, None)
    r.compute(r.situation, r.running, COMPASS)
    known, found = r.fallback(r.situation, COMPASS)
    assert known and found is not None and found.cost == 47


def test_it_keeps_the_derived_tasks_of_the_last_few_situations_only() -> None:
    """A long run meets ever new situations (here reliabilities lowered step by
    step); each derived task keeps its grounding and bounds once planned on, so
    only the :data:`TASKS_KEPT` most recently used are kept."""
    _, r = _start(STEP2)
    situations = [r.situation.with_reliability(("compass", "Emil"), 0.5**n) for n in range(20)]
    tasks = [r.derived(s) for s in situations]
    assert len({id(t) for t in tasks}) == 20
    assert r.derived(situations[-1]) is tasks[-1]  # among the last used: kept
    assert r.derived(situations[-TASKS_KEPT]) is tasks[-TASKS_KEPT]
    assert r.derived(situations[0]) is not tasks[0]  # dropped, derived again
    assert len(r._tasks) == TASKS_KEPT


def test_it_keeps_the_fallbacks_of_the_last_few_situations_only() -> None:
    """Fallbacks are looked up in the situation they were computed in: those of
    situations left long ago are forgotten, :data:`TASKS_KEPT` situations are
    kept (a long run would otherwise keep one set per situation it met)."""
    _, r = _start(STEP2)
    assert r.running is not None
    situations = [r.situation.with_reliability(("compass", "Emil"), 0.5**n) for n in range(12)]
    for situation in situations:
        r.compute(situation, r.running, COMPASS)
    assert len(r._fallbacks) == TASKS_KEPT
    known, found = r.fallback(situations[-1], COMPASS)
    assert known and found is not None and found.cost == 47
    assert r.fallback(situations[-TASKS_KEPT], COMPASS)[0]
    assert r.fallback(situations[-TASKS_KEPT - 1], COMPASS) == (False, None)


def test_after_a_rollback_a_broken_configuration_is_left_at_the_next_chance() -> None:
    """The switch away from the failed compass could not be deployed, so the
    society still runs the configuration that uses it: the next change (here
    an operator's update that changes nothing) must not keep it as valid,
    whatever the hysteresis says of the costs (44 against 47)."""
    _, r = _start(STEP2)
    decision = r.failed(COMPASS)
    assert decision.config is not None and decision.config.cost == 47
    r.rollback(decision.previous)
    assert r.running is decision.previous and r.situation.breaks(r.running)  # type: ignore[arg-type]
    after = r.updated((), ())
    assert after.action == "switch" and after.config is not None and after.config.cost == 47
    assert not r.situation.breaks(after.config)


def test_after_a_rollback_a_failure_of_something_unused_still_leaves_it() -> None:
    """Rolled back to the configuration with the failed compass, the society
    meets another failure, of something that configuration does not use: it
    must not stay on it."""
    _, r = _start(STEP2)
    decision = r.failed(COMPASS)
    r.rollback(decision.previous)
    assert r.running is not None and not LASER.fail(Situation()).breaks(r.running)
    after = r.failed(LASER)
    assert after.action in ("switch", "stop")
    assert after.config is None or not r.situation.breaks(after.config)


SEQUENCE = (
    DOMAINS / "cross-door/domain-steps.lisp",
    DOMAINS / "cross-door/state-6.2.2-sequence.lisp",
)


def test_a_step_rolled_back_to_after_it_was_accomplished_serves_no_goal() -> None:
    """6.2.2 as a sequence: Pippi has crossed, the switch to Emil's crossing
    could not be deployed, so the society runs Pippi's crossing again. A
    failure of a part only Emil's crossing uses does not break it, yet it
    must not stay: its task is accomplished. It switches to the next step's
    best without that part, or stops when the next step has none."""
    problem = load(*SEQUENCE, None, None)  # type: ignore[arg-type]
    first, second = problem.goal_calls
    configs, _ = plan(problem.task, first)
    helped = ("measure-robot-orient-compass", "Pippi", "Emil")  # Pippi's compass for Emil
    door = ("measure-door", "Pippi", "Door1")  # Pippi's camera sees the door for Emil
    decisions = []
    for part in (helped, door):
        r = Reconfigurator(problem.task, problem.domain, first, configs[0], goals=(second,))
        step = r.achieved()
        assert step.action == "switch" and step.previous is configs[0]
        r.rollback(step.previous)  # not deployed: Pippi's crossing runs again
        assert part not in {(f.name, *f.args) for f in configs[0].functionalities}
        decisions.append(r.failed(Resource("functionality", instance=part, text=str(part))))
    switched, stopped = decisions
    assert switched.action == "switch" and switched.config is not None
    running = {(f.name, *f.args) for f in switched.config.functionalities}
    assert ("cross-door", "Emil", "Door1") in running and helped not in running
    assert switched.config.cost == 47
    assert stopped.action == "stop" and stopped.config is None
