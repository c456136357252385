"""Who coordinates, told without planning (cfgplan.reconfigure.owner, 5.5): a
robot that is not the goal's coordinator follows it and loads no search
(``cfgplan run --robot``), so that a society started together does not run
one planner per robot."""

from __future__ import annotations

from pathlib import Path

import pytest

from benchmarks.fault_conditions import DOCKING_IMPL
from cfgplan.problem import Problem, load
from cfgplan.reconfigure.owner import certain_agents, coordinator_of, never_coordinates, owner
from cfgplan.runtime.registry import Registry
from tests.backends.support import DOMAINS, ROOT
from tests.runtime.netutil import endpoint, free_port, hermetic_config
from tests.runtime.test_imports import loading

DOCKING = DOMAINS / "docking" / "domain.lisp"
CROSS_DOOR = (DOMAINS / "cross-door/domain.lisp", DOMAINS / "cross-door/state-6.2.2-step1.lisp")
DOCKING_STATE = """(state (robot Vacu) (station Charger1) (in Vacu Kitchen) (in Charger1 Kitchen)
  (robot H1) (laser H1) (in H1 Kitchen) (robot H2) (laser H2) (in H2 Kitchen))
(goal (do-dock Vacu Charger1))
"""

RELAYED = """
(make-functionality :name '(sense ?r) :precond '((sensor ?r)) :out '((data ?r)))
(make-functionality :name '(relay ?h ?r) :in '((data ?h)) :out '((report ?r)))
(make-functionality :name '(act ?r) :in '((report ?r)))
;; ?r acts on its own data, or on what ?h senses
(make-config-method :name '(do-task ?r)
  :precond '((robot ?r) (sensor ?r))
  :channels '(((local ?r) ?s ?l (data ?r)) ((local ?r) ?l ?a (report ?r)))
  :body '((?s (sense ?r)) (?l (relay ?r ?r)) (?a (act ?r))))
(make-config-method :name '(do-task ?r)
  :precond '((robot ?r) (robot ?h) (sensor ?h))
  :channels '(((local ?h) ?s ?l (data ?h)) ((global ?h ?r) ?l ?a (report ?r)))
  :body '((?s (sense ?h)) (?l (relay ?h ?r)) (?a (act ?r))))
;; a goal on two robots whose method places nothing itself
(make-config-method :name '(do-both ?a ?b)
  :precond '((robot ?a) (robot ?b))
  :body '((?x (do-task ?a)) (?y (do-task ?b))))
"""
RELAYED_STATE = """(state (robot Ada) (robot Bo) (sensor Bo) (robot Cy) (sensor Cy))
(goal (do-task Ada))
"""


def _problem(tmp_path: Path, domain: Path | str, state: str, goal: str | None = None) -> Problem:
    if not isinstance(domain, Path):
        path = tmp_path / "domain.lisp"
        path.write_text(domain, encoding="utf-8")
        domain = path
    written = tmp_path / "state.lisp"
    written.write_text(state, encoding="utf-8")
    return load(domain, written, goal)


def test_the_docking_robot_coordinates_whatever_helper_lends_its_laser(tmp_path: Path) -> None:
    """Every version of do-dock runs dock(?r, ?s) on the robot that docks:
    whatever helper lends its laser, Vacu is the coordinator."""
    problem = _problem(tmp_path, DOCKING, DOCKING_STATE)
    assert certain_agents(problem.task, problem.goal_call) == {"Vacu"}
    assert owner(problem.task, problem.goal_call) == "Vacu"


def test_the_owner_told_without_planning_is_the_planned_coordinator() -> None:
    """Cross-door 6.2.2: Pippi, in each configuration planned (44 and 47)."""
    from cfgplan.planner import plan

    problem = load(*CROSS_DOOR)
    configs, _ = plan(problem.task, problem.goal_call, limit=8)
    assert len(configs) == 2
    told = owner(problem.task, problem.goal_call)
    assert told == "Pippi"
    assert {coordinator_of(problem.goal_call, c) for c in configs} == {told}


SEQUENCE = (
    DOMAINS / "cross-door/domain-steps.lisp",
    DOMAINS / "cross-door/state-6.2.2-sequence.lisp",
)


