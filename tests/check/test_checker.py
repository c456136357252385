"""The static checker (thesis 3.2-3.5, 4.4): one test per check, with the span it reports."""

from __future__ import annotations

from pathlib import Path

import pytest

from cfgplan.check import check
from cfgplan.diagnostics import Diagnostic, render_all
from cfgplan.ir.model import Goal
from cfgplan.syntax.reader import domain_from, parse, read_domain, read_state, state_from

ROOT = Path(__file__).resolve().parents[2]
DOMAINS = sorted((ROOT / "domains").glob("*/domain*.lisp"))
PAIRS = [(d, s) for d in DOMAINS for s in sorted(d.parent.glob("state-*.lisp"))]

# Three functionalities on lines 1-3; the tests append methods from line 4 on.
BASE = """\
(make-functionality :name '(camera ?r) :out '((image ?r)))
(make-functionality :name '(measure-door ?r ?d) :in '((image ?r)) :out '((pos ?r ?d)(orient ?r ?d)))
(make-functionality :name '(cross-door ?r ?d) :in '((pos ?r ?d) (orient ?r ?d)))
"""

GOOD = """\
(make-config-method :name '(get-door-info ?r ?d)
  :precond '((camera ?r) (door ?d))
  :out '((?f2 (pos ?r ?d)) (?f2 (orient ?r ?d)))
  :channels '(((local ?r) ?f1 ?f2 (image ?r)))
  :body '((?f1 (camera ?r)) (?f2 (measure-door ?r ?d))))
"""


def at(text: str, needle: str, nth: int = 1) -> str:
    """``line:col`` of the ``nth`` occurrence of ``needle`` in ``text``."""
    index = -1
    for _ in range(nth):
        index = text.index(needle, index + 1)
    line = text.count("\n", 0, index) + 1
    column = index - (text.rfind("\n", 0, index) + 1) + 1
    return f"{line}:{column}"


def run(text: str, state: str | None = None, goal: Goal | None = None) -> list[Diagnostic]:
    domain = domain_from(parse(text, "t.lisp"))
    world = state_from(parse(state, "s.lisp")) if state is not None else None
    return check(domain, world, goal)


def only(found: list[Diagnostic], severity: str = "error") -> Diagnostic:
    """The one diagnostic of ``severity`` (the message lists all if there are more)."""
    hits = [d for d in found if d.severity == severity]
    assert len(hits) == 1, "\n".join(f"{d.severity}: {d.message} @ {d.span}" for d in found)
    return hits[0]


def loc(d: Diagnostic) -> str:
    assert d.span is not None
    return f"{d.span.line}:{d.span.column}"


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
    text = BASE + GOOD.replace("(?f1 (camera ?r))", "(?f1 (kamera ?r))")
    d = only(run(text))
    assert "(kamera ...) with 1 argument is defined" in d.message
    assert "?f1 calls (kamera ?r)" in d.message
    assert loc(d) == at(text, "(kamera ?r)") == "8:16"
    assert d.hint is None


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


# -- data flow: what the endpoints produce and consume -------------------------


def test_channel_data_not_produced_by_functionality() -> None:
    text = BASE + GOOD.replace("?f1 ?f2 (image ?r)", "?f1 ?f2 (sound ?r)")
    found = run(text)
    d = [x for x in found if "not produced" in x.message]
    assert len(d) == 1
    assert d[0].message == "channel data (sound ?r) is not produced by ?f1 (camera ?r)"
    assert d[0].hint == "it produces (image ?r)"
    assert loc(d[0]) == "7:15"


def test_channel_data_not_consumed_by_functionality() -> None:
    text = BASE + GOOD.replace("(?f1 (camera ?r))", "(?f1 (measure-door ?r ?d))")
    text = text.replace("?f1 ?f2 (image ?r)", "?f1 ?f2 (pos ?r ?d)")
    d = only(run(text))
    assert d.message == "channel data (pos ?r ?d) is not consumed by ?f2 (measure-door ?r ?d)"
    assert d.hint == "it consumes (image ?r)"
    assert loc(d) == "7:15"


def test_descriptor_arity_must_match() -> None:
    text = BASE + GOOD.replace("?f1 ?f2 (image ?r)", "?f1 ?f2 (image ?r ?d)")
    found = run(text)
    assert [(d.message, loc(d)) for d in found] == [
        ("channel data (image ?r ?d) is not produced by ?f1 (camera ?r)", "7:15"),
        ("channel data (image ?r ?d) is not consumed by ?f2 (measure-door ?r ?d)", "7:15"),
    ]


