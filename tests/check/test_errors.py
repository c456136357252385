"""The checker's errors, rendered: ``file:line:col``, the source line and a caret
under the offending column (thesis 4.4); an ``(eval ...)`` outside the safe
subset is reported, never run."""

from __future__ import annotations

import pytest

from cfgplan.check import check
from cfgplan.check.evaluate import EvalFailure, holds
from cfgplan.diagnostics import Diagnostic
from cfgplan.ir.model import Eval
from cfgplan.syntax.reader import domain_from, parse
from tests.syntax.test_errors import FUNCTIONALITIES, assert_rendered


def checker_errors(text: str) -> list[Diagnostic]:
    return [d for d in check(domain_from(parse(text, "t.lisp"))) if d.is_error]


def _method(body: str, channels: str = "") -> str:
    return (
        FUNCTIONALITIES
        + "(make-config-method :name '(get-door-info ?r ?d)\n"
        + "  :precond '((camera ?r) (door ?d))\n"
        + (f"  :channels '({channels})\n" if channels else "")
        + f"  :body '({body}))\n"
    )


def test_body_naming_an_undefined_method() -> None:
    text = _method("(?f1 (camera ?r)) (?f2 (measure-window ?r ?d))")
    (d,) = checker_errors(text)
    assert_rendered(d, text, 5, 34, "no functionality or method (measure-window ...)")


def test_channel_label_not_in_body() -> None:
    text = _method(
        "(?f1 (camera ?r)) (?f2 (measure-door ?r ?d))", "((local ?r) ?f1 ?f3 (image ?r))"
    )
    (d,) = checker_errors(text)
    assert_rendered(d, text, 5, 15, "channel target ?f3 is not a label of the body")


def test_channel_descriptor_not_produced() -> None:
    text = _method(
        "(?f1 (camera ?r)) (?f2 (measure-door ?r ?d))", "((local ?r) ?f1 ?f2 (sound ?r))"
    )
    found = checker_errors(text)
    assert [d.message for d in found] == [
        "channel data (sound ?r) is not produced by ?f1 (camera ?r)",
        "channel data (sound ?r) is not consumed by ?f2 (measure-door ?r ?d)",
    ]
    out = assert_rendered(found[0], text, 5, 15, "is not produced by ?f1 (camera ?r)")
    assert "hint: it produces (image ?r)" in out


def test_arity_mismatch() -> None:
    text = _method("(?f1 (camera ?r ?d)) (?f2 (measure-door ?r ?d))")
    (d,) = checker_errors(text)
    assert_rendered(d, text, 5, 16, "arity mismatch: (camera ...) takes 1 argument, found 2")


@pytest.mark.parametrize(
    ("expr", "message"),
    [
        ("(shell-command (quote rm))", "eval may not call shell-command"),
        ("(exit)", "eval may not call exit"),
        ("(print (quote pwned))", "eval may not call print"),
        ("(progn (quit) t)", "eval may not call progn"),
    ],
)
def test_eval_outside_the_safe_subset_is_reported_not_run(
    expr: str, message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    text = FUNCTIONALITIES + (
        "(make-config-method :name '(get-door-info ?r ?d)\n"
        f"  :precond '((camera ?r) (eval {expr}))\n"
        "  :body '((?f1 (camera ?r)) (?f2 (measure-door ?r ?d))))\n"
    )
    (d,) = checker_errors(text)
    assert_rendered(d, text, 4, 26, message)
    # Interpreting it (as the planner would) refuses it too: nothing is executed.
    test = domain_from(parse(text, "t.lisp")).methods[0].precond[1]
    assert isinstance(test, Eval)
    with pytest.raises(EvalFailure, match="eval may not call"):
        holds(test.expr, {})
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == ""  # print never ran; exit/quit never ran
