"""Extensions beyond the thesis: the adaptive channel ``(any ?a ?b)`` and devices.

The docking example (``domains/docking``, README "Devices and adaptive
channels"): Vacu docks using its own laser (a local channel), or Robby's laser
or the ceiling camera CamKitchen (a global channel); the camera is a device,
weighted by ``device`` (10 by default, like a robot).
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from cfgplan.configuration.admissible import problems
from cfgplan.configuration.cost import Weights
from cfgplan.configuration.model import Configuration
from cfgplan.diagnostics import CfgplanError
from cfgplan.planner import plan
from cfgplan.problem import Problem, load
from tests.planner.problems import load_text

DOCKING = Path(__file__).resolve().parents[2] / "domains" / "docking"


def docking(state: str, weights: Weights | None = None) -> tuple[Problem, list[Configuration]]:
    problem = load(DOCKING / "domain.lisp", DOCKING / state, None, weights)
    configs, _ = plan(problem.task, problem.goal_call, limit=None)
    for config in configs:
        assert problems(config, problem.domain, problem.state, problem.task.weights) == []
    return problem, configs


def test_any_channel_is_local_when_both_ends_are_one_robot() -> None:
    """Vacu's own laser: the pose channel (any Vacu Vacu) is local, costed 1:
    10 (Vacu) + 3 functionalities + 2 local channels."""
    _, configs = docking("state-kitchen.lisp")
    best = configs[0]
    assert best.cost == 15
    assert (best.local_channels, best.global_channels) == (2, 0)
    assert [c.cost for c in configs] == [15, 27, 27]


def test_any_channel_is_global_between_two_agents_and_devices_are_listed_apart() -> None:
    """Vacu's laser failed: Robby (a robot) or CamKitchen (a device) sends the
    pose over a global channel: 10 + 10 + 3 + 1 local + 3 global = 27 each."""
    _, configs = docking("state-kitchen-laser-failed.lisp")
    assert [(c.cost, c.robots, list(c.devices)) for c in configs] == [
        (27, ["Vacu", "Robby"], []),
        (27, ["Vacu"], ["CamKitchen"]),
    ]
    assert all(c.global_channels == 1 for c in configs)


def test_the_device_weight_prices_devices_only() -> None:
    cheap = Weights(device=5)
    _, configs = docking("state-kitchen-laser-failed.lisp", cheap)
    assert [(c.cost, list(c.devices)) for c in configs] == [(22, ["CamKitchen"]), (27, [])]


ANY_WITH_MEDIA = """\
(make-functionality :name '(sense ?h) :out '((d ?h)))
(make-functionality :name '(use ?r ?h) :in '((d ?h)))
(make-config-method :name '(go ?r)
  :precond '((robot ?h))
  :channels '(((any ?h ?r) ?s ?u (d ?h) 40))
  :body '((?s (sense ?h)) (?u (use ?r ?h))))
"""


@pytest.mark.parametrize(("capacity", "costs"), [(30, [13]), (50, [13, 25])])
def test_a_channel_that_became_global_needs_a_medium(capacity: int, costs: list[int]) -> None:
    """Checked as what it became (4.6): from A to A it is local and needs no
    medium; from B to A it is global, and its 40 must fit in the medium."""
    state = f"(state (robot A) (robot B) (medium wifi B A {capacity})) (goal (go A))"
    problem = load_text(ANY_WITH_MEDIA, state)
    configs, _ = plan(problem.task, problem.goal_call, limit=None)
    assert [c.cost for c in configs] == costs
    kinds = [(c.local_channels, c.global_channels) for c in configs]
    assert kinds == [(1, 0), (0, 1)][: len(costs)]


def test_any_takes_two_robots() -> None:
    domain = ANY_WITH_MEDIA.replace("(any ?h ?r)", "(any ?h)")
    with pytest.raises(CfgplanError) as caught:
        load_text(domain, "(state (robot A)) (goal (go A))")
    assert caught.value.diagnostics[0].message == "any takes 2 robot(s): (any ?from ?to)"


# -- reliability in the cost (7.2) ---------------------------------------------------

RELIABLE = """\
(make-functionality :name '(cam ?r) :out '((img ?r)) :reliability 0.5)
(make-functionality :name '(sonar ?r) :out '((img ?r)) :cost 2)
(make-functionality :name '(use ?r ?h) :in '((img ?h)))
(make-config-method :name '(go ?r) :precond '((robot ?h))
  :channels '(((any ?h ?r) ?s ?u (img ?h))) :body '((?s (cam ?h)) (?u (use ?r ?h))))
(make-config-method :name '(go ?r) :channels '(((local ?r) ?s ?u (img ?r)))
  :body '((?s (sonar ?r)) (?u (use ?r ?r))))
"""


def test_reliability_weight_adds_minus_log_reliability() -> None:
    """``reliability=W`` adds ``W·(−ln p)`` per part: the camera (p = 0.5)
    costs 1 + 2·ln 2 = 2.386 with W = 2, more than the sonar's :cost 2."""
    state = "(state (robot A) (robot B) (medium wifi B A 100 0.8)) (goal (go A))"
    plain = load_text(RELIABLE, state)
    costs = [c.cost for c in plan(plain.task, plain.goal_call, limit=None)[0]]
    assert costs == [13, 14, 25]  # cam(A), sonar(A), cam(B) over wifi
    weighted = load_text(RELIABLE, state, Weights(reliability=2))
    configs, _ = plan(weighted.task, weighted.goal_call, limit=None)
    assert [round(c.cost, 4) for c in configs] == [
        14,
        round(13 + 2 * math.log(2), 4),
        round(25 + 2 * math.log(2) + 2 * -math.log(0.8), 4),
    ]
    assert [round(c.reliability, 4) for c in configs] == [1.0, 0.5, 0.4]
    for config in configs:
        assert problems(config, weighted.domain, weighted.state, weighted.task.weights) == []


@pytest.mark.parametrize("value", ["0", "1.5", "-0.2", "x"])
def test_reliability_must_be_a_chance(value: str) -> None:
    with pytest.raises(CfgplanError) as caught:
        load_text(RELIABLE.replace(":reliability 0.5", f":reliability {value}"), "(state)")
    assert "reliability" in caught.value.diagnostics[0].message
