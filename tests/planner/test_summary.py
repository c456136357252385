"""The static summaries of ground instances (cfgplan.planner.bound): what
every expansion of an instance holds, intersected over its method versions
and bindings, and the least it can cost; computed without recursion, so a
hierarchy far deeper than Python's recursion limit is summarised.
"""

from __future__ import annotations

import sys

from benchmarks.fuzz_inputs import chain
from cfgplan.planner import plan
from cfgplan.planner.bound import Summaries
from cfgplan.planner.graph import graph_of
from cfgplan.planner.ground import Grounder
from tests.planner.problems import load_text

TWO_VERSIONS = """\
(make-functionality :name '(sense ?r) :out '((d ?r)))
(make-functionality :name '(filter ?r) :in '((d ?r)) :out '((e ?r)))
(make-functionality :name '(smooth ?r) :in '((d ?r)) :out '((e ?r)))
(make-functionality :name '(act ?r) :in '((e ?r)))
(make-config-method :name '(get ?r) :out '((?f (e ?r)))
  :channels '(((local ?r) ?s ?f (d ?r)))
  :body '((?s (sense ?r)) (?f (filter ?r))))
(make-config-method :name '(get ?r) :precond '((helper ?h))
  :out '((?f (e ?r)))
  :channels '(((global ?h ?r) ?s ?f (d ?h)))
  :body '((?s (sense ?h)) (?f (smooth ?r))))
(make-config-method :name '(go ?r) :channels '(((local ?r) ?g ?a (e ?r)))
  :body '((?g (get ?r)) (?a (act ?r))))
"""


def test_a_summary_holds_what_every_expansion_holds() -> None:
    """``(get A)`` expands by its first version (sense and filter on A) or by
    its second with helper B (sense on B, smooth on A): only A is certain,
    no functionality instance is in both, and the least is two
    functionalities and one local channel."""
    problem = load_text(TWO_VERSIONS, "(state (robot A) (robot B) (helper B)) (goal (go A))")
    summary = Summaries(problem.task).summary(("get", "A"))
    assert summary.feasible
    assert summary.robots == frozenset({"A"})
    assert summary.functionalities == frozenset()
    assert (summary.minimum, summary.wiring) == (2.0, 1.0)
    assert summary.producer(("e", "A")) is None  # filter or smooth: not certain
    only_own = load_text(TWO_VERSIONS, "(state (robot A)) (goal (go A))")
    alone = Summaries(only_own.task).summary(("get", "A"))
    assert alone.functionalities == frozenset({("sense", "A"), ("filter", "A")})
    assert alone.producer(("e", "A")) == ("filter", "A")


def test_a_hierarchy_deeper_than_the_recursion_limit() -> None:
    """A chain of methods deeper than Python's recursion limit
    is summarised and planned without recursion (before: RecursionError in
    the bound at about 330 levels)."""
    depth = sys.getrecursionlimit() + 200
    problem = load_text(chain(depth).decode(), "(state (robot A)) (goal (top A))")
    assert Summaries(problem.task).summary(("m0", "A")).minimum == 1.0
    (config,), _ = plan(problem.task, problem.goal_call)
    assert config.cost == 10 + 2 + 1


def test_the_grounding_memo_s_graph_gives_the_same_summaries() -> None:
    """The search's summaries are a pass over the grounding memo's graph of
    ground instances (:attr:`Summaries.grounder`, the graph the partitioned
    bound reads: it holds what they summarised); with a memo of their own,
    they must be the same, with two helpers (three expansions of ``(get A)``)
    and with none."""
    for state, helpers in (("(robot A) (robot B) (helper B) (helper C)", 2), ("(robot A)", 0)):
        problem = load_text(TWO_VERSIONS, f"(state {state}) (goal (go A))")
        grounder = Grounder(problem.task)
        shared = Summaries(problem.task, grounder)
        own = Summaries(problem.task)
        for call in [("go", "A"), ("get", "A"), ("get", "B"), ("act", "A")]:
            assert shared.summary(call) == own.summary(call)
            if problem.task.is_method(call):
                assert call in graph_of(grounder).instances
        options = graph_of(grounder).instances[("get", "A")].options
        assert len(options) == 1 + helpers
        with_helper = problem.task.versions(("get", "A"))[1]
        assert len(grounder.method_bindings(with_helper, ("get", "A"))) == helpers


def test_a_recursive_instance_costs_its_lightest_derivation() -> None:
    """In a conversion graph (benchmarks/families/shared.py) every
    ``(get ?t)`` can reach itself. Met again inside its own summary, a call
    was summarised as UNKNOWN, costing nothing, and the instances of its
    cycle came out almost free (type 12: 2 and 1, for the converter on top).
    Raised to the least fixpoint of their equations (Knuth's lightest
    derivation, the recursion guard ignored): type 12 costs at least six
    skips from the sensed type 0 (6 x 4) and its sensor (1), over six
    channels; type 11 five skips to type 10 and one forward step (2), over
    six channels."""
    from benchmarks.families import conversion

    problem = load_text(*conversion(12))
    summaries = Summaries(problem.task)
    top = summaries.summary(("get", "T12", "R"))
    assert (top.minimum, top.wiring) == (25.0, 6.0)
    below = summaries.summary(("get", "T11", "R"))
    assert (below.minimum, below.wiring) == (23.0, 6.0)
