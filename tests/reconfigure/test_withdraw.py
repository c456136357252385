"""Which facts a failure withdraws, read off the domain (5.5; 6.2.2 step 3, 6.3.2).

The thesis's operator removed the failed sensors' facts by hand; these tests
check that the rule of :mod:`cfgplan.reconfigure.withdraw` gives the same
facts on the thesis's three domains and the docking extension, and no more
(``(robot Emil)``, ``(odometer ...)`` and ``(sonar ...)`` of other sensors stay).
"""

from __future__ import annotations

import pytest

from cfgplan.planner.task import Ground
from cfgplan.problem import load
from cfgplan.reconfigure.withdraw import (
    justification,
    reaching,
    specific,
    withdrawn_by_failure,
    withdrawn_by_loss,
)
from tests.backends.support import DOMAINS

CASES = [
    # (domain, state, failed instance, withdrawn)
    ("cross-door", "state-6.2.2-step2.lisp", ("compass", "Emil"), [("compass", "Emil")]),
    ("cross-door", "state-6.2.2-step2.lisp", ("camera", "Pippi"), [("camera", "Pippi")]),
    ("cross-door", "state-6.2.2-step2.lisp", ("cross-door", "Emil", "Door1"), []),
    ("cross-door", "state-6.2.2-step2.lisp", ("measure-robot-orient-compass", "Pippi", "Emil"), []),
    ("carry-bar", "state-6.3.2.lisp", ("laser", "Emil"), [("laser", "Emil")]),
    ("carry-bar", "state-6.3.2.lisp", ("odometer", "Pippi"), [("odometer", "Pippi")]),
    ("carry-bar", "state-6.3.2.lisp", ("sonar", "Pippi"), [("sonar", "Pippi")]),
    ("build-wall", "state-6.4.lisp", ("laser", "Emil"), [("laser", "Emil")]),
    ("build-wall", "state-6.4.lisp", ("push-block", "Emil", "B1", "W1"), []),
    ("docking", "state-kitchen.lisp", ("laser", "Vacu"), [("laser", "Vacu")]),
    ("docking", "state-kitchen.lisp", ("camera", "CamKitchen"), [("camera", "CamKitchen")]),
    ("docking", "state-kitchen.lisp", ("dock", "Vacu", "Charger1"), []),
]


def _task(domain: str, state: str):  # type: ignore[no-untyped-def]
    return load(DOMAINS / domain / "domain.lisp", DOMAINS / domain / state).task


@pytest.mark.parametrize(("domain", "state", "failed", "withdrawn"), CASES)
def test_a_failure_withdraws_the_facts_the_domain_ties_to_it(
    domain: str, state: str, failed: Ground, withdrawn: list[Ground]
) -> None:
    assert list(withdrawn_by_failure(_task(domain, state), failed)) == withdrawn


def test_the_odometer_does_not_take_the_sonar_with_it() -> None:
    """Rule 1: the sonar version of get-global-pos tests (sonar ?r) and calls
    the odometer, but the laser version calls it without testing a sonar."""
    task = _task("carry-bar", "state-6.3.2.lisp")
    schema = task.functionality(("odometer", "Pippi"))
    assert schema is not None
    assert justification(task, schema, ("odometer", "Pippi")) == {
        ("odometer", "Pippi"),
        ("robot", "Pippi"),
    }


def test_robot_is_not_specific_to_the_laser_but_laser_is() -> None:
    """Rule 3: (robot ?r) is tested by the sonar version of get-global-pos,
    which never reaches laser; (laser ?r) only by versions that do."""
    task = _task("carry-bar", "state-6.3.2.lisp")
    found = specific(task, ("laser", 1))
    assert ("laser", 1) in found and ("robot", 1) not in found


def test_reaching_goes_through_methods() -> None:
    """get-robot-orient's camera version reaches camera through get-robot-angle."""
    task = _task("cross-door", "state-6.2.2-step2.lisp")
    reach = reaching(task, ("camera", 1))
    assert (("get-robot-orient", 2), 2) in reach
    assert (("get-robot-orient", 2), 1) not in reach  # the compass version
    assert (("do-cross-door", 2), 1) in reach


def test_a_lost_robot_withdraws_every_fact_naming_it() -> None:
    task = _task("cross-door", "state-6.2.2-step2.lisp")
    assert list(withdrawn_by_loss(task, "Pippi")) == [
        ("robot", "Pippi"),
        ("camera", "Pippi"),
        ("compass", "Pippi"),
        ("in", "Pippi", "Room2"),
    ]