def test_constants_of_a_call_must_match() -> None:
    method = GOOD.replace(":name '(get-door-info ?r ?d)", ":name '(get-door-info ?r)")
    method = method.replace("(door ?d)", "(door Door1)")
    method = method.replace("(measure-door ?r ?d)", "(measure-door ?r Door1)")
    method = method.replace("(?f2 (pos ?r ?d))", "(?f2 (pos ?r Door2))")
    text = BASE + method.replace("(?f2 (orient ?r ?d))", "(?f2 (orient ?r Door1))")
    d = only(run(text))
    assert d.message == ":out data (pos ?r Door2) is not produced by ?f2 (measure-door ?r Door1)"
    assert d.hint == "it produces (pos ?r Door1), (orient ?r Door1)"
    assert loc(d) == at(text, "(?f2 (pos ?r Door2))") == "6:10"


USES_METHOD = """\
(make-config-method :name '(do-cross ?r ?d)
  :precond '((robot ?r) (door ?d))
  :channels '(((local ?r) ?f1 ?f2 (pos ?r ?d)) ((local ?r) ?f1 ?f2 (orient ?r ?d)))
  :body '((?f1 (get-door-info ?r ?d)) (?f2 (cross-door ?r ?d))))
"""


def test_channel_from_method_uses_its_out_ports() -> None:
    assert run(BASE + GOOD + USES_METHOD) == []


def test_channel_data_not_on_out_port_of_method() -> None:
    text = BASE + GOOD.replace("(?f2 (orient ?r ?d))", "").replace(
        ":out '((?f2 (pos ?r ?d)) )", ":out '((?f2 (pos ?r ?d)))"
    )
    text += USES_METHOD
    d = only(run(text))
    assert d.message == "channel data (orient ?r ?d) is not produced by ?f1 (get-door-info ?r ?d)"
    assert d.hint == "it produces (pos ?r ?d) (the :out ports of its method versions)"
    assert loc(d) == at(text, "((local ?r) ?f1 ?f2 (orient") == "11:48"


def test_method_port_substitutes_the_version_parameters() -> None:
    # (get-door-info ?r Door1) produces (pos ?r Door1), never (pos ?r Door2).
    text = BASE + GOOD + USES_METHOD.replace("(get-door-info ?r ?d)", "(get-door-info ?r Door1)")
    text = text.replace("?f1 ?f2 (pos ?r ?d)", "?f1 ?f2 (pos ?r Door2)")
    found = run(text)
    d = only(found)
    assert d.message == (
        "channel data (pos ?r Door2) is not produced by ?f1 (get-door-info ?r Door1)"
    )
    assert d.hint == (
        "it produces (pos ?r Door1), (orient ?r Door1) (the :out ports of its method versions)"
    )
    assert loc(d) == at(text, "((local ?r) ?f1 ?f2 (pos") == "11:15"
    # The other ends match only for some bindings of the caller's ?d: warnings.
    assert [(x.message, loc(x)) for x in found if not x.is_error] == [
        (
            "channel data (pos ?r Door2) is consumed by ?f2 (cross-door ?r ?d) only if ?d = Door2",
            "11:15",
        ),
        (
            "channel data (orient ?r ?d) is produced by ?f1 (get-door-info ?r Door1) "
            "only if ?d = Door1",
            at(text, "((local ?r) ?f1 ?f2 (orient"),
        ),
    ]


def test_in_port_must_be_consumed() -> None:
    text = BASE + GOOD.replace(":out '(", ":in '((?f1 (image ?r))) :out '(")
    d = only(run(text))
    assert d.message == ":in data (image ?r) is not consumed by ?f1 (camera ?r)"
    assert d.hint == "it consumes nothing"
    assert loc(d) == at(text, "(?f1 (image ?r))") == "6:9"


def test_in_port_consumed_passes() -> None:
    text = BASE + GOOD.replace(":out '(", ":in '((?f2 (image ?r))) :out '(")
    assert run(text) == []


def test_out_port_must_be_produced() -> None:
    text = BASE + GOOD.replace("(?f2 (orient ?r ?d))", "(?f1 (orient ?r ?d))")
    d = only(run(text))
    assert d.message == ":out data (orient ?r ?d) is not produced by ?f1 (camera ?r)"
    assert loc(d) == at(text, "(?f1 (orient") == "6:28"


def test_match_only_by_equating_caller_variables_is_a_warning() -> None:
    text = BASE + GOOD.replace("?f1 ?f2 (image ?r)", "?f1 ?f2 (image ?d)")
    found = run(text)
    assert [(d.severity, d.message, loc(d)) for d in found] == [
        (
            "warning",
            "channel data (image ?d) is produced by ?f1 (camera ?r) only if ?r = ?d",
            "7:15",
        ),
        (
            "warning",
            "channel data (image ?d) is consumed by ?f2 (measure-door ?r ?d) only if ?r = ?d",
            "7:15",
        ),
    ]
    assert found[0].hint == "it produces (image ?r); check the variables of both"


