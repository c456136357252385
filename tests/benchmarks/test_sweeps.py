"""The shapes of the benchmark sweeps (benchmarks/sweeps.py) and how one of
their processes is measured."""

from __future__ import annotations

from itertools import islice
from pathlib import Path

from benchmarks import families
from benchmarks.run import ROOT
from benchmarks.sweeps import measure, plan_command, written
from cfgplan.planner import plan
from cfgplan.planner.sequence import SequenceSearch, unseen
from tests.planner.problems import load_text


def test_missions_are_independent_steps_whose_sum_is_the_sequence() -> None:
    for moving in (False, True):
        problem = load_text(*families.missions(3, 4, moving))
        assert unseen(problem.task, problem.goal_calls) == (True, True, True)
        (best,) = islice(SequenceSearch(problem.goal_calls, problem.task), 1)
        alone = [plan(problem.task, goal)[0][0].cost for goal in problem.goal_calls]
        assert best.total == sum(alone) == 3 * 39
        if moving:
            assert [s.changes for s in best.steps] == [
                (f"(not (at G{i} Dock))", f"(at G{i} Place{i})") for i in (1, 2, 3)
            ]


def test_any_delegation_has_one_configuration() -> None:
    problem = load_text(*families.any_delegation(3))
    every, _ = plan(problem.task, problem.goal_call, limit=None)
    assert [(c.cost, c.agents) for c in every] == [(30, ["r1", "r2"])]


def test_a_measured_process_says_what_it_found(tmp_path: Path) -> None:
    domain, state = written(tmp_path, families.missions(2, 2))
    found = measure(plan_command(domain, state, 30.0, "-k", "1"), ROOT, 30.0)
    assert found.best == 78 and found.seconds is not None and found.mib > 0
    stopped = measure(plan_command(domain, state, 30.0, "--bogus"), ROOT, 30.0)
    assert stopped.seconds is None and stopped.best is None


def test_structured_domains_are_the_same_for_a_seed_and_plan() -> None:
    """The randomised generator is deterministic for its arguments, differs by
    seed, and what it writes reads, checks and plans (media included)."""
    assert families.structured(3, pieces=4) == families.structured(3, pieces=4)
    assert families.structured(3, pieces=4) != families.structured(4, pieces=4)
    for media in (False, True):
        problem = load_text(*families.structured(3, pieces=4, depth=2, media=media))
        configs, _ = plan(problem.task, problem.goal_call, limit=1)
        assert configs and configs[0].agents[0] == "G"
        assert (len(problem.task.media) > 0) == media
