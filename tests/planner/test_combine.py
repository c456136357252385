"""Independent parts searched apart (cfgplan/planner/combine.py, combine.py)
list exactly what the plain best-first search lists: the same configurations,
costs, labels and derivation numbers, in the same order."""

from __future__ import annotations

import re

import pytest
from hypothesis import Phase, assume, given, settings
from hypothesis import strategies as st

from benchmarks.families import ecology, media_tight
from cfgplan.planner.combine import Combined
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.plan import Run, divided, growing
from cfgplan.planner.report import Condition
from cfgplan.planner.search import BestFirst
from tests.planner.generated import generated
from tests.planner.oracle import depth_first
from tests.planner.problems import PROPERTY, Generated, run, solve
from tests.planner.test_scale import problem_of

# A goal whose two choice items share nothing, but two forced functionalities
# between them: T feeds get-a, get-a feeds S, S feeds get-b, get-b feeds T.
# Version 1 of each passes its input on to its output (a1, b1), version 2
# does not (a sink and a source): a1 with b1 make a cycle T -> a1 -> S ->
# b1 -> T, which only the whole configuration shows (4.5 step 4).
CYCLE = """\
(make-functionality :name '(t ?r) :in '((z ?r)) :out '((t ?r)))
(make-functionality :name '(s ?r) :in '((x ?r)) :out '((y ?r)))
(make-functionality :name '(a1 ?r) :in '((t ?r)) :out '((x ?r)))
(make-functionality :name '(a-sink ?r) :in '((t ?r)))
(make-functionality :name '(a-source ?r) :out '((x ?r)))
(make-functionality :name '(b1 ?r) :in '((y ?r)) :out '((z ?r)))
(make-functionality :name '(b-sink ?r) :in '((y ?r)))
(make-functionality :name '(b-source ?r) :out '((z ?r)))
(make-config-method :name '(get-a ?r) :in '((?f (t ?r))) :out '((?f (x ?r)))
  :body '((?f (a1 ?r))))
(make-config-method :name '(get-a ?r) :in '((?k (t ?r))) :out '((?o (x ?r)))
  :body '((?k (a-sink ?r)) (?o (a-source ?r))))
(make-config-method :name '(get-b ?r) :in '((?f (y ?r))) :out '((?f (z ?r)))
  :body '((?f (b1 ?r))))
(make-config-method :name '(get-b ?r) :in '((?k (y ?r))) :out '((?o (z ?r)))
  :body '((?k (b-sink ?r)) (?o (b-source ?r))))
{twin}
(make-config-method :name '(loop ?r)
  :channels '(((local ?r) ?t ?a (t ?r)) ((local ?r) ?a ?s (x ?r))
              ((local ?r) ?s ?b (y ?r)) ((local ?r) ?b ?t (z ?r)))
  :body '((?t (t ?r)) (?s (s ?r)) (?a (get-a ?r)) (?b (get-b ?r))))
"""
TWIN = """\
(make-config-method :name '(get-b ?r) :in '((?f (y ?r))) :out '((?f (z ?r)))
  :body '((?f (b1 ?r))))"""
STATE = "(state (robot R))\n(goal (loop R))\n"


def _listing(run: Run) -> list[str]:
    return [config.model_dump_json() for config in run]


def _both(texts: tuple[str, str], limit: int, distinct: bool = True) -> tuple[Run, list[str]]:
    """The run with parts, having checked it lists what the plain search does."""
    problem = problem_of(texts)
    plain = Run(
        problem.task, problem.goal_call, limit, distinct, options=SearchOptions(components=False)
    )
    expected = _listing(plain)
    assert isinstance(plain.strategy, BestFirst)
    run = Run(problem.task, problem.goal_call, limit, distinct)
    assert _listing(run) == expected
    return run, expected


def test_the_rooms_of_an_ecology_are_its_parts() -> None:
    """Ecology N=12 R=3 C=2: every member's pose comes from its own room, the
    door's from the leader's: one part per room, each the get-pose items of
    the room's members (and the leader's get-door in Room1's)."""
    problem = problem_of(ecology(12, 3, 2))
    found = divided(problem.task, problem.goal_call)
    assert found is not None
    rooms = []
    for items in found.parts:
        members = {int(item.call[1][1:]) for item in items}
        rooms.append({(m - 1) % 3 for m in members})
        assert {item.call[0] for item in items} <= {"get-pose", "get-door"}
    assert rooms == [{0}, {1}, {2}]
    assert sum(len(items) for items in found.parts) == 13  # 12 poses and the door