def test_two_out_ports_with_same_descriptor() -> None:
    text = BASE + GOOD.replace("(?f2 (orient ?r ?d))", "(?f2 (pos ?r ?d))")
    d = only(run(text))
    assert d.message == "two :out ports give (pos ?r ?d); the first is at line 6"
    assert loc(d) == at(text, "(?f2 (pos ?r ?d))", 2) == "6:28"


# -- variables -------------------------------------------------------------------


def test_channel_variable_bound_by_nothing_is_an_error() -> None:
    """Issue 10: the planner cannot instantiate the channel, so every expansion
    of the method fails and configurations are lost without a word."""
    text = BASE + GOOD.replace("((local ?r) ?f1", "((local ?x) ?f1")
    d = only(run(text))
    assert d.message == (
        "?x is bound by neither the name nor a precondition of (get-door-info ?r ?d), "
        "so no expansion of it can be made"
    )
    assert loc(d) == "7:15"


def test_variable_bound_by_precondition_is_fine() -> None:
    text = BASE + GOOD.replace("((local ?r) ?f1", "((local ?x) ?f1").replace(
        "(door ?d))", "(door ?d) (robot ?x))"
    )
    assert run(text) == []


def test_body_call_variable_bound_by_nothing_is_an_error_once() -> None:
    text = BASE + GOOD.replace("(measure-door ?r ?d)", "(measure-door ?r ?z)")
    text = text.replace(
        ":out '((?f2 (pos ?r ?d)) (?f2 (orient ?r ?d)))", ":out '((?f2 (pos ?r ?z)))"
    )
    found = run(text)
    d = only(found)
    assert d.message.startswith("?z is bound by neither the name nor a precondition")
    assert loc(d) == at(text, "(?f2 (pos ?r ?z))") == "6:10"  # the first use, by position


def test_functionality_variable_not_in_name_is_a_warning() -> None:
    text = "(make-functionality :name '(camera ?r) :out '((image ?r ?q)))\n"
    d = only(run(text), "warning")
    assert d.message == (
        "?q in (image ?r ?q) occurs neither in the name (camera ?r) nor in a precondition"
    )
    assert loc(d) == at(text, "(image") == "1:47"


def test_functionality_output_bound_by_its_precondition_is_fine() -> None:
    """(loc ?r) with (in ?r ?room) produces (pos ?r ?room): the precondition
    binds ?room when the functionality is placed (4.5, 2a), so no warning."""
    text = "(make-functionality :name '(loc ?r) :precond '((in ?r ?room)) :out '((pos ?r ?room)))\n"
    assert run(text) == []


# -- preconditions ---------------------------------------------------------------


def test_eval_outside_safe_subset() -> None:
    text = BASE + GOOD.replace("(door ?d))", "(door ?d)\n  (eval (shell-command (quote rm))))")
    d = only(run(text))
    assert d.message.startswith("eval may not call shell-command")
    assert loc(d) == at(text, "(eval") == "6:3"


def test_eval_problems_each_reported() -> None:
    text = BASE + GOOD.replace("(door ?d))", "(door ?d) (eval (and (exit) (< ?r))) (eval foo))")
    found = [d for d in run(text) if d.is_error]
    assert [d.message.split(";")[0] for d in found] == [
        "eval may not call exit",
        "the bare symbol foo has no value",
    ]
    assert [loc(d) for d in found] == [at(text, "(eval (and"), at(text, "(eval foo")]


def test_eval_variable_never_bound() -> None:
    text = BASE + GOOD.replace("(door ?d))", "(door ?d) (eval (not (eql (quote ?r) (quote ?h)))))")
    d = only(run(text))
    assert d.message.startswith(
        "?h in (eval (not (eql (quote ?r) (quote ?h)))) is bound by neither"
    )
    assert "can never be bound" in d.message
    assert loc(d) == at(text, "(eval") == "5:36"


def test_negation_variable_never_bound() -> None:
    text = BASE + GOOD.replace("(door ?d))", "(door ?d) (not (in ?r ?room)))")
    d = only(run(text))
    assert d.message.startswith("?room in (not (in ?r ?room)) is bound by neither")
    assert loc(d) == at(text, "(not (in") == "5:36"


def test_negation_bound_by_a_later_atom_is_fine() -> None:
    text = BASE + GOOD.replace("(door ?d))", "(not (in ?r ?room)) (door ?d) (in ?d ?room))")
    assert run(text) == []


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
    """Issue 10: the hint names the top method of the domain at hand."""
    from cfgplan.diagnostics import CfgplanError
    from cfgplan.problem import load

    root = Path(__file__).resolve().parents[2] / "domains"
    (tmp_path / "s.lisp").write_text("(state (robot Vacu))\n")
    with pytest.raises(CfgplanError) as caught:
        load(root / "docking/domain.lisp", tmp_path / "s.lisp")
    (d,) = caught.value.diagnostics
    assert d.hint == "add (goal (do-dock R S)) to the state file, or pass --goal"
