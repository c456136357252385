"""The static checker (thesis 3.2-3.5, 4.4): one test per check, with the span it
reports. Data flow, variables and preconditions: test_flow.py."""

from __future__ import annotations

from pathlib import Path

import pytest

from cfgplan.check import check
from cfgplan.diagnostics import render_all
from cfgplan.syntax.reader import read_domain, read_state
from tests.check.checking import BASE, GOOD, at, loc, only, run

ROOT = Path(__file__).resolve().parents[2]
DOMAINS = sorted((ROOT / "domains").glob("*/domain*.lisp"))
PAIRS = [(d, s) for d in DOMAINS for s in sorted(d.parent.glob("state-*.lisp"))]

# -- the bundled domains ---------------------------------------------------------


def test_bundled_domains_found() -> None:
    assert len(DOMAINS) >= 4 and len(PAIRS) >= 10


@pytest.mark.parametrize("domain_path", DOMAINS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_bundled_domain_has_no_errors(domain_path: Path) -> None:
    domain, text = read_domain(domain_path)
    found = check(domain)
    errors = [d for d in found if d.is_error]
    assert errors == [], render_all(found, {str(domain_path): text})


@pytest.mark.parametrize(
    ("domain_path", "state_path"),
    PAIRS,
    ids=[f"{d.parent.name}/{d.name}+{s.name}" for d, s in PAIRS],
)
def test_bundled_domain_and_state_have_no_errors(domain_path: Path, state_path: Path) -> None:
    domain, dtext = read_domain(domain_path)
    state, stext = read_state(state_path)
    assert state.goal is not None or state.sequence  # a goal, or goals in order
    found = check(domain, state)
    errors = [d for d in found if d.is_error]
    sources = {str(domain_path): dtext, str(state_path): stext}
    assert errors == [], render_all(found, sources)


def test_clean_tiny_domain_has_no_diagnostics() -> None:
    assert run(BASE + GOOD) == []


# -- calls: name and arity -------------------------------------------------------


def test_body_calls_undefined_name() -> None:
    text = BASE + GOOD.replace("(?f1 (camera ?r))", "(?f1 (lens ?r))")
    d = only(run(text))
    assert "(lens ...) with 1 argument is defined" in d.message
    assert "?f1 calls (lens ?r)" in d.message
    assert loc(d) == at(text, "(lens ?r)") == "8:16"
    assert d.hint is None  # close to no defined name


def test_body_call_misspelt_gets_did_you_mean() -> None:
    """A misspelt call in a method body names the functionality or
    method it is close to, as a misspelt goal does (one rule:
    :func:`cfgplan.diagnostics.did_you_mean`); before, only a slip in case did."""
    detect = (
        "(make-functionality :name '(detect-robot ?r ?o) :in '((image ?r)) :out '((pos ?r ?o)))\n"
    )
    method = """\
(make-config-method :name '(find ?r ?o)
  :precond '((camera ?r))
  :channels '(((local ?r) ?c ?d (image ?r)))
  :body '((?c (camera ?r)) (?d (detect-robt ?r ?o))))
"""
    text = BASE + detect + method
    d = only(run(text))
    assert "?d calls (detect-robt ?r ?o), but no functionality or method" in d.message
    assert d.hint == "did you mean detect-robot?"
    assert loc(d) == at(text, "(detect-robt")
    kamera = only(run(BASE + GOOD.replace("(?f1 (camera ?r))", "(?f1 (kamera ?r))")))
    assert kamera.hint == "did you mean camera?"


def test_body_call_differing_in_case_gets_hint() -> None:
    text = BASE + GOOD.replace("(?f2 (measure-door", "(?f2 (Measure-Door")
    d = only(run(text))
    assert "no functionality or method (Measure-Door ...)" in d.message
    assert d.hint == "symbols are case-sensitive: did you mean measure-door?"
    assert loc(d) == at(text, "(Measure-Door") == "8:34"


TWO_ARITIES = (
    GOOD
    + """\
(make-config-method :name '(get-door-info ?h ?r ?d)
  :out '((?f1 (pos ?r ?d)))
  :body '((?f1 (get-door-info ?r ?d))))
(make-config-method :name '(top ?r ?d)
  :body '((?f1 (get-door-info ?r ?d)) (?f2 (get-door-info ?r ?r ?d))))
"""
)


def test_name_and_arity_identify_a_method() -> None:
    assert run(BASE + TWO_ARITIES) == []


def test_arity_mismatch() -> None:
    text = BASE + TWO_ARITIES.replace(
        "(?f2 (get-door-info ?r ?r ?d))", "(?f2 (get-door-info ?r ?r ?d ?d))"
    )
    d = only(run(text))
    assert d.message == "arity mismatch: (get-door-info ...) takes 2 or 3 arguments, found 4"
    assert loc(d) == at(text, "(get-door-info ?r ?r ?d ?d)") == "13:44"


def test_name_both_functionality_and_method() -> None:
    text = BASE + "(make-config-method :name '(camera ?r) :body '((?f1 (measure-door ?r D1))))\n"
    d = only(run(text))
    assert "(camera ...) with 1 argument is both a functionality and a method" in d.message
    assert "line 1" in d.message
    assert loc(d) == at(text, "(camera ?r) :body") == "4:28"


def test_same_name_other_arity_is_not_a_clash() -> None:
    text = BASE + "(make-config-method :name '(camera ?r ?x) :body '((?f1 (camera ?r))))\n"
    assert [d for d in run(text) if d.is_error] == []


def test_duplicate_functionality() -> None:
    text = BASE + "(make-functionality :name '(camera ?r) :out '((photo ?r)))\n"
    d = only(run(text))
    assert "functionality (camera ...) with 1 argument is defined twice" in d.message
    assert "the first is at line 1" in d.message
    assert loc(d) == at(text, "(camera ?r)", 2) == "4:28"


# -- labels ----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("?f1 ?f2 (image", "?f9 ?f2 (image", "channel source ?f9 is not a label of the body"),
        ("?f1 ?f2 (image", "?f1 ?f7 (image", "channel target ?f7 is not a label of the body"),
    ],
)
def test_channel_label_not_in_body(old: str, new: str, message: str) -> None:
    text = BASE + GOOD.replace(old, new)
    d = only(run(text))
    assert message in d.message
    assert d.hint == "body labels: ?f1, ?f2"
    assert loc(d) == at(text, "((local ?r)") == "7:15"


