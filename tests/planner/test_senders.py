"""Where a method instance can send its outputs from (cfgplan/planner/ground.py;
thesis 4.5 steps 3d and 4): the expansions whose channel can never get its
sending end onto the robot it declares are dead ends from the start."""

from __future__ import annotations

from benchmarks.families import any_delegation
from cfgplan.planner import plan
from cfgplan.planner.explain import explain
from cfgplan.planner.plan import analysis
from tests.planner.problems import load_text

RELAY = """
(make-functionality :name '(cam ?r) :precond '((cam ?r)) :out '((img ?r)))
(make-functionality :name '(pass ?h ?r) :in '((img ?h)) :out '((img ?r)))
(make-functionality :name '(use ?r) :in '((img ?r)))
(make-config-method :name '(feed ?r) :precond '((cam ?r))
  :out '((?a (img ?r))) :body '((?a (cam ?r))))
(make-config-method :name '(feed ?r) :precond '((robot ?h) (cam ?h))
  :out '((?p (img ?r))) :channels '(((global ?h ?r) ?c ?p (img ?h)))
  :body '((?c (cam ?h)) (?p (pass ?h ?r))))
(make-config-method :name '(go ?r)
  :channels '(((local ?r) ?x ?u (img ?r))) :body '((?x (feed ?r)) (?u (use ?r))))
"""


def test_a_channel_from_a_method_that_sends_only_elsewhere_is_a_dead_end_with_its_reason() -> None:
    """feed(A) can only relay B's image from a pass(B, A) on B: the (local A)
    channel of go(A) can never start on A. Said once, at go(A)'s version,
    naming where feed(A) can send from (the search found it only below
    feed(A), at the pass functionality placed on B)."""
    problem = load_text(RELAY, "(state (robot A) (robot B) (cam B)) (goal (go A))")
    configs, run = plan(problem.task, problem.goal_call, limit=None)
    assert configs == []
    text = "\n".join(explain(run.report, "go(A)"))
    assert "go(A), version 1" in text
    assert "declared (local A) but feed(A) can send (img A) only from B" in text
    grounder = analysis(problem.task).grounder
    assert grounder.placement.senders(("feed", "A")) == {("img", "A"): frozenset({"B"})}


def test_where_a_camera_is_on_the_robot_itself_nothing_is_cut() -> None:
    """feed(A) can now also send from A (its own camera, or a pass(A, A)):
    go(A) is expanded, and both configurations on A are found (the relay
    from B is still misplaced, found by the search at the pass on B)."""
    problem = load_text(RELAY, "(state (robot A) (robot B) (cam A) (cam B)) (goal (go A))")
    configs, _ = plan(problem.task, problem.goal_call, limit=None)
    assert [(c.cost, c.agents) for c in configs] == [(13, ["A"]), (17, ["A"])]
    grounder = analysis(problem.task).grounder
    assert grounder.placement.senders(("feed", "A")) == {("img", "A"): frozenset({"A", "B"})}


def test_delegation_to_any_robot_is_the_least_fixpoint_of_its_recursion() -> None:
    """Every chain of delegations ends where the camera is (r2): a (get ?h ?o)
    on another robot can only send from r2, so its version that needs its own
    datum on ?h is cut, and with it the whole subtree the search would have
    walked to find that out; --all at 6 robots expands a few hundred method
    instances (the search without the cut: over 74,000 at 5 robots for -k 1)."""
    problem = load_text(*any_delegation(6))
    grounder = analysis(problem.task).grounder
    assert grounder.placement.senders(("get", "r3", "o1")) == {("e", "r3", "o1"): frozenset({"r2"})}
    assert grounder.placement.senders(("get", "r4", "r1", "o1")) == {
        ("e", "r1", "o1"): frozenset({"r2"})
    }
    configs, run = plan(problem.task, problem.goal_call, limit=None)
    assert [(c.cost, c.agents) for c in configs] == [(30, ["r1", "r2"])]
    assert run.stats.expansions < 2_000
