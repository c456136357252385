"""The planner's entry point (cfgplan.planner.plan): what it keeps per task."""

from __future__ import annotations

import dataclasses
import gc
import weakref

from cfgplan.planner import plan
from cfgplan.planner.plan import analysis
from cfgplan.problem import load
from tests.backends.support import DOMAINS

STEP1 = (DOMAINS / "cross-door/domain.lisp", DOMAINS / "cross-door/state-6.2.2-step1.lisp")


def test_the_grounding_and_bounds_of_a_task_are_made_once_and_go_with_it() -> None:
    """A run that reconfigures plans on one derived task after another: what
    the planner works out for each must not outlive it."""
    problem = load(*STEP1)
    gone = []
    for _ in range(3):
        task = dataclasses.replace(problem.task)  # as a derived task is made
        assert task.analyses == {}  # derived: nothing worked out yet
        configs, search = plan(task, problem.goal_call, limit=2)
        assert [c.cost for c in configs] == [44, 47]  # 6.2.2 step 1
        assert analysis(task) is analysis(task)  # made once, then found
        gone.append(weakref.ref(task))
        del task, search
    gc.collect()
    assert [ref() for ref in gone] == [None, None, None]
    assert configs[0].cost == 44  # what was planned is kept, without its task
