"""The search and the solver's process racing for ``-k 1`` (:mod:`cfgplan.planner.solver`).

The race itself with stand-in engines (who wins, that the child is gone by its
pid however the race ends, that nothing is raced within the search's own budget),
then the planner's race: the same configuration as the
search alone on random domains, and past the search's cliff the solver's.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import replace
from pathlib import Path
from typing import cast

import pytest
from hypothesis import given

from benchmarks.families import structured
from cfgplan.configuration.admissible import problems
from cfgplan.planner import clock, plan
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.report import Engine, Status
from cfgplan.planner.solver import Answer, Overtaken, Prepare, Rival, racing
from tests.planner.generated import generated
from tests.planner.problems import PROPERTY, Generated, load_text, solve
from tests.planner.test_thesis import problem

LIMIT = 20.0
"""No wait below is longer (seconds)."""


def searching(rival: Rival, until: float = LIMIT) -> Iterator[int]:
    """Steps of a stand-in search's clock for at most ``until`` seconds: the
    child's pid at each (-1: none runs)."""
    end = time.monotonic() + until
    while time.monotonic() < end:
        clock.check()
        yield -1 if rival.pid is None else rival.pid
        time.sleep(0.001)


def gone(pid: int) -> bool:
    """Whether process ``pid`` has ended (a zombie its parent has not waited
    for yet counts: it runs no more)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except FileNotFoundError:
        return True
    return state == "Z"


ANSWER = cast(Answer, ("the solver's configuration", "its work"))


def answering() -> Callable[[], Answer | None]:
    return lambda: ANSWER


def sleeping() -> Callable[[], Answer | None]:
    def solve() -> Answer:
        time.sleep(LIMIT)
        return ANSWER  # not if it is killed first

    return solve


def failing_to_prepare() -> Callable[[], Answer | None]:
    raise RuntimeError("costs without a unit")


def failing() -> Callable[[], Answer | None]:
    def solve() -> Answer:
        raise RuntimeError("out of time")

    return solve


def nothing() -> Callable[[], Answer | None]:
    return lambda: None


def test_the_childs_answer_ends_the_search_and_the_child() -> None:
    pids = set()
    with pytest.raises(Overtaken) as won, racing(answering, after=3) as rival:
        for pid in searching(rival):
            pids.add(pid)
    assert won.value.answer == ANSWER
    assert rival.started and rival.pid is None
    started = pids - {-1}
    assert len(started) == 1 and gone(started.pop())


def test_a_search_that_ends_first_has_the_child_killed() -> None:
    pids = set()
    with racing(sleeping, after=0) as rival:
        for steps, pid in enumerate(searching(rival)):
            pids.add(pid)
            if steps == 50:
                break
    assert rival.started and rival.pid is None
    started = pids - {-1}
    assert len(started) == 1 and gone(started.pop())
    assert rival.status is not None and os.WIFSIGNALED(rival.status)
    assert os.WTERMSIG(rival.status) == signal.SIGKILL


@pytest.mark.parametrize("engine", [nothing, failing, failing_to_prepare])
def test_a_child_without_an_answer_leaves_the_search_alone(engine: Prepare) -> None:
    pids = set()
    with racing(engine, after=0) as rival:
        for pid in searching(rival):
            pids.add(pid)
            if rival.gave_up:
                break
        for _ in range(100):  # the search goes on; no second child
            clock.check()
            pids.add(-1 if rival.pid is None else rival.pid)
    assert rival.gave_up and rival.started and rival.pid is None
    started = pids - {-1}
    assert len(started) == 1 and gone(started.pop())


def test_nothing_is_raced_within_the_searchs_budget() -> None:
    """The child prepares from the first step, but is killed before it solves."""
    with racing(answering, after=1000) as rival:
        for _ in range(999):
            clock.check()
        pid = rival.pid
    assert not rival.started and pid is not None and gone(pid)
    assert rival.status is not None and os.WIFSIGNALED(rival.status)


def test_where_no_process_can_be_forked_the_search_runs_alone(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Out of processes (``fork`` fails with EAGAIN): the search goes on, alone,
    and the pipes made for the child are closed again."""

    def refused() -> int:
        raise BlockingIOError(11, "Resource temporarily unavailable")

    before = len(os.listdir("/proc/self/fd"))
    monkeypatch.setattr(os, "fork", refused)
    with racing(answering, after=0) as rival:
        for _ in range(100):
            clock.check()
    assert rival.gave_up and not rival.started and rival.pid is None
    assert len(os.listdir("/proc/self/fd")) == before


