"""Sequences of configurations (thesis 7.2, 6.2.2 as one plan)."""

from __future__ import annotations

import json
import subprocess
import sys
from itertools import islice, pairwise
from pathlib import Path

import pytest
from hypothesis import example, given

from benchmarks.families import ecology
from cfgplan.configuration.admissible import problems
from cfgplan.configuration.cost import Weights
from cfgplan.configuration.model import Configuration
from cfgplan.ir.model import Atom
from cfgplan.notation import atom_text
from cfgplan.planner import plan
from cfgplan.planner.combine import Combined
from cfgplan.planner.costs import level
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.sequence import SequenceSearch, apply, fixed_effects, touched, unseen
from cfgplan.planner.task import Task, derive
from cfgplan.problem import Problem, load
from tests.planner.generated import generated
from tests.planner.problems import PROPERTY, Generated, load_text, solve

ROOT = Path(__file__).resolve().parents[2]
STEPS = ROOT / "domains/cross-door/domain-steps.lisp"
SEQUENCE = ROOT / "domains/cross-door/state-6.2.2-sequence.lisp"
GOLDEN = ROOT / "tests/golden/sequence-6.2.2.txt"


def search(problem: Problem, switch: float = 0.0) -> SequenceSearch:
    return SequenceSearch(problem.goal_calls, problem.task, switch)


def test_section_6_2_2_as_one_sequence() -> None:
    """Pippi crosses guided by Emil (44, Fig. 4.3), then Emil guided by Pippi
    from Room2 (44, roles exchanged); then 91, 91 (one camera configuration,
    47, Fig. 6.4 bottom) and 94."""
    problem = load(STEPS, SEQUENCE)
    found = list(search(problem))
    assert [s.total for s in found] == [88, 91, 91, 94]
    first, second = found[0].steps
    assert (first.configuration.cost, second.configuration.cost) == (44, 44)
    assert first.changes == ("(not (in Pippi Room1))", "(in Pippi Room2)")
    helper = {f.name: f.args for f in second.configuration.functionalities}["transform-info"]
    assert helper == ("Pippi", "Emil", "Door1")  # Pippi, now in Room2, guides Emil


def test_golden_sequence_description() -> None:
    """The three cheapest sequences of 6.2.2 as --format lisp prints them
    (tests/golden/sequence-6.2.2.txt, checked by eye against 4.6 and Fig. 4.3)."""
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "cfgplan",
            "plan",
            str(STEPS.relative_to(ROOT)),
            str(SEQUENCE.relative_to(ROOT)),
            "-k",
            "3",
            "--format",
            "lisp",
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout == GOLDEN.read_text()


TOKEN = """\
(make-functionality :name '(sense ?r) :out '((d ?r)))
(make-functionality :name '(fast ?r ?g) :in '((d ?r)) :postcond '((not (ok ?r)) (done ?g)))
(make-functionality :name '(slow ?r ?g) :in '((d ?r)) :cost 4 :postcond '((done ?g)))
(make-config-method :name '(job ?g) :precond '((robot ?r) (ok ?r))
  :channels '(((local ?r) ?s ?x (d ?r))) :body '((?s (sense ?r)) (?x (fast ?r ?g))))
(make-config-method :name '(job ?g) :precond '((robot ?r))
  :channels '(((local ?r) ?s ?x (d ?r))) :body '((?s (sense ?r)) (?x (slow ?r ?g))))
(make-config-method :name '(special ?g) :precond '((robot ?r) (ok ?r) (expert ?r))
  :channels '(((local ?r) ?s ?x (d ?r))) :body '((?s (sense ?r)) (?x (fast ?r ?g))))
"""


