"""A goal that fails on a near-miss fact: the "no configuration"
explanation names the fact the failed precondition was likely meant to
match, in the words of every "did you mean" of cfgplan."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

import cfgplan.cli.plan  # noqa: F401  (loads the command module)
from cfgplan.cli.app import app
from tests.cli.conftest import ROOT

CLEAN = """\
(make-functionality :name '(vacuum ?r) :in '((room ?r)))
(make-functionality :name '(locate ?r) :out '((room ?r)))
(make-config-method :name '(clean ?r ?room)
  :precond '((robot ?r) (in ?r ?room))
  :channels '(((local ?r) ?l ?v (room ?r)))
  :body '((?l (locate ?r)) (?v (vacuum ?r))))
"""
NEAR = "did you mean Living? the state has (in Vacu Living)"


@pytest.fixture
def files(tmp_path: Path) -> list[str]:
    (tmp_path / "d.lisp").write_text(CLEAN)
    state = "(state (robot Vacu) (robot Robby) (in Robby Kitchen) (in Vacu Living))\n"
    (tmp_path / "s.lisp").write_text(state + "(goal (clean Vacu Livng))\n")
    return [str(tmp_path / "d.lisp"), str(tmp_path / "s.lisp")]


def test_the_explanation_names_the_near_miss(files: list[str]) -> None:
    result = CliRunner().invoke(app, ["plan", *files])
    assert result.exit_code == 3
    assert f"no fact matches (in Vacu Livng): {NEAR}" in result.stderr
    assert result.stdout == ""


def test_the_json_explanation_holds_it_too(files: list[str]) -> None:
    result = CliRunner().invoke(app, ["plan", *files, "--format", "json"])
    assert result.exit_code == 3
    (dead,) = json.loads(result.stdout)["explanation"]["dead_ends"]
    assert dead["failed"] == "(in Vacu Livng)"
    assert dead["reason"] == f"no fact matches (in Vacu Livng): {NEAR}"


@pytest.mark.parametrize(
    "goal",
    [
        "(clean Vacu Garage)",  # no room spelt like it
        "(clean Robby Livng)",  # Living is Vacu's room: two constants differ
    ],
)
def test_no_near_miss_is_claimed_where_there_is_none(files: list[str], goal: str) -> None:
    result = CliRunner().invoke(app, ["plan", *files, "--goal", goal])
    assert result.exit_code == 3
    assert "no fact matches (in " in result.stderr
    explanation = result.stderr.split("no admissible configuration", 1)[1]
    assert "did you mean" not in explanation


def test_a_name_of_the_state_is_no_slip() -> None:
    """Thesis 6.2.2 step 3 as printed: the door is in Room1, Pippi in Room2.
    Room2 is spelt like Room1 but is a room of the state, not a slip: the
    explanation says what failed and suggests nothing."""
    folder = ROOT / "domains/cross-door"
    args = [str(folder / "domain.lisp"), str(folder / "state-6.2.2-step3-as-printed.lisp")]
    result = CliRunner().invoke(app, ["plan", *args])
    assert result.exit_code == 3
    assert "no fact matches (in Door1 ?room) with ?room = Room2\n" in result.stderr
    assert "did you mean" not in result.stderr


def test_a_goal_of_the_bundled_docking_domain() -> None:
    """A misspelt station in the goal (``Chargr1``) of a bundled domain."""
    folder = ROOT / "domains/docking"
    args = [str(folder / "domain.lisp"), str(folder / "state-kitchen.lisp")]
    result = CliRunner().invoke(app, ["plan", *args, "--goal", "(do-dock Vacu Chargr1)"])
    assert result.exit_code == 3
    assert (
        "no fact matches (station Chargr1): did you mean Charger1? the state has (station Charger1)"
    ) in result.stderr
