"""Input errors as JSON: with ``--format json`` or ``jsonl`` every
input error prints one :class:`ErrorDocument` on stdout, the human message
stays on stderr and the exit code is unchanged; ``cfgplan check --format
json`` prints the same document, or a :class:`CheckDocument` when the input
is fine.

Through :func:`cfgplan.cli.app.main`, in process: the path a real command
takes (``main`` prints the human message and sets the exit code).
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from cfgplan.cli.app import main
from cfgplan.cli.errors import CheckDocument, ErrorDocument
from tests.cli.conftest import ROOT

CROSS = [str(ROOT / "domains/cross-door" / f) for f in ("domain.lisp", "state-6.2.2-step1.lisp")]

CAMERA = "(make-functionality :name '(camera ?r) :out '((image ?r)))\n"
SEE = "(make-config-method :name '(see ?r) :body '((c1 (camera ?r))))\n"
STATE = "(state (robot R1))\n(goal (see R1))\n"

Main = Callable[..., tuple[int, str, str]]


@pytest.fixture
def cfgplan(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> Main:
    """``cfgplan(*args)``: exit code, stdout, stderr, run in ``tmp_path``."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "unraisablehook", sys.unraisablehook)  # main() replaces it

    def run(*args: str) -> tuple[int, str, str]:
        monkeypatch.setattr(sys, "argv", ["cfgplan", *args])
        with pytest.raises(SystemExit) as done:
            main()
        out = capsys.readouterr()
        code = done.value.code
        assert isinstance(code, int)
        return code, out.out, out.err

    return run


def _error(stdout: str) -> ErrorDocument:
    """The one document on stdout: one line, ASCII, no key the model lacks."""
    assert stdout.endswith("\n") and stdout.count("\n") == 1, stdout
    assert stdout.isascii()
    return ErrorDocument.model_validate(json.loads(stdout))


@pytest.mark.parametrize("format_", ["json", "jsonl"])
def test_a_parse_error_is_a_json_object_on_stdout(
    cfgplan: Main, tmp_path: Path, format_: str
) -> None:
    (tmp_path / "d.lisp").write_text(CAMERA + SEE[:-2] + "\n")  # one ')' short
    (tmp_path / "s.lisp").write_text(STATE)
    code, out, err = cfgplan("plan", "d.lisp", "s.lisp", "--format", format_)
    assert code == 1
    doc = _error(out)
    assert doc.errors == [doc.error] and doc.warnings == []
    e = doc.error
    assert (e.severity, e.file, e.line) == ("error", "d.lisp", 2)
    assert e.column is not None and e.end_column is not None and e.end_column > e.column
    assert "not closed" in e.message and e.hint is not None and "'('" in e.hint
    # stderr keeps the human message, at the same place
    assert err.startswith(f"d.lisp:2:{e.column}: error: {e.message}")
    assert "^" in err


def test_every_check_error_and_warning_is_listed(cfgplan: Main, tmp_path: Path) -> None:
    loose = CAMERA.replace("(image ?r)", "(image ?x)")  # a warning
    body = "(make-config-method :name '(see ?r) :body '((c1 (camra ?r)) (c2 (Camera ?r))))\n"
    (tmp_path / "d.lisp").write_text(loose + body)
    (tmp_path / "s.lisp").write_text(STATE)
    code, out, err = cfgplan("plan", "d.lisp", "s.lisp", "--format", "jsonl")
    assert code == 1
    doc = _error(out)
    assert [(e.line, e.column) for e in doc.errors] == [(2, 49), (2, 65)]
    assert doc.error == doc.errors[0]
    assert "camra" in doc.errors[0].message
    assert doc.errors[1].hint == "symbols are case-sensitive: did you mean camera?"
    (warning,) = doc.warnings
    assert (warning.severity, warning.line) == ("warning", 1)
    assert err.count("error:") == 2 and err.count("warning:") == 1


