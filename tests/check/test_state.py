"""The static checker's checks of a state and goal against a domain
(cfgplan.check.state, thesis 4.4-4.5): one test per check, with the span it
reports."""

from __future__ import annotations

from pathlib import Path

from typer.testing import CliRunner

from cfgplan.cli import commands  # noqa: F401  (loads every command module)
from cfgplan.cli.app import app
from cfgplan.ir.model import Atom, Goal
from tests.check.test_checker import BASE, GOOD, at, loc, only, run

STATE = "(state (robot Pippi) (camera Pippi) (door Door1))\n"


def test_goal_from_state_naming_a_method_is_fine() -> None:
    assert run(BASE + GOOD, STATE + "(goal (get-door-info Pippi Door1))\n") == []


def test_goal_names_no_method() -> None:
    state = STATE + "(goal (open-door Pippi Door1))\n"
    d = only(run(BASE + GOOD, state))
    assert (
        d.message
        == "the goal (open-door Pippi Door1) names no method (open-door ...) with 2 arguments"
    )
    assert d.span is not None and d.span.file == "s.lisp"
    assert loc(d) == "2:7"


def test_goal_case_hint() -> None:
    d = only(run(BASE + GOOD, STATE + "(goal (Get-Door-Info Pippi Door1))\n"))
    assert d.hint == "symbols are case-sensitive: did you mean get-door-info?"


def test_goal_arity_hint() -> None:
    d = only(run(BASE + GOOD, STATE + "(goal (get-door-info Pippi))\n"))
    assert "names no method (get-door-info ...) with 1 argument" in d.message
    assert d.hint == "(get-door-info ...) takes 2 arguments, found 1"


def test_goal_names_a_functionality() -> None:
    d = only(run(BASE + GOOD, STATE + "(goal (camera Pippi))\n"))
    assert d.message == "the goal (camera Pippi) names a functionality, not a method"
    assert loc(d) == "2:7"


def test_goal_argument_overrides_state_goal() -> None:
    goal = Goal(call=Atom(predicate="nope", args=("Pippi",)))
    d = only(run(BASE + GOOD, STATE + "(goal (get-door-info Pippi Door1))\n", goal))
    assert d.message.startswith("the goal (nope Pippi) names no method")
    assert d.span is None


def test_state_predicate_differing_in_case_warns_twice() -> None:
    text = BASE + GOOD
    found = run(text, "(state (Camera Pippi) (door Door1))\n")
    assert [d.severity for d in found] == ["warning", "warning"]
    domain_side, state_side = found  # the domain file is reported first
    assert (
        domain_side.message == "the state has no (camera ...) fact for the precondition (camera ?r)"
    )
    assert domain_side.hint == "symbols are case-sensitive: the state writes Camera"
    assert loc(domain_side) == at(text, "(camera ?r) (door") == "5:14"
    assert (
        state_side.message
        == "no precondition tests (Camera ...), so the fact (Camera Pippi) is never used"
    )
    assert state_side.hint == "symbols are case-sensitive: did you mean camera?"
    assert state_side.span is not None and state_side.span.file == "s.lisp"
    assert loc(state_side) == "1:8"


def test_unused_state_predicate_without_case_twin_is_silent() -> None:
    """A state may describe more of the world than a domain tests."""
    assert run(BASE + GOOD, "(state (heavy B1) (camera Pippi) (door Door1))\n") == []


def test_a_misspelt_fact_is_a_warning_with_a_suggestion() -> None:
    """(camrea Pippi) is tested by nothing; camera is close."""
    d = only(run(BASE + GOOD, "(state (camrea Pippi) (door Door1))\n"), "warning")
    assert d.message == (
        "no precondition tests (camrea ...), so the fact (camrea Pippi) is never used"
    )
    assert d.hint == "did you mean camera?"
    assert loc(d) == "1:8"


def test_devices_are_read_by_the_planner_even_when_untested() -> None:
    assert run(BASE + GOOD, "(state (device Cam) (camera Pippi) (door Door1))\n") == []


def test_goal_spelling_hint() -> None:
    d = only(run(BASE + GOOD, STATE + "(goal (get-dor-info Pippi Door1))\n"))
    assert d.hint == "did you mean get-door-info?"


def test_a_goal_object_no_fact_names_is_a_warning_with_a_suggestion() -> None:
    """``check`` said ok for ``(do-cross-door Bob Door1)`` and for ``PIPPI``,
    which ``plan`` then found no configuration for (a newcomer's report)."""
    unknown = only(run(BASE + GOOD, STATE + "(goal (get-door-info Bob Door1))\n"), "warning")
    assert unknown.severity == "warning"
    assert unknown.message == (
        "the goal (get-door-info Bob Door1) names Bob, which no fact of the state names"
    )
    assert unknown.hint is None and loc(unknown) == "2:7"
    case = only(run(BASE + GOOD, STATE + "(goal (get-door-info PIPPI Door1))\n"), "warning")
    assert case.hint == "symbols are case-sensitive: did you mean Pippi?"
    typo = only(run(BASE + GOOD, STATE + "(goal (get-door-info Pipi Door1))\n"), "warning")
    assert typo.hint == "did you mean Pippi?"


def test_a_goal_object_written_twice_is_named_once_and_numbers_are_objects() -> None:
    found = run(BASE + GOOD, STATE + "(goal (get-door-info Bob Bob))\n")
    assert [d.message.split(" names ")[-1] for d in found if "Bob" in d.message] == [
        "Bob, which no fact of the state names"
    ]
    assert [
        d for d in run(BASE + GOOD, STATE + "(goal (get-door-info 2 Door1))\n") if "2," in d.message
    ] == []


def test_a_fact_object_differing_in_case_from_everywhere_else_is_pointed_out() -> None:
    """``(camera pippi)`` where the other facts and the goal write ``Pippi``:
    the fact is about another object (check said ok, plan said only "no fact
    matches (camera Pippi)"); language.md promises the case is pointed out."""
    state = "(state (robot Pippi) (camera pippi) (door Door1))\n"
    d = only(run(BASE + GOOD, state + "(goal (get-door-info Pippi Door1))\n"), "warning")
    assert d.message == (
        "the fact (camera pippi) names pippi, which differs only in case from Pippi "
        "(written elsewhere)"
    )
    assert d.hint == "symbols are case-sensitive: did you mean Pippi?"
    assert loc(d) == "1:22"
    # One spelling everywhere: nothing to say.
    assert run(BASE + GOOD, STATE + "(goal (get-door-info Pippi Door1))\n") == []


def test_plan_points_out_a_fact_object_differing_in_case(tmp_path: Path) -> None:
    """``cfgplan plan`` prints the warning before saying no configuration is admissible."""
    domain = tmp_path / "d.lisp"
    domain.write_text(BASE + GOOD, "utf-8")
    state = tmp_path / "s.lisp"
    state.write_text(
        "(state (robot Pippi) (camera pippi) (door Door1))\n(goal (get-door-info Pippi Door1))\n",
        "utf-8",
    )
    result = CliRunner().invoke(app, ["plan", str(domain), str(state)])
    assert result.exit_code == 3, result.output
    assert "names pippi, which differs only in case from Pippi" in result.stderr
    assert "did you mean Pippi?" in result.stderr