RACE = SearchOptions(race=0)
"""The solver's process is started at the search's first step."""


@pytest.mark.quick(10)
@PROPERTY
@given(generated())
def test_the_race_finds_the_searchs_first_configuration(example: Generated) -> None:
    """Whoever wins, the race lists what the search alone lists first: the same
    configuration of the same cost, labels, channel order and derivation number."""
    p = solve(example)
    searched, _ = plan(p.task, p.goal_call, limit=1)
    p = solve(example)
    raced, run = plan(p.task, p.goal_call, limit=1, options=RACE)
    assert [c.model_dump() for c in raced] == [c.model_dump() for c in searched]
    if raced and not p.task.weights.reliability:  # costs with a unit: a race was run
        assert run.raced and run.status is Status.UNKNOWN


def test_a_search_within_its_budget_runs_alone() -> None:
    """The thesis's 6.2.2 step 1 (Fig. 6.3, cost 44) ends long before the
    solver would start: nothing forks, and the run lists and counts what the
    search alone does (the more note included)."""
    p = problem("cross-door/domain.lisp", "cross-door/state-6.2.2-step1.lisp")
    alone, run_alone = plan(p.task, p.goal_call, limit=1)
    p = problem("cross-door/domain.lisp", "cross-door/state-6.2.2-step1.lisp")
    raced, run = plan(p.task, p.goal_call, limit=1, options=SearchOptions(race=2_000))
    assert [c.model_dump() for c in raced] == [c.model_dump() for c in alone]
    assert raced[0].cost == 44
    assert not run.raced and run.engine is Engine.SEARCH
    assert replace(run.stats, seconds=0) == replace(run_alone.stats, seconds=0)


@pytest.mark.slow
def test_past_the_searchs_cliff_the_solver_answers() -> None:
    """``structured`` seed 2 with 16 pieces: the search alone takes about 13 s
    (docs/explanation/planner.md), the solver about one. Raced, the solver's
    process answers: the configuration the solver alone finds (the search's
    first, as the solver's own tests show), admissible by the independent
    checker, with the solver's work."""
    texts = structured(2, pieces=16)
    p = load_text(*texts)
    (alone,), _ = plan(p.task, p.goal_call, limit=1, options=SearchOptions(solver=True))
    p = load_text(*texts)
    (raced,), run = plan(p.task, p.goal_call, limit=1, options=RACE)
    assert run.engine is Engine.SOLVER and run.raced and run.status is Status.UNKNOWN
    assert raced.model_dump() == alone.model_dump()
    assert problems(raced, p.domain, p.state) == []
    assert run.stats.derivations == 1  # the walk's, not the search's thousands of nodes


RACER = """
import sys, time
from cfgplan.planner import clock
from cfgplan.planner.solver import racing

def prepare():
    def solve():
        time.sleep(60)
    return solve

with racing(prepare, after=0) as rival:
    clock.check()
    print(rival.pid, flush=True)
    time.sleep(60)
"""


def test_the_child_does_not_outlive_a_parent_killed_outright() -> None:
    """``kill -9`` of the planning process runs none of its ``finally``: the
    kernel ends the racing child with it (it would otherwise solve on, alone)."""
    parent = subprocess.Popen([sys.executable, "-c", RACER], stdout=subprocess.PIPE, text=True)
    try:
        assert parent.stdout is not None
        child = int(parent.stdout.readline())
        assert not gone(child)
    finally:
        os.kill(parent.pid, signal.SIGKILL)
        parent.wait(LIMIT)
    end = time.monotonic() + LIMIT
    while not gone(child) and time.monotonic() < end:
        time.sleep(0.01)
    assert gone(child)


@pytest.mark.slow
def test_the_solver_proves_nothing_admissible_where_the_search_cannot() -> None:
    """``structured`` seed 1 with media at 12 pieces admits nothing: the
    relaxation has no model, which the solver proves in about two seconds and
    the search alone did not decide in 20 (docs/explanation/planner.md). Raced,
    the run lists nothing, says the solver proved it, and still explains why
    from a search without the bounds (dead ends met)."""
    p = load_text(*structured(1, pieces=12, media=True))
    configs, run = plan(p.task, p.goal_call, limit=1, options=RACE)
    assert configs == []
    assert run.inadmissible and run.engine is Engine.SOLVER
    assert run.report.dead  # the dead ends of the search for why
