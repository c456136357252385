"""Planner semantics of thesis 4.5 on small domains written for the purpose."""

from __future__ import annotations

from pathlib import Path

from cfgplan.configuration.model import Configuration
from cfgplan.planner import Run, plan
from cfgplan.planner.explain import explain
from cfgplan.planner.report import Condition
from cfgplan.problem import Problem, load


def setup(tmp_path: Path, domain: str, state: str) -> Problem:
    d, s = tmp_path / "d.lisp", tmp_path / "s.lisp"
    d.write_text(domain)
    s.write_text(state)
    return load(d, s)


def solve(p: Problem, distinct: bool = True) -> tuple[list[Configuration], Run]:
    return plan(p.task, p.goal_call, limit=None, distinct=distinct)


PIPE = """
(make-functionality :name '(cam ?r) :out '((img ?r)) :freq {cam})
(make-functionality :name '(use ?r) :in '((img ?r)) :freq 10)
(make-config-method :name '(go ?r) :precond '((robot ?r))
  :channels '(((local ?r) ?a ?b (img ?r))) :body '((?a (cam ?r)) (?b (use ?r))))
"""


def test_freq_sender_must_keep_up(tmp_path: Path) -> None:
    """3.5 information admissibility: Freq(sender) against Freq(receiver)."""
    slow = setup(tmp_path, PIPE.format(cam=5), "(state (robot A)) (goal (go A))")
    configs, search = solve(slow)
    assert configs == []
    assert "runs at 5 Hz but feeds use(A) at 10 Hz" in "\n".join(explain(search.report, "go(A)"))
    equal = setup(tmp_path, PIPE.format(cam=10), "(state (robot A)) (goal (go A))")
    assert [c.cost for c in solve(equal)[0]] == [10 + 1 + 2]


def test_local_channel_must_stay_on_its_robot(tmp_path: Path) -> None:
    """A channel declared (local ?r) whose ends land on two robots is inadmissible."""
    domain = """
(make-functionality :name '(cam ?r) :out '((img ?r)))
(make-functionality :name '(use ?r ?o) :in '((img ?o)))
(make-config-method :name '(go ?r) :precond '((robot ?o) (eval (not (eql (quote ?r) (quote ?o)))))
  :channels '(((local ?r) ?a ?b (img ?o))) :body '((?a (cam ?o)) (?b (use ?r ?o))))
"""
    p = setup(tmp_path, domain, "(state (robot A) (robot B)) (goal (go A))")
    configs, search = solve(p)
    assert configs == []
    text = "\n".join(explain(search.report, "go(A)"))
    assert "declared (local A) but it runs from cam(B) on B to use(A, B) on A" in text


def test_reuse_and_merge(tmp_path: Path) -> None:
    """4.5 step 2a: an instance already in C is reused; identical channels merge."""
    domain = """
(make-functionality :name '(cam ?r) :out '((img ?r)))
(make-functionality :name '(use ?r) :in '((img ?r)))
(make-config-method :name '(feed ?r) :out '((?a (img ?r)))
  :channels '() :body '((?a (cam ?r))))
(make-config-method :name '(go ?r) :precond '((robot ?r))
  :channels '(((local ?r) ?x ?u (img ?r)) ((local ?r) ?y ?u (img ?r)))
  :body '((?x (feed ?r)) (?y (feed ?r)) (?u (use ?r))))
"""
    p = setup(tmp_path, domain, "(state (robot A)) (goal (go A))")
    (config,), _ = solve(p)
    assert [f.name for f in config.functionalities] == ["use", "cam"]
    assert len(config.channels) == 1  # the two channels became identical and merged
    assert config.cost == 10 + 1 + 2


def test_recursion_is_pruned(tmp_path: Path) -> None:
    """A method instance repeated on its own expansion path is pruned, not looped."""
    domain = """
(make-functionality :name '(cam ?r) :out '((img ?r)))
(make-functionality :name '(use ?r) :in '((img ?r)))
(make-config-method :name '(feed ?r) :out '((?a (img ?r))) :body '((?a (feed ?r))))
(make-config-method :name '(feed ?r) :out '((?a (img ?r))) :body '((?a (cam ?r))))
(make-config-method :name '(go ?r) :precond '((robot ?r))
  :channels '(((local ?r) ?x ?u (img ?r))) :body '((?x (feed ?r)) (?u (use ?r))))
"""
    p = setup(tmp_path, domain, "(state (robot A)) (goal (go A))")
    configs, search = solve(p)
    assert [c.cost for c in configs] == [13]
    assert any(d.condition is Condition.RECURSION for d in search.report.dead.values())


def test_functionality_preconditions_bind_and_branch(tmp_path: Path) -> None:
    """Functionality preconditions may bind free variables; each binding is a
    branch with its own postconditions P (4.5); (not ATOM) in P deletes."""
    domain = """
(make-functionality :name '(cam ?r) :out '((img ?r)))
(make-functionality :name '(move ?r) :in '((img ?r))
  :precond '((in ?r ?from) (connects ?from ?to))
  :postcond '((in ?r ?to) (not (in ?r ?from))))
(make-config-method :name '(go ?r) :precond '((robot ?r))
  :channels '(((local ?r) ?a ?b (img ?r))) :body '((?a (cam ?r)) (?b (move ?r))))
"""
    state = "(state (robot A) (in A R1) (connects R1 R2) (connects R1 R3)) (goal (go A))"
    p = setup(tmp_path, domain, state)
    distinct, _ = solve(p)
    assert [c.postconditions for c in distinct] == [
        ("(in A R2)", "(not (in A R1))"),
        ("(in A R3)", "(not (in A R1))"),
    ]


def test_rewiring_fails_without_matching_out(tmp_path: Path) -> None:
    """4.5 step 3d: a channel whose data no :out of the expanded version produces
    (under this binding) ends the branch."""
    domain = """
(make-functionality :name '(cam ?r) :out '((img ?r)))
(make-functionality :name '(use ?r) :in '((img ?r)))
(make-config-method :name '(feed ?r ?o) :out '((?a (img ?o))) :body '((?a (cam ?o))))
(make-config-method :name '(go ?r)
  :precond '((robot ?r) (robot ?s) (eval (not (eql (quote ?r) (quote ?s)))))
  :channels '(((local ?r) ?x ?u (img ?r))) :body '((?x (feed ?r ?s)) (?u (use ?r))))
"""
    p = setup(tmp_path, domain, "(state (robot A) (robot B)) (goal (go A))")
    configs, search = solve(p)
    assert configs == []
    assert "no :out entry produces (img A)" in "\n".join(explain(search.report, "go(A)"))


def test_case_mismatch_is_explained(tmp_path: Path) -> None:
    domain = PIPE.format(cam=10)
    p = setup(tmp_path, domain, "(state (robot a)) (goal (go A))")
    configs, search = solve(p)
    assert configs == []
    text = "\n".join(explain(search.report, "go(A)"))
    assert "(robot A): symbols are case-sensitive: did you mean a?" in text