def test_the_cheapest_first_step_is_not_the_cheapest_sequence() -> None:
    """Step 1's cheapest configuration, first in the thesis's order, has X do
    it fast (13), which leaves X not ok: step 2, which only an ok expert can
    do, is then impossible. The sequence search has Y do step 1 fast (13),
    then X step 2 (13): 26; then the slow ones first (16 + 13)."""
    state = "(state (robot X) (robot Y) (ok X) (ok Y) (expert X)) (sequence (job A) (special B))"
    problem = load_text(TOKEN, state)
    first, _ = plan(problem.task, problem.goal_calls[0])
    assert first[0].cost == 13 and first[0].agents == ["X"]  # the greedy choice
    found = list(search(problem))
    assert [s.total for s in found] == [26, 29, 29]
    best = found[0]
    assert [s.configuration.agents for s in best.steps] == [["Y"], ["X"]]
    assert best.steps[0].changes == ("(not (ok Y))", "(done A)")
    assert [s.steps[0].configuration.agents for s in found[1:]] == [["X"], ["Y"]]


def test_an_impossible_step_is_named_with_its_reason() -> None:
    """Two special jobs: the expert X can do one, not both (it is no longer ok):
    step 2 has no configuration in any state step 1 leaves."""
    state = "(state (robot X) (ok X) (expert X)) (sequence (special A) (special B))"
    problem = load_text(TOKEN, state)
    searching = search(problem)
    assert list(searching) == []
    blocked = searching.blocked()
    assert blocked is not None
    step, task, report = blocked
    assert step == 1 and ("ok", "X") not in task.facts
    (dead,) = report.dead.values()
    assert dead.reason == "no fact matches (ok ?r) with ?r = X"


def sequence_of(example: Generated) -> Problem:
    """The generated problem with a second goal: do the task for R2 after R1."""
    problem = solve(example)
    goal = problem.goal.model_copy(update={"call": Atom(predicate="do-task", args=("R2",))})
    return Problem(
        problem.domain,
        problem.state,
        problem.goal,
        problem.task,
        goals=(problem.goal, goal),
    )


@pytest.mark.quick(20)
@PROPERTY
@given(generated())
def test_one_goal_sequences_are_plans(example: Generated) -> None:
    problem = solve(example)
    configs, _ = plan(problem.task, problem.goal_call, limit=5)
    sequences = list(islice(search(problem), 5))
    assert [s.total for s in sequences] == [c.cost for c in configs]
    assert [s.steps[0].configuration for s in sequences] == configs


@pytest.mark.quick(20)
@PROPERTY
@given(generated())
def test_sequences_come_cheapest_first_and_every_step_is_admissible(example: Generated) -> None:
    problem = sequence_of(example)
    found = list(islice(search(problem), 12))
    for before, after in pairwise(found):
        assert before.total <= after.total
    for planned in found:
        state = problem.state
        total = sum(s.configuration.cost for s in planned.steps)
        assert planned.total == level(total)  # both at eleven digits (no costs here have more)
        for step in planned.steps:
            assert problems(step.configuration, problem.domain, state) == []
            facts = [(a.predicate, *a.args) for a in state.facts]
            kept = [f for f in facts if f"(not {atom_text(f)})" not in step.changes]
            added = [c for c in step.changes if not c.startswith("(not ")]
            atoms = [*kept, *(tuple(c[1:-1].split()) for c in added)]
            state = state.model_copy(
                update={"facts": tuple(Atom(predicate=a[0], args=a[1:]) for a in atoms)}
            )