@pytest.mark.parametrize(
    ("texts", "limit"),
    [
        (ecology(12, 3, 2), 40),
        (ecology(18, 3, 3), 12),
        (media_tight(6, 2, 1), 40),
        (media_tight(8, 3, 2), 12),
    ],
    ids=["ecology-12", "ecology-18", "media-tight-6", "media-tight-8"],
)
def test_parts_list_what_the_plain_search_lists(texts: tuple[str, str], limit: int) -> None:
    """Many configurations of equal cost (a room's camera hosts): their order
    is the thesis's depth-first one across the rooms' interleaved members."""
    run, listed = _both(texts, limit)
    assert isinstance(run.strategy, Combined)
    assert len(listed) == limit


def test_every_derivation_of_parts_is_listed_as_the_plain_search_does() -> None:
    """``--derivations``: not distinct, every derivation in its own place."""
    run, listed = _both(ecology(9, 3, 2), 30, distinct=False)
    assert isinstance(run.strategy, Combined) and len(listed) == 30


def test_a_cycle_through_forced_functionalities_is_rejected_in_the_whole() -> None:
    """get-a and get-b are two parts; a1 with b1 is the cheapest combination
    but has a cycle: the three others are listed, as the plain search does."""
    run, listed = _both((CYCLE.format(twin=""), STATE), 10)
    assert isinstance(run.strategy, Combined)
    assert len(listed) == 3
    assert run.stats.rejected == 1


def test_a_forced_functionality_nothing_may_feed_leaves_it_to_the_plain_search() -> None:
    """Without the channel from get-b to t, t's input is fed by nothing any
    part may add: no combination is admissible, and the plain search, not the
    parts, finds that out (and says why)."""
    unfed = CYCLE.format(twin="").replace(" ((local ?r) ?b ?t (z ?r))", "")
    problem = problem_of((unfed, STATE))
    assert divided(problem.task, problem.goal_call) is None
    run = Run(problem.task, problem.goal_call, 10)
    assert list(run) == [] and isinstance(run.strategy, BestFirst)


def test_a_part_meeting_a_configuration_twice_hands_over_to_the_plain_search() -> None:
    """get-b's first version twice: its part meets a configuration again,
    which the plain search would count among the derivations (numbering the
    next ones after it): the plain search lists the rest."""
    run, listed = _both((CYCLE.format(twin=TWIN), STATE), 10)
    assert isinstance(run.strategy, Combined) and run.strategy.handed_over
    assert len(listed) == 3


@pytest.mark.parametrize(("twin", "handed_over", "rejections"), [(TWIN, True, 2), ("", False, 1)])
def test_what_the_parts_reject_is_counted_and_reported_once(
    twin: str, handed_over: bool, rejections: int
) -> None:
    """The cycle a1-b1 is rejected among the combinations. With get-b's twin
    the parts then hand over, and the plain search meets it again: it is
    counted, and reported, once, as by the plain search alone; without the
    twin the combinations' own report says it."""
    problem = problem_of((CYCLE.format(twin=twin), STATE))
    plain = Run(problem.task, problem.goal_call, 10, options=SearchOptions(components=False))
    run = Run(problem.task, problem.goal_call, 10)
    assert len(list(plain)) == len(list(run)) == 3
    assert isinstance(run.strategy, Combined) and run.strategy.handed_over is handed_over
    assert run.stats.rejected == plain.stats.rejected == rejections
    rejected = [dead.describe() for dead in run.report.rejected]
    assert rejected == [dead.describe() for dead in plain.report.rejected]
    assert len(rejected) == rejections


def test_the_dive_of_parts_stopped_at_once_reports_what_it_met() -> None:
    """Stopped before anything was proven, the parts' run dives greedily: it
    finds a configuration, and the cycle it met on the way (a1 with b1,
    rejected by step 4) is in the run's report."""
    problem = problem_of((CYCLE.format(twin=""), STATE))
    run = Run(problem.task, problem.goal_call, 10, time_limit=0)
    run._divide()  # the parts found now: under the limit of 0 s they would not be
    assert isinstance(run.strategy, Combined)
    found = list(run)
    assert len(found) == 1 and not found[0].proven
    assert not run.strategy.handed_over
    assert [dead.condition for dead in run.report.rejected] == [Condition.CYCLE]


HELPERS = """\
(make-functionality :name '(base ?r) :out '((ready ?r)))
(make-functionality :name '(a ?r) :out '((a ?r)))
(make-functionality :name '(b ?r) :out '((b ?r)))
(make-config-method :name '(get-a ?r) :precond '((helper ?h)) :body '((?f (a ?h))))
(make-config-method :name '(get-a ?r) :body '((?f (a ?r))))
(make-config-method :name '(get-b ?r) :precond '((helper ?h)) :body '((?f (b ?h))))
(make-config-method :name '(get-b ?r) :body '((?f (b ?r))))
(make-config-method :name '(pair ?r)
  :body '((?x (base ?r)) {more}(?a (get-a ?r)) (?b (get-b ?r))))
"""