def test_who_never_coordinates(tmp_path: Path) -> None:
    """A docking helper never does; Vacu does. In the 6.2.2 sequence Pippi
    coordinates and Emil, whom the second goal names, may take over: each
    plans at start."""
    docking = _problem(tmp_path, DOCKING, DOCKING_STATE)
    goals = docking.goal_calls
    assert [r for r in ("Vacu", "H1", "H2") if never_coordinates(docking.task, goals, r)] == [
        "H1",
        "H2",
    ]
    sequence = load(*SEQUENCE)
    assert owner(sequence.task, sequence.goal_call) == "Pippi"
    assert not never_coordinates(sequence.task, sequence.goal_calls, "Emil")
    assert not never_coordinates(sequence.task, sequence.goal_calls, "Pippi")


def test_where_the_goals_method_does_not_tell_every_robot_plans(tmp_path: Path) -> None:
    """do-task's two versions both run act on the goal's robot: Ada. do-both
    places only through sub-methods, whose robots the plan chooses; do-for
    runs act on its second argument for sure but its first, which the
    coordinator would be if a configuration runs on it, only maybe."""
    problem = _problem(tmp_path, RELAYED, RELAYED_STATE)
    assert certain_agents(problem.task, problem.goal_call) == {"Ada"}
    assert owner(problem.task, problem.goal_call) == "Ada"
    both = _problem(tmp_path, RELAYED, RELAYED_STATE, "(do-both Bo Cy)")
    assert certain_agents(both.task, both.goal_call) == frozenset()
    assert owner(both.task, both.goal_call) is None
    assert not never_coordinates(both.task, both.goal_calls, "Ada")  # it may: it plans
    domain = (
        RELAYED
        + """
(make-config-method :name '(do-for ?h ?r)
  :precond '((robot ?h) (robot ?r))
  :body '((?t (do-task ?h)) (?a (act ?r))))
"""
    )
    then = _problem(tmp_path, domain, RELAYED_STATE, "(do-for Bo Ada)")
    assert certain_agents(then.task, then.goal_call) == {"Ada"}
    assert owner(then.task, then.goal_call) is None


def test_implementations_that_serve_every_functionality() -> None:
    """A follower plans nothing only if any part it may be sent can run here."""
    problem = load(*CROSS_DOOR)
    every = [(n, a - 1, len(s.inputs)) for (n, a), s in problem.task.functionalities.items()]
    registry = Registry.load(ROOT / "examples" / "cross-door" / "impl.py")
    assert registry.serves(every)
    assert not registry.serves([*every, ("teleport", 1, 0)])
    name, objects, inputs = every[0]
    assert not registry.serves([(name, objects + 2, inputs)])  # cannot take the arguments


def _loaded(tmp_path: Path, robot: str) -> tuple[list[str], str]:
    """What ``cfgplan run --robot ROBOT`` of the docking society of three loads
    (a peer alone on a free port, for half a second), and its first line."""
    state, impl = tmp_path / "state.lisp", tmp_path / "impl.py"
    state.write_text(DOCKING_STATE, encoding="utf-8")
    impl.write_text(DOCKING_IMPL, encoding="utf-8")
    args = ["run", str(DOCKING), str(state), "--impl", str(impl), "--robot", robot,
            "--listen", endpoint(free_port()), "--zenoh-config", str(hermetic_config(tmp_path)),
            "--society", f"owner-{robot.lower()}", "--duration", "0.5"]  # fmt: skip
    modules, printed = loading(args, tmp_path)
    return modules, printed.splitlines()[0]


SEARCH = ("cfgplan.planner.plan", "cfgplan.planner.search", "cfgplan.reconfigure.policy")


@pytest.mark.slow
def test_a_helper_follows_without_loading_the_planner(tmp_path: Path) -> None:
    """H1 cannot coordinate do-dock(Vacu, Charger1): it plans nothing, loads no
    search and says it follows; Vacu, the coordinator, plans (the check can fail)."""
    modules, first = _loaded(tmp_path, "H1")
    assert [m for m in SEARCH if m in modules] == []
    assert first == "Following the coordinator, for do-dock(Vacu, Charger1): H1; 0.5 s"
    modules, first = _loaded(tmp_path, "Vacu")
    assert [m for m in SEARCH if m in modules] == list(SEARCH)
    assert first.startswith("Configuration rank 1, cost ")