# Found by the property below at 1,000 examples: sequences of 2.9, summed
# left to right, and 2.9000000000000004.
TIES = Generated(
    """\
(make-functionality :name '(sens1 ?r)
  :out '((d1 ?r)))
(make-functionality :name '(filt1 ?r)
  :in '((d1 ?r))
  :out '((d1 ?r)))
(make-functionality :name '(p1-1 ?h ?r)
  :in '((d1 ?h))
  :out '((need1 ?r)))
(make-functionality :name '(loc ?r)
  :precond '((in ?r ?room))
  :out '((pos ?r ?room)))
(make-functionality :name '(act ?r)
  :precond '((in ?r ?where))
  :in '((need1 ?r) (pos ?r ?where)))
(make-functionality :name '(mon ?r)
  :in '((need1 ?r)))
(make-config-method :name '(loop1 ?x)
  :in '((?g (d1 ?x)))
  :out '((?g (d1 ?x)))
  :body '((?g (filt1 ?x))))
(make-config-method :name '(get-d1 ?x)
  :out '((?f2 (d1 ?x)))
  :channels '(((local ?x) ?f1 ?f2 (d1 ?x)) ((local ?x) ?f2 ?f2 (d1 ?x)))
  :body '((?f1 (sens1 ?x)) (?f2 (loop1 ?x))))
(make-config-method :name '(get-d1 ?x)
  :out '((?f1 (d1 ?x)))
  :body '((?f1 (sens1 ?x))))
(make-config-method :name '(get-need1 ?h ?r)
  :out '((?f0 (need1 ?r)))
  :channels '(((local ?h) ?f1 ?f0 (d1 ?h)))
  :body '((?f0 (p1-1 ?h ?r)) (?f1 (sens1 ?h))))
(make-config-method :name '(get-need1 ?h ?r)
  :out '((?f0 (need1 ?r)))
  :channels '(((local ?h) ?f1 ?f0 (d1 ?h)))
  :body '((?f0 (p1-1 ?h ?r)) (?f1 (sens1 ?h))))
(make-config-method :name '(do-task ?r)
  :precond '((robot ?h) (in ?r ?where))
  :channels '(((global ?h ?r) ?f1 ?f0 (need1 ?r)) ((local ?r) ?fl ?f0 (pos ?r ?where)))
  :body '((?f0 (act ?r)) (?f1 (get-need1 ?h ?r)) (?fl (loc ?r))))
""",
    """\
(state robot(R1), robot(R2), in(R1, Room1), in(R2, Room1), broken(R1), broken(R2),
       device(R1), device(R2))

(goal (do-task R1))
""",
    Weights(robot=0.1, global_=0.1, local=0.1, functionality=0.1, device=0.2),
)


@pytest.mark.quick(20)
@PROPERTY
@given(generated())
@example(TIES)
def test_equal_totals_come_in_the_order_of_their_steps(example: Generated) -> None:
    """Three steps (R1, R2, then R1 again): the bound of a prefix sums its
    steps right to left, a total left to right. With decimal weights the two
    floats of one sum may differ in the last bit; ranked by the floats, a
    sequence whose steps rank later could come first at equal cost."""
    problem = solve(example)
    goals = (*sequence_of(example).goal_calls, problem.goal_call)
    found = list(islice(SequenceSearch(goals, problem.task), 12))
    for before, after in pairwise(found):
        assert before.total <= after.total
        if before.total == after.total:
            ranks = [tuple(s.configuration.derivation for s in p.steps) for p in (before, after)]
            assert ranks[0] < ranks[1]


def test_json_schema_of_sequences() -> None:
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "cfgplan",
            "plan",
            str(STEPS.relative_to(ROOT)),
            str(SEQUENCE.relative_to(ROOT)),
            "-k",
            "2",
            "--format",
            "json",
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    assert list(doc) == ["goals", "sequences", "communication_checked", "stats"]
    first = doc["sequences"][0]
    assert (first["rank"], first["total_cost"]) == (1, 88)
    assert [s["goal"] for s in first["steps"]] == doc["goals"]
    assert first["steps"][0]["state_changes"] == ["(not (in Pippi Room1))", "(in Pippi Room2)"]
    assert first["steps"][1]["configuration"]["cost"] == 44


def test_goals_given_on_the_command_line_make_a_sequence() -> None:
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "cfgplan",
            "plan",
            str(STEPS.relative_to(ROOT)),
            "domains/cross-door/state-6.2.2-step1.lisp",
            "--goal",
            "(do-cross-door Pippi Door1)",
            "--goal",
            "(do-cross-door Emil Door1)",
            "--format",
            "jsonl",
            "-k",
            "1",
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )
    # step1's door is only in Room1: Emil's helper in Room2 cannot see it
    assert out.returncode == 3, out.stderr
    assert "step 2, do-cross-door(Emil, Door1), has no configuration" in out.stderr