def test_a_bad_goal_points_into_the_option(cfgplan: Main) -> None:
    goal = "(do-cross-dor Pippi Door1)"
    code, out, err = cfgplan("plan", *CROSS, "--format", "json", "--goal", goal)
    assert code == 1
    e = _error(out).error
    assert (e.file, e.line, e.column) == ("--goal", 1, 7)
    assert e.hint == "did you mean do-cross-door?"
    assert err.startswith("--goal:1:7: error: the goal (do-cross-dor Pippi Door1) names no method")


def test_errors_about_no_place_have_a_null_place(cfgplan: Main, tmp_path: Path) -> None:
    code, out, err = cfgplan("plan", "nope.lisp", CROSS[1], "--format", "json")
    assert code == 1
    e = _error(out).error
    assert e.message == "no such file: nope.lisp"
    assert (e.file, e.line, e.column, e.end_line, e.end_column) == (None,) * 5
    assert err == "cfgplan: error: no such file: nope.lisp\n"
    (tmp_path / "out.json").write_text("keep me")
    code, out, _ = cfgplan("plan", *CROSS, "--format", "json", "-o", "out.json")
    assert code == 1
    assert "pass --force" in _error(out).error.message
    assert (tmp_path / "out.json").read_text() == "keep me"


def test_a_rank_past_the_last_keeps_exit_3(cfgplan: Main) -> None:
    code, out, err = cfgplan("plan", *CROSS, "--format", "json", "--rank", "3")
    assert code == 3
    e = _error(out).error
    assert e.message == "do-cross-door(Pippi, Door1) has 2 configurations, none of rank 3"
    assert e.hint == "--rank 1 to 2"
    assert e.message in err


def test_the_table_keeps_stdout_empty(cfgplan: Main, tmp_path: Path) -> None:
    code, out, err = cfgplan("plan", "nope.lisp", CROSS[1])
    assert (code, out) == (1, "")
    assert "no such file" in err


def test_check_json_says_ok_with_the_counts(cfgplan: Main) -> None:
    code, out, err = cfgplan("check", *CROSS, "--format", "json")
    assert code == 0, err
    assert out.count("\n") == 1
    doc = CheckDocument.model_validate(json.loads(out))
    assert doc.ok is True
    assert (doc.domain, doc.state) == tuple(CROSS)
    assert (doc.functionalities, doc.methods, doc.versions) == (9, 6, 7)
    assert (doc.facts, doc.media, doc.goal) == (12, 0, "(do-cross-door Pippi Door1)")
    assert doc.warnings == []
    code, text, _ = cfgplan("check", *CROSS)  # text stays the default
    assert code == 0 and text.startswith("ok: ")


def test_check_json_lists_the_errors(cfgplan: Main, tmp_path: Path) -> None:
    (tmp_path / "d.lisp").write_text(CAMERA + SEE.replace("(camera ?r)", "(camra ?r)"))
    code, out, err = cfgplan("check", "d.lisp", "--format", "json")
    assert code == 1
    e = _error(out).error
    assert (e.file, e.line, e.column) == ("d.lisp", 2, 49)
    assert "1 error(s), 0 warning(s)" in err
    (tmp_path / "p.lisp").write_text(CAMERA[:-2] + "\n")
    code, out, _ = cfgplan("check", "p.lisp", "--format", "json")
    assert code == 1
    assert _error(out).error.file == "p.lisp"


def test_check_json_keeps_the_warnings(cfgplan: Main, tmp_path: Path) -> None:
    (tmp_path / "d.lisp").write_text(CAMERA.replace("(image ?r)", "(image ?x)") + SEE)
    code, out, err = cfgplan("check", "d.lisp", "--format", "json")
    assert code == 0
    (warning,) = CheckDocument.model_validate(json.loads(out)).warnings
    assert warning.severity == "warning" and warning.message.startswith("?x in (image ?x)")
    assert "warning:" in err
