"""``-k N`` looks ahead for one more configuration within bounded work.

``cfgplan plan -k 1`` used to plan two configurations to say whether more
exist, so where only one exists it searched to the end to prove it (112 s on
a recursive delegation where the first took 0.39 s). Now the search looks for
one more with at most as much work again as the listed ones took (at least
``ahead_least`` steps of :func:`cfgplan.planner.clock.check`, a measure that
is the same on every machine): one found, more exist; the search ended, none
do; the work ran out, not known.
"""

from __future__ import annotations

from benchmarks.families.delegation import delegation
from cfgplan.cli.formats import more_note
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.plan import Run, plan
from cfgplan.planner.report import Status
from tests.planner.problems import load_text
from tests.planner.test_reproducers import REUSED_SENSOR


def _listed(domain: str, state: str, least: int) -> tuple[Run, list[object]]:
    problem = load_text(domain, state)
    search = Run(
        problem.task, problem.goal_call, 1, ahead=True, options=SearchOptions(ahead_least=least)
    )
    return search, list(search)


def _hidden(depth: int) -> tuple[str, str]:
    """``(go R)`` has a cheap first version; its second reaches the only other
    configuration through ``depth`` levels of two versions each, where every
    derivation but the last in depth-first order uses a ``deaf`` step whose
    second input nothing feeds: 2**depth - 1 derivations are rejected at
    step 4 (4.5) before the second configuration is met, and no bound sees
    an unfed input coming."""
    lines = [
        "(make-functionality :name '(sense ?r) :out '((d0 ?r)))",
        "(make-functionality :name '(act ?r) :in '((d0 ?r)))",
        f"(make-functionality :name '(use ?r) :in '((d{depth} ?r)))",
        "(make-config-method :name '(go ?r) :channels '(((local ?r) ?s ?a (d0 ?r)))",
        "  :body '((?s (sense ?r)) (?a (act ?r))))",
        f"(make-config-method :name '(go ?r) :channels '(((local ?r) ?l ?u (d{depth} ?r)))",
        f"  :body '((?l (level{depth} ?r)) (?u (use ?r))))",
        "(make-config-method :name '(level0 ?r) :out '((?s (d0 ?r))) :body '((?s (sense ?r))))",
    ]
    for i in range(1, depth + 1):
        lines += [
            f"(make-functionality :name '(deaf{i} ?r) :in '((d{i - 1} ?r) (z ?r)) "
            f":out '((d{i} ?r)))",
            f"(make-functionality :name '(good{i} ?r) :in '((d{i - 1} ?r)) :out '((d{i} ?r)))",
        ]
        lines += [
            f"(make-config-method :name '(level{i} ?r) :out '((?x (d{i} ?r)))\n"
            f"  :channels '(((local ?r) ?a ?x (d{i - 1} ?r)))\n"
            f"  :body '((?a (level{i - 1} ?r)) (?x ({step}{i} ?r))))"
            for step in ("deaf", "good")
        ]
    return "\n".join(lines) + "\n", "(state (robot R))\n(goal (go R))\n"


def test_the_look_ahead_says_more_exist_none_or_not_known() -> None:
    """The second configuration of ``_hidden(6)`` lies behind 63 rejected
    derivations, the first costs a few nodes: with room to look, one more is
    found; with no room beyond the work the first took, it is not known.
    Either way the one listed is the first of a plain search, and the one
    looked for is not listed."""
    domain, state = _hidden(6)
    problem = load_text(domain, state)
    first, _ = plan(problem.task, problem.goal_call, limit=1)
    found, listed = _listed(domain, state, 10_000)
    assert found.status is Status.MORE and listed == first
    cut, listed = _listed(domain, state, 0)
    assert cut.status is Status.UNKNOWN and listed == first
    assert cut.stats.nodes < found.stats.nodes  # it stopped looking early
    alone, listed = _listed(REUSED_SENSOR, "(state robot(R1))\n(goal (do-task R1))\n", 10_000)
    assert alone.status is Status.COMPLETE and len(listed) == 1


def test_without_the_look_ahead_nothing_is_said() -> None:
    domain, state = delegation(6)
    problem = load_text(domain, state)
    search = Run(problem.task, problem.goal_call, 1)
    assert len(list(search)) == 1 and search.status is Status.CUT


def test_the_note_says_may_when_it_is_not_known() -> None:
    assert more_note(1) == (
        "note: at least one more configuration exists: -k 11 lists up to 11, --all lists them all\n"
    )
    assert more_note(1, more=None) == (
        "note: more configurations may exist (the search for one more stopped early): "
        "-k 11 searches for up to 11, --all for them all\n"
    )


def test_sequences_look_ahead_by_the_same_rule() -> None:
    """``cfgplan plan -k N`` of a sequence planned N + 1 sequences to fill
    ``more``; now it looks for one more as one goal does
    (:mod:`cfgplan.planner.search`). 6.2.2 as a sequence (Pippi, then Emil,
    crosses): more exist; the one listed is the first of a search without a
    limit; a sequence of one goal with one configuration has no second."""
    from pathlib import Path

    from cfgplan.planner.sequence import SequenceSearch
    from cfgplan.problem import load

    root = Path(__file__).resolve().parents[2] / "domains" / "cross-door"
    problem = load(root / "domain-steps.lisp", root / "state-6.2.2-sequence.lisp")
    unlimited = next(iter(SequenceSearch(problem.goal_calls, problem.task)))
    search = SequenceSearch(problem.goal_calls, problem.task, limit=1, ahead=True)
    assert list(search) == [unlimited] and search.status is Status.MORE
    assert not search.status.exhausted  # it was left before its end
    alone = load_text(REUSED_SENSOR, "(state robot(R1))\n(sequence (do-task R1))\n")
    one = SequenceSearch(alone.goal_calls, alone.task, limit=1, ahead=True)
    assert len(list(one)) == 1 and one.status is Status.COMPLETE


def test_the_json_reads_one_status() -> None:
    """How a run ended was spread over ``Stats.complete``, ``Run.stopped``,
    ``Run.more`` and the report's ``unfinished``/``undecided``; the JSON's
    ``exhausted``, ``more`` and ``stopped`` are now read off one
    :class:`Status`, for each way a run ends: the list cut with one more
    found, cut without looking, run to its end, stopped by the time limit."""
    from cfgplan.cli.formats import stats

    domain, state = _hidden(2)
    problem = load_text(domain, state)
    ends = {}
    for limit, ahead, seconds in (
        (1, True, None),
        (1, False, None),
        (None, False, None),
        (1, True, 0.0),
    ):
        run = Run(problem.task, problem.goal_call, limit, ahead=ahead, time_limit=seconds)
        list(run)
        shown = stats(run, run.status.more)
        ends[run.status] = (shown["exhausted"], shown["more"], shown["stopped"])
    assert ends == {
        Status.MORE: (False, True, None),
        Status.CUT: (False, False, None),
        Status.COMPLETE: (True, False, None),
        Status.TIME_LIMIT: (False, False, "time limit"),
    }