def test_a_step_with_independent_parts_is_searched_in_parts_as_a_run_is() -> None:
    """A sequence's steps are assembled as ``plan -k`` is (plan.in_parts):
    a convoy's rooms are searched apart for a step too, and the step lists
    what the plain search lists, labels and order included."""
    problem = load_text(*ecology(6, 2, 1))
    sequences = SequenceSearch((problem.goal_call,), problem.task, limit=5)
    listed = list(sequences)
    assert isinstance(sequences.ranked(0, problem.task.facts).search, Combined)
    plain, _ = plan(
        problem.task, problem.goal_call, limit=5, options=SearchOptions(components=False)
    )
    assert [s.steps[0].configuration for s in listed] == plain


def every_sequence(
    problem: Problem, goals: tuple[tuple[str, ...], ...]
) -> list[tuple[float, tuple[int, ...], tuple[Configuration, ...]]]:
    """Every sequence of ``goals``, by brute force: each step's configurations
    listed whole (``--all``) in the state the steps before it leave, every
    combination kept; sorted as a sequence search must list them (total, then
    each step's rank, the first step first)."""
    found = []

    def walk(
        task: Task, step: int, ranks: tuple[int, ...], configs: tuple[Configuration, ...]
    ) -> None:
        if step == len(goals):
            total = level(sum(c.cost for c in configs))
            found.append((total, ranks, configs))
            return
        listed, _ = plan(task, goals[step], limit=None)
        for j, config in enumerate(listed):
            facts, _ = apply(task.facts, config.effects)
            walk(derive(task, facts), step + 1, (*ranks, j), (*configs, config))

    walk(problem.task, 0, (), ())
    return sorted(found, key=lambda s: (s[0], s[1]))


@pytest.mark.quick(20)
@PROPERTY
@given(generated())
def test_sequences_are_those_of_every_step_listed_whole(example: Generated) -> None:
    """Differential: the sequence search lists what the brute force of
    :func:`every_sequence` lists, in its order, whether the steps change the
    state (postconditions) or not (then a step's later configurations are
    never planned to price its offers when no later step reads what it
    changes, :func:`unseen`)."""
    problem = sequence_of(example)
    goals = problem.goal_calls
    expected = every_sequence(problem, goals)[:12]
    found = list(islice(SequenceSearch(goals, problem.task), 12))
    assert [s.total for s in found] == [total for total, _, _ in expected]
    listed = [tuple(s.configuration for s in p.steps) for p in found]
    # equal totals in the order of their steps' ranks: the configurations
    # themselves, as ranks of equal-cost configurations are the brute force's
    assert listed == [configs for _, _, configs in expected]


def test_a_sequence_of_steps_whose_changes_are_unseen_plans_each_step_once() -> None:
    """Two goals whose postconditions (a sensor was used) no step reads: of each step's
    configurations (3 x 3: a helper for each of two kinds) the first is
    planned, and the next one, offered when the first is taken, before the
    best sequence is listed (priced without the later steps, every one of
    step 1's was planned first)."""
    domain = """
(make-functionality :name '(sense ?h ?k) :precond '((helper ?h)) :out '((data ?h ?k))
  :postcond '((used ?h ?k)))
(make-functionality :name '(use ?r) :in '((data ?r k1) (data ?r k2)))
(make-config-method :name '(get ?r ?k) :precond '((helper ?h))
  :out '((?b (data ?r ?k)))
  :channels '(((global ?h ?r) ?a ?b (data ?h ?k)))
  :body '((?a (sense ?h ?k)) (?b (relay ?r ?h ?k))))
(make-functionality :name '(relay ?r ?h ?k) :in '((data ?h ?k)) :out '((data ?r ?k)))
(make-config-method :name '(mission ?r)
  :channels '(((local ?r) ?a ?f (data ?r k1)) ((local ?r) ?b ?f (data ?r k2)))
  :body '((?a (get ?r k1)) (?b (get ?r k2)) (?f (use ?r))))
"""
    helpers = " ".join(f"(robot H{i}) (helper H{i})" for i in range(1, 4))
    state = f"(state (robot G1) (robot G2) {helpers}) (sequence (mission G1) (mission G2))"
    problem = load_text(domain, state)
    assert unseen(problem.task, problem.goal_calls) == (True, True)
    searching = SequenceSearch(problem.goal_calls, problem.task)
    (best,) = islice(searching, 1)
    assert [len(r.found) for r in searching._ranked.values()] == [2, 2]
    expected = every_sequence(problem, problem.goal_calls)[0]
    assert best.total == expected[0]
    assert tuple(s.configuration for s in best.steps) == expected[2]


