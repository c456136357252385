"""Extensions beyond the thesis: the adaptive channel ``(any ?a ?b)`` and devices.

The docking example (``domains/docking``, README "Devices and adaptive
channels"): Vacu docks using its own laser (a local channel), or Robby's laser
or the ceiling camera CamKitchen (a global channel); the camera is a device,
weighted by ``device`` (10 by default, like a robot).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from cfgplan.configuration.admissible import problems
from cfgplan.configuration.cost import Weights
from cfgplan.configuration.model import Configuration
from cfgplan.diagnostics import CfgplanError
from cfgplan.planner import plan
from cfgplan.problem import Problem, load
from tests.planner.generated import load_text

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