def test_out_label_not_in_body() -> None:
    text = BASE + GOOD.replace("(?f2 (orient ?r ?d))", "(?f3 (orient ?r ?d))")
    d = only(run(text))
    assert ":out label ?f3 is not a label of the body" in d.message
    assert loc(d) == at(text, "(?f3 (orient") == "6:28"


def test_in_label_not_in_body() -> None:
    text = BASE + GOOD.replace(":out '(", ":in '((?f5 (image ?r))) :out '(")
    d = only(run(text))
    assert ":in label ?f5 is not a label of the body" in d.message
    assert loc(d) == at(text, "(?f5 (image") == "6:9"


def test_duplicate_body_label() -> None:
    text = BASE + GOOD.replace("(?f2 (measure-door ?r ?d))", "(?f1 (measure-door ?r ?d))")
    found = run(text)
    d = [x for x in found if "used twice" in x.message]
    assert len(d) == 1
    assert "body label ?f1 is used twice" in d[0].message and "line 8" in d[0].message
    assert loc(d[0]) == at(text, "(?f1 (measure-door") == "8:29"


# -- forms -----------------------------------------------------------------------


def test_functionality_without_in_or_out() -> None:
    text = BASE + "(make-functionality :name '(idle ?r)\n  :precond '((robot ?r)))\n"
    d = only(run(text))
    assert d.message == "functionality (idle ?r) has neither :in nor :out"
    assert loc(d) == "4:1"


@pytest.mark.parametrize("body", [":body '()", ":body nil", ""])
def test_method_with_empty_body(body: str) -> None:
    text = BASE + f"(make-config-method :name '(nothing ?r) {body})\n"
    d = only(run(text))
    assert d.message == "method (nothing ?r) has an empty :body"
    assert loc(d) == "4:1"


def test_diagnostics_are_sorted_by_position() -> None:
    text = BASE + GOOD.replace("(?f1 (camera ?r))", "(?f1 (kamera ?r))").replace(
        "((local ?r) ?f1 ?f2", "((local ?r) ?f1 ?f9"
    )
    text += "(make-functionality :name '(idle ?r))\n"
    found = run(text, "(state (robot Pippi))\n(goal (nope Pippi))\n")
    keys = [(d.span.file, d.span.line, d.span.column) for d in found if d.span is not None]
    assert len(keys) == len(found) == 4
    assert keys == sorted(keys, key=lambda k: (k[0] != "t.lisp", k[1], k[2]))
    assert found[-1].span is not None and found[-1].span.file == "s.lisp"


def test_no_goal_hint_names_a_method_of_this_domain(tmp_path: Path) -> None:
    """The hint names the top method of the domain at hand."""
    from cfgplan.diagnostics import CfgplanError
    from cfgplan.problem import load

    root = Path(__file__).resolve().parents[2] / "domains"
    (tmp_path / "s.lisp").write_text("(state (robot Vacu))\n")
    with pytest.raises(CfgplanError) as caught:
        load(root / "docking/domain.lisp", tmp_path / "s.lisp")
    (d,) = caught.value.diagnostics
    assert d.hint == "add (goal (do-dock R S)) to the state file, or pass --goal"