def test_items_that_may_use_one_robot_more_are_one_part() -> None:
    """get-a and get-b may each run on helper H, which nothing forced uses:
    together they pay for H once, so they are one part (no parts at all);
    with H's base forced too, H costs the same either way: two parts."""
    state = "(state (robot R) (robot H) (helper H))\n(goal (pair R))\n"
    alone = problem_of((HELPERS.format(more=""), state))
    assert divided(alone.task, alone.goal_call) is None
    run, listed = _both((HELPERS.format(more="(?y (base H)) "), state), 10)
    assert isinstance(run.strategy, Combined) and len(run.strategy.parts.parts) == 2
    assert len(listed) == 4


def test_one_room_is_one_part() -> None:
    """Ecology in one room: every member may take its pose from the one
    ceiling camera, so all are tied: no parts."""
    problem = problem_of(ecology(6, 1, 1))
    assert divided(problem.task, problem.goal_call) is None


def twin(example: Generated) -> Generated:
    """``example`` twice: its robots R1..R4 and their facts again as S1..S4,
    and the goal both its goals. A half may still take a helper from the
    other (any robot of the state), so they are parts only now and then."""
    facts = example.state.split("\n\n(goal")[0].removeprefix("(state ").removesuffix(")")
    renamed = re.sub(r"\bR(\d)\b", r"S\1", facts)
    state = f"(state {facts}, {renamed})\n\n(goal (twin R1 S1))\n"
    both = "(make-config-method :name '(twin ?a ?b) :body '((?x (do-task ?a)) (?y (do-task ?b))))"
    return Generated(example.domain + both + "\n", state, example.weights)


@pytest.mark.quick(3)
@PROPERTY
@given(generated(), st.integers(1, 8))
def test_twins_list_as_depth_first(example: Generated, k: int) -> None:
    """On random domains made twice (:func:`twin`), the ``k`` cheapest
    derivations are the depth-first planner's first ``k``, and the distinct
    ones what the plain search lists."""
    alone = solve(example)
    assume(0 < len(run(alone, distinct=False)) <= 25)
    problem = solve(twin(example))
    derivations = run(problem, limit=k, distinct=False)
    oracle = depth_first(problem, example.weights)
    assert [(c.cost, c.identity()) for c in derivations] == oracle[:k]
    plain = Run(problem.task, problem.goal_call, k, options=SearchOptions(components=False))
    assert run(problem, limit=k, distinct=True) == list(plain)


@pytest.mark.slow
def test_twins_are_often_parts() -> None:
    """The property above exercises the parts: many twins split."""
    split = []

    @settings(PROPERTY, max_examples=100, phases=[Phase.generate])
    @given(generated())
    def collect(example: Generated) -> None:
        problem = solve(twin(example))
        split.append(divided(problem.task, problem.goal_call) is not None)

    collect()
    assert sum(split) >= 20


def test_a_search_in_parts_stopped_by_its_limit_says_how_long_it_took() -> None:
    """``plan -v`` said "0.0 ms" for a search in parts that ``-k`` stopped:
    the time was written only when the listing ran to its end."""
    problem = problem_of(ecology(6, 2, 1))
    run = Run(problem.task, problem.goal_call, limit=2)
    found = list(run)
    assert isinstance(run.strategy, Combined) and len(found) == 2
    assert run.stats.seconds > 0.0


def test_completions_are_numbered_among_the_derivations_repeats_counted() -> None:
    """A search's completions (what a part's search lists: no configuration
    built) are numbered among the derivations as the configurations built
    from them are: a repeat (get-b's twin version, distinct mode) counts, so
    the numbers skip it; an inadmissible one (the cycle) does not."""
    problem = problem_of((CYCLE.format(twin=TWIN), STATE))
    grower, pricer = growing(problem.task, SearchOptions(components=False))
    search = BestFirst(grower, pricer, problem.goal_call)
    numbers, counted, repeats = [], [], []
    for admitted in search.completions():
        assert admitted.node.done
        assert grower.build(admitted).derivation == admitted.derivation
        numbers.append(admitted.derivation)
        counted.append(search.stats.derivations)
        repeats.append(search.stats.duplicates)
    assert numbers == counted == [i + 1 + r for i, r in enumerate(repeats)]
    assert repeats[-1] > 0 and search.stats.rejected > 0
