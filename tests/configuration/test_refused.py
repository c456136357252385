"""Once planner bugs, now refused by both the planner and the admissibility
checker (4.6): a channel into a functionality that does not consume it, and
a call that does not match a repeated variable of its schema."""

from __future__ import annotations

from pathlib import Path

from cfgplan.configuration.admissible import problems
from cfgplan.configuration.model import Channel, Configuration, FunctionalityInstance
from cfgplan.planner import plan
from cfgplan.problem import Problem, load

# The static checker only warns about both domains below, so they reach the planner.

UNCONSUMED_DOMAIN = """\
(make-functionality :name '(sens ?r) :out '((d ?r)))
(make-functionality :name '(act ?r) :in '((d ?r)))
(make-config-method :name '(do-task ?r)
  :precond '((robot ?h) (eval (not (eql (quote ?h) (quote ?r)))))
  :channels '(((local ?r) ?f1 ?f0 (d ?r))
              ((global ?h ?r) ?f2 ?f0 (d ?h)))
  :body '((?f0 (act ?r)) (?f1 (sens ?r)) (?f2 (sens ?h))))
"""

REPEATED_VARIABLE_DOMAIN = """\
(make-functionality :name '(sens ?r ?r) :out '((d ?r)))
(make-functionality :name '(act ?r) :in '((d ?r)))
(make-config-method :name '(do-task ?r)
  :precond '((robot ?h))
  :channels '(((global ?h ?r) ?f1 ?f0 (d ?r)))
  :body '((?f0 (act ?r)) (?f1 (sens ?h ?r))))
"""

TWO_ROBOTS = "(state robot(R1), robot(R2))\n(goal (do-task R1))\n"


def planned(tmp_path: Path, domain: str, state: str) -> tuple[Problem, list[Configuration]]:
    (tmp_path / "domain.lisp").write_text(domain, encoding="utf-8")
    (tmp_path / "state.lisp").write_text(state, encoding="utf-8")
    problem = load(tmp_path / "domain.lisp", tmp_path / "state.lisp")
    configs, _ = plan(problem.task, problem.goal_call, limit=None, distinct=False)
    return problem, configs


def _by_hand(
    functionalities: list[tuple[str, str, tuple[str, ...]]],
    channels: list[tuple[str, str, str, str, str, tuple[str, ...]]],
    cost: float,
) -> Configuration:
    return Configuration(
        functionalities=tuple(
            FunctionalityInstance(label=label, name=name, args=args)
            for label, name, args in functionalities
        ),
        channels=tuple(
            Channel(kind=kind, source=src, target=dst, source_robot=sr, target_robot=tr, data=data)  # type: ignore[arg-type]
            for kind, src, dst, sr, tr, data in channels
        ),
        cost=cost,
    )


def test_planner_refuses_a_channel_into_a_functionality_that_does_not_consume_it(
    tmp_path: Path,
) -> None:
    _, configs = planned(tmp_path, UNCONSUMED_DOMAIN, TWO_ROBOTS)
    assert configs == []


def test_the_checker_reports_the_unconsumed_channel(tmp_path: Path) -> None:
    problem, _ = planned(tmp_path, UNCONSUMED_DOMAIN, TWO_ROBOTS)
    config = _by_hand(
        [("F2", "act", ("R1",)), ("F3", "sens", ("R1",)), ("F4", "sens", ("R2",))],
        [
            ("local", "F3", "F2", "R1", "R1", ("d", "R1")),
            ("global", "F4", "F2", "R2", "R1", ("d", "R2")),
        ],
        cost=20 + 3 + 1 + 3,
    )
    assert problems(config, problem.domain, problem.state) == [
        "information: channel 1 (global F4 -> F2 (d R2)): F2: act(R1) does not consume it"
    ]


def test_planner_refuses_a_call_that_does_not_match_a_repeated_variable(tmp_path: Path) -> None:
    """Only ?h = R1 gives a call, sens(R1, R1), that matches (sens ?r ?r)."""
    problem, configs = planned(tmp_path, REPEATED_VARIABLE_DOMAIN, TWO_ROBOTS)
    assert [[f"{f.name}{f.args}" for f in c.functionalities] for c in configs] == [
        ["sens('R1', 'R1')", "act('R1',)"]
    ]
    assert problems(configs[0], problem.domain, problem.state) == []


def test_the_checker_reports_the_repeated_variable(tmp_path: Path) -> None:
    problem, _ = planned(tmp_path, REPEATED_VARIABLE_DOMAIN, TWO_ROBOTS)
    config = _by_hand(
        [("F2", "act", ("R1",)), ("F3", "sens", ("R2", "R1"))],
        [("global", "F3", "F2", "R2", "R1", ("d", "R1"))],
        cost=20 + 3 + 2,
    )
    bad = problems(config, problem.domain, problem.state)
    assert "domain: F3: sens(R2, R1) does not match the schema (sens ?r ?r)" in bad
