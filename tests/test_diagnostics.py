"""Diagnostics are safe for a terminal (cfgplan/diagnostics.py).

Whatever bytes a domain holds, an error message shows no raw control or
format character (ESC, BEL, NUL, a bidirectional override), and a line of
173,000 characters is quoted as a window around the caret, not whole.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from cfgplan.diagnostics import (
    WINDOW,
    Diagnostic,
    did_you_mean,
    near_names,
    printable,
    quote_line,
    render,
)
from cfgplan.ir.model import Span

ROOT = Path(__file__).resolve().parents[1]


def _at(line: int, column: int, end: int | None = None) -> Span:
    return Span(
        file="t.lisp", line=line, column=column, end_line=line, end_column=end or column + 1
    )


def _raw_controls(text: str) -> list[str]:
    return [c for c in text if c != "\n" and printable(c) != c]


def test_control_and_format_characters_are_escaped() -> None:
    assert printable("a\x1b[31mb\x07c\x00d") == "a\\x1b[31mb\\x07c\\x00d"
    assert printable("\u202eevil\u2028x\x85") == "\\u202eevil\\u2028x\\x85"
    assert printable("Pippi, Émil, 🤖, tab\tend") == "Pippi, Émil, 🤖, tab\\x09end"
    assert printable("two\nlines", keep="\n") == "two\nlines"


def test_a_diagnostic_shows_no_raw_control_characters() -> None:
    text = "(state (robot \x1b]0;owned\x07Pippi\u202e))\n"
    d = Diagnostic("error", "unexpected '\x1b]0;owned\x07'", _at(1, 15, 25), "hint \x1b[2J")
    out = render(d, {"t.lisp": text})
    assert _raw_controls(out) == []
    rows = out.splitlines()
    assert rows[1] == "    1 | (state (robot \\x1b]0;owned\\x07Pippi\\u202e))"
    caret = rows[2].index("^")
    assert rows[1][caret:].startswith("\\x1b]0;owned\\x07")  # the caret under the escape
    assert rows[2].count("^") == len("\\x1b]0;owned\\x07")


def test_a_huge_line_is_cut_around_the_caret() -> None:
    line = "(state " + "x" * 100_000 + " @bad " + "y" * 73_000 + ")"
    column = line.index("@") + 1
    shown, caret = quote_line(line, column, 4)
    assert len(shown) <= WINDOW + 2
    assert shown.startswith("…") and shown.endswith("…")
    assert shown[caret.index("^") :].startswith("@bad")
    assert caret.count("^") == 4


def test_the_ends_of_a_long_line() -> None:
    line = "(state " + "z" * 500 + ")"
    shown, caret = quote_line(line, 2, 5)  # near the start: nothing cut before
    assert shown.startswith("(state zz") and shown.endswith("…")
    assert caret == " ^^^^^"
    shown, caret = quote_line(line, len(line) + 1, 1)  # past the end (end of file)
    assert shown.startswith("…") and shown.endswith("z)")
    assert caret.index("^") == len(shown)


def test_a_wide_character_moves_the_caret_two_columns() -> None:
    shown, caret = quote_line("(robot 🤖 x)", 10, 1)
    assert shown == "(robot 🤖 x)"
    assert caret == " " * 10 + "^"  # '(robot ' 7 + the robot 2 + ' ' 1


def test_a_huge_word_in_a_message_is_shortened() -> None:
    name = "n" * 100_000
    out = render(Diagnostic("error", f"no method {name} here"), {})
    assert len(out) < 200
    assert out.startswith("cfgplan: error: no method nnnn") and out.endswith("n here")


@pytest.mark.parametrize("command", ["check", "plan"])
def test_the_command_line_escapes_what_it_quotes(tmp_path: Path, command: str) -> None:
    domain = tmp_path / "d\x1b[31m.lisp"
    domain.write_bytes(b"(make-functionality :name '(camera ?r) :out '((image ?r)) \x1b[31m\x07)\n")
    long = tmp_path / "long.lisp"
    long.write_text("(make-functionality :name '(camera ?r)" + " " * 173_000 + " :bad)\n")
    for path in (domain, long):
        args = [command, str(path)] + ([str(path)] if command == "plan" else [])
        done = subprocess.run(
            [sys.executable, "-m", "cfgplan", *args],
            capture_output=True,
            cwd=ROOT,
            timeout=60,
        )
        assert done.returncode == 1
        err = done.stderr.decode("utf-8")
        assert _raw_controls(err) == [], err
        assert len(err) < 2000
        assert "Traceback" not in err


def test_names_with_escape_sequences_are_escaped_in_tables_and_summaries(tmp_path: Path) -> None:
    """Not only errors: the plan table and the check summary are for people too."""
    (tmp_path / "d.lisp").write_text(
        "(make-functionality :name '(camera ?r) :out '((image ?r)))\n"
        "(make-functionality :name '(look ?r) :in '((image ?r)))\n"
        "(make-config-method :name '(see ?r) :precond '((robot ?r))\n"
        "  :channels '(((local ?r) ?f1 ?f2 (image ?r)))\n"
        "  :body '((?f1 (camera ?r)) (?f2 (look ?r))))\n"
    )
    evil = "\x1b[31mEvil\x07\x1b[2J"  # no ";": it would start a comment
    (tmp_path / "s.lisp").write_text(f"(state (robot {evil}))\n(goal (see {evil}))\n")
    for args in (["plan", "--details"], ["check"]):
        done = subprocess.run(
            [sys.executable, "-m", "cfgplan", args[0], "d.lisp", "s.lisp", *args[1:]],
            capture_output=True,
            cwd=tmp_path,
            timeout=60,
        )
        assert done.returncode == 0, done.stderr
        out = done.stdout.decode("utf-8")
        assert _raw_controls(out) == [], out
        assert "\\x1b[31mEvil\\x07\\x1b[2J" in out


# -- did you mean (one rule for the checker and the planner) ------------


def test_did_you_mean_prefers_a_slip_in_case() -> None:
    known = ["camera", "Camera2", "kamera"]
    assert near_names("Camera", known) == (["camera"], True)
    assert did_you_mean("Camera", known) == "symbols are case-sensitive: did you mean camera?"


def test_did_you_mean_names_at_most_two_close_spellings_closest_first() -> None:
    known = ["detect-robot", "detect-door", "detect-robots", "measure-door"]
    close, case = near_names("detect-robt", known)
    assert (close, case) == (["detect-robot", "detect-robots"], False)
    assert did_you_mean("detect-robt", known) == "did you mean detect-robot or detect-robots?"
    assert did_you_mean("Livng", ["Living", "Kitchen"]) == "did you mean Living?"


def test_did_you_mean_stays_silent_when_nothing_is_close() -> None:
    assert did_you_mean("lens", ["camera", "laser"]) is None
    assert did_you_mean("camera", ["camera"]) is None  # the name itself is no slip
    assert near_names("x", []) == ([], False)