def test_what_a_step_changes_is_seen_by_a_later_step_that_reads_it() -> None:
    """The expert is no longer ok after one special job; the next job reads
    (ok ?r): step 1's changes are seen. The last step has no later one."""
    state = "(state (robot X) (ok X) (expert X)) (sequence (special A) (special B))"
    problem = load_text(TOKEN, state)
    assert ("ok", "?") in touched(problem.task, problem.goal_calls[0]).writes
    assert unseen(problem.task, problem.goal_calls) == (False, True)


MOVES = """\
(make-functionality :name '(see ?h ?r) :precond '((helper ?h)) :out '((view ?r)))
(make-functionality :name '(go ?r ?a ?b) :precond '((at ?r ?a)) :in '((view ?r))
  :postcond '((not (at ?r ?a)) (at ?r ?b)))
(make-config-method :name '(move ?r ?b) :precond '((at ?r ?a) (helper ?h))
  :channels '(((global ?h ?r) ?s ?g (view ?r)))
  :body '((?s (see ?h ?r)) (?g (go ?r ?a ?b))))
"""


@pytest.mark.parametrize(
    ("goals", "expected"),
    [
        ("(move G1 Hall) (move G2 Hall)", (True, True)),  # G2's step reads (at G2 ...) only
        ("(move G1 Hall) (move G1 Lab)", (False, True)),  # the robot that moved moves again
    ],
)
def test_a_robot_that_moved_is_seen_only_by_the_steps_that_read_where_it_is(
    goals: str, expected: tuple[bool, ...]
) -> None:
    helpers = " ".join(f"(robot H{i}) (helper H{i})" for i in range(1, 4))
    state = f"(state (robot G1) (robot G2) (at G1 Dock) (at G2 Dock) {helpers}) (sequence {goals})"
    problem = load_text(MOVES, state)
    assert unseen(problem.task, problem.goal_calls) == expected
    found = list(islice(SequenceSearch(problem.goal_calls, problem.task), 20))
    brute = every_sequence(problem, problem.goal_calls)[:20]
    assert [s.total for s in found] == [total for total, _, _ in brute]
    assert [tuple(s.configuration for s in p.steps) for p in found] == [c for _, _, c in brute]
    assert found[0].steps[-1].changes[-1].startswith("(at G")


def test_a_robot_that_moves_twice_leaves_one_state_whoever_helps_it() -> None:
    """Step 2 reads where G1 is, which step 1 changes: seen. But every
    configuration of step 1 moves G1 from Dock to Hall (the one functionality
    with a postcondition is in every expansion, with one binding), so step 1
    leaves one state: its first configuration, and the next one offered, are
    the only ones planned (of 3, one a helper)."""
    helpers = " ".join(f"(robot H{i}) (helper H{i})" for i in range(1, 4))
    state = f"(state (robot G1) (at G1 Dock) {helpers}) (sequence (move G1 Hall) (move G1 Lab))"
    problem = load_text(MOVES, state)
    assert unseen(problem.task, problem.goal_calls) == (False, True)
    assert fixed_effects(problem.task, problem.goal_calls[0], SearchOptions()) == (
        (False, ("at", "G1", "Dock")),
        (True, ("at", "G1", "Hall")),
    )
    searching = SequenceSearch(problem.goal_calls, problem.task)
    (best,) = islice(searching, 1)
    first = searching._ranked[(0, problem.task.facts)]
    assert len(first.found) == 2
    assert best.total == every_sequence(problem, problem.goal_calls)[0][0]


def test_effects_that_depend_on_the_configuration_are_not_fixed() -> None:
    """(special ?g) and (job ?g) may be done by X or Y: the robot no longer ok
    depends on the configuration."""
    state = "(state (robot X) (robot Y) (ok X) (ok Y) (expert X)) (sequence (job A) (special B))"
    problem = load_text(TOKEN, state)
    assert fixed_effects(problem.task, problem.goal_calls[0], SearchOptions()) is None
