"""Bad input gives a positioned, readable error: ``file:line:col``, the source line
and a caret under the offending column (the reader, thesis 4.4; the checker's
errors rendered: ``tests/check/test_errors.py``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from cfgplan.diagnostics import WINDOW, CfgplanError, Diagnostic, render, source_line
from cfgplan.syntax.reader import parse, read_domain, read_state, state_from
from cfgplan.syntax.transform import MAX_NESTING

ROOT = Path(__file__).resolve().parents[2]
CROSS_DOOR = ROOT / "domains" / "cross-door" / "domain.lisp"
TYPOGRAPHIC = ROOT / "tests" / "data" / "cross-door-typographic.lisp"

FUNCTIONALITIES = """\
(make-functionality :name '(camera ?r) :out '((image ?r)))
(make-functionality :name '(measure-door ?r ?d) :in '((image ?r)) :out '((pos ?r ?d)))
"""


def reader_error(text: str, filename: str = "t.lisp") -> Diagnostic:
    """The single diagnostic the reader raises for ``text``."""
    with pytest.raises(CfgplanError) as info:
        parse(text, filename)
    assert len(info.value.diagnostics) == 1
    return info.value.diagnostics[0]


def assert_rendered(d: Diagnostic, text: str, line: int, column: int, message: str) -> str:
    """``d`` is at ``line:column``, and render() shows the line with a caret there."""
    assert d.span is not None
    assert (d.span.file, d.span.line, d.span.column) == ("t.lisp", line, column)
    assert message in d.message
    out = render(d, {"t.lisp": text})
    rows = out.splitlines()
    assert rows[0] == f"t.lisp:{line}:{column}: {d.severity}: {d.message}"
    quoted = source_line(text, line).expandtabs(1)
    gutter = f"{line:>5} | "
    caret_row = rows[2]
    assert caret_row.startswith(" " * (len(gutter) - 2) + "| ")
    caret = caret_row.index("^") - len(gutter)
    if len(quoted) <= WINDOW:
        assert rows[1] == gutter + quoted
        assert caret == column - 1
    else:  # a long line is cut to a window around the caret, "…" where cut
        shown = rows[1][len(gutter) :]
        assert len(shown) <= WINDOW + 2 and "…" in shown
        assert shown.strip("…") in quoted
        if column <= len(quoted):
            assert shown[caret] == quoted[column - 1]
        else:
            assert caret == len(shown)
    if d.hint:
        assert rows[3] == f"  hint: {d.hint}"
    return out


# -- reader errors ---------------------------------------------------------------


def test_unbalanced_parenthesis_missing_close() -> None:
    text = "(make-functionality :name '(camera ?r)\n  :out '((image ?r))\n"
    d = reader_error(text)
    out = assert_rendered(d, text, 2, 21, "a list is not closed (missing ')')")
    assert "the '(' at line 1, column 1 is never closed" in out


def test_unbalanced_parenthesis_one_too_many() -> None:
    text = "(state (robot Pippi)))\n"
    d = reader_error(text)
    assert_rendered(d, text, 1, 22, "unexpected ')'")
    assert d.hint == "there is one ')' too many, or an opening '(' is missing"


@pytest.mark.parametrize("value", ["a", "(a b)", "(a\n b)"])
def test_a_keyword_after_a_goal_names_the_one_thing_expected(value: str) -> None:
    """A goal holds one value: after it only its ")" may come, whatever the
    value (a list on one line is one token, grammar/cfgplan.lark)."""
    text = f"(goal {value} :k)\n"
    d = reader_error(text)
    at = text.index(":k")
    line, column = text.count("\n", 0, at) + 1, at - text.rfind("\n", 0, at)
    assert_rendered(d, text, line, column, "unexpected ':k'")
    assert d.message == "unexpected ':k'; expected \")\""


@pytest.mark.parametrize("value", ["a", "(a b)"])
def test_a_keyword_among_facts_names_what_may_come(value: str) -> None:
    """In a state another fact, or its ")", may follow a fact (no quote: facts
    are not quoted)."""
    text = f"(state {value} :k)\n"
    d = reader_error(text)
    assert_rendered(d, text, 1, text.index(":k") + 1, "unexpected ':k'")
    expected = '"(", ")", ",", a name followed by (, a number or a symbol'
    assert d.message == f"unexpected ':k'; expected {expected}"


def test_missing_close_before_next_form() -> None:
    text = "(make-functionality :name '(camera ?r) :out '((image ?r))\n" + FUNCTIONALITIES
    d = reader_error(text)
    assert_rendered(d, text, 2, 1, "the form before it is not closed (missing ')')")
    assert d.hint == (
        "every '(' needs a matching ')'; the '(' at line 1, column 1 is not closed before this form"
    )


def test_missing_close_in_the_middle_of_a_file_is_found_where_it_is() -> None:
    """A ')' missing in the middle of the cross-door domain (Appendix A.1) is
    reported at the next form, naming the '(' left open: as good a hint as
    for a ')' missing at the end of the file, not an error at the end."""
    lines = CROSS_DOOR.read_text("utf-8").split("\n")
    row = lines.index("  :out '((pos ?rh1 ?r)))")  # the end of measure-robot-pos (line 21)
    lines[row] = "  :out '((pos ?rh1 ?r))"
    text = "\n".join(lines)
    d = reader_error(text, "domain.lisp")
    assert d.span is not None and (d.span.line, d.span.column) == (row + 2, 1)
    assert "the form before it is not closed (missing ')')" in d.message
    opened = next(i for i in range(row, -1, -1) if lines[i].startswith("(make-functionality"))
    assert d.hint is not None and f"the '(' at line {opened + 1}, column 1" in d.hint


def test_missing_close_of_a_fact_is_found_at_the_goal() -> None:
    text = "(state (robot Pippi) (robot Emil (in Pippi Room1))\n(goal (do-it Pippi))\n"
    d = reader_error(text)
    assert_rendered(d, text, 2, 1, "the form before it is not closed (missing ')')")
    assert d.hint is not None and "the '(' at line 1, column 1" in d.hint


def test_missing_close_before_a_keyword_names_the_open_list() -> None:
    text = "(make-functionality :name '(camera ?r)\n  :out '((image ?r)\n  :cost 2)\n"
    d = reader_error(text)
    assert_rendered(d, text, 3, 3, "a list is not closed before ':cost' (missing ')')")
    assert d.hint == (
        "every '(' needs a matching ')'; the '(' at line 2, column 9 is not closed before :cost"
    )


def test_a_form_at_column_1_inside_a_closed_one_is_not_blamed() -> None:
    """A list written at column 1 inside a form that is closed later is no
    missing ')': a later error is reported as itself."""
    text = '(state (robot Pippi)\n(robot Emil))\n(goal "do")\n'
    d = reader_error(text)
    assert_rendered(d, text, 3, 7, "unexpected character '\"'")


def test_unknown_keyword() -> None:
    text = "(make-functionality :name '(camera ?r) :output '((image ?r)))\n"
    d = reader_error(text)
    assert_rendered(d, text, 1, 40, "unknown keyword :output in make-functionality")
    assert d.hint is not None and ":out" in d.hint


def test_keyword_in_wrong_case() -> None:
    text = "(make-functionality :NAME '(camera ?r) :out '((image ?r)))\n"
    d = reader_error(text)
    assert_rendered(d, text, 1, 21, "unknown keyword :NAME")
    assert d.hint == "keywords are case-sensitive: write :name"


@pytest.mark.parametrize(
    ("value", "read_as"),
    [
        ("99999999999999999999999999999999", "1e+32"),  # a newcomer's: the cost came out wrong
        ("12345678901234567", "1.2345678901234568e+16"),
        ("0.99999999999999999999", "1.0"),
    ],
)
def test_a_number_is_never_silently_rounded(value: str, read_as: str) -> None:
    """cfgplan's quantities are floats: a number written with more digits than a
    float keeps is refused where it stands, not rounded into another."""
    keywords = [":freq", ":reliability"] if float(value) <= 1 else [":freq"]
    for keyword in keywords:
        text = f"(make-functionality :name '(camera ?r)\n  {keyword} {value})\n"
        d = reader_error(text)
        assert_rendered(
            d, text, 2, len(keyword) + 4, f"{value} has more digits than a number keeps"
        )
        assert d.message.endswith(f"it would be read as {read_as}")
        assert d.hint == "write at most 15 significant digits"


@pytest.mark.parametrize("value", ["0.1", "1000000000000000", "100000000000000000000", "007.50"])
def test_numbers_a_float_keeps_are_read(value: str) -> None:
    """0.1 reads back as 0.1, and 1e20 is a float exactly: both kept."""
    (form,) = parse(f"(make-functionality :name '(camera ?r) :freq {value})\n").functionalities
    assert form.freq == float(value)


def test_a_cost_is_at_most_the_largest_weight() -> None:
    """A :cost replaces a weight (thesis 3.2), and weights are at most 1e15 so
    that a configuration's cost stays exact: 1e15 is read, more is refused."""
    (form,) = parse(
        "(make-functionality :name '(camera ?r) :cost 1000000000000000)\n"
    ).functionalities
    assert form.cost == 1e15
    text = "(make-functionality :name '(camera ?r) :cost 1000000000000001)\n"
    d = reader_error(text)
    assert_rendered(d, text, 1, 46, ":cost is at most 1e+15, found 1000000000000001")


def test_a_mediums_numbers_are_never_silently_rounded() -> None:
    for fact, read_as in [
        ("(medium wifi Pippi Emil 200.00000000000000000001)", "200.0"),
        ("(medium wifi Pippi Emil 200 0.90000000000000000001)", "0.9"),
    ]:
        text = f"(state (robot Pippi) (robot Emil)\n  {fact})\n"
        d = reader_error(text)
        assert_rendered(d, text, 2, 3, "has more digits than a number keeps")
        assert d.message.endswith(f"it would be read as {read_as}")


def test_state_fact_that_is_not_an_atom() -> None:
    text = "(state (robot Pippi)\n       Pippi)\n"
    d = reader_error(text)
    assert_rendered(d, text, 2, 8, "expected a fact such as (robot Pippi), found Pippi")


def test_state_fact_with_nested_list() -> None:
    text = "(state (in Pippi (Room1)))\n"
    d = reader_error(text)
    assert_rendered(d, text, 1, 18, "an argument of (in ...) must be a symbol or a number")


def test_state_fact_printed_with_space_before_paren() -> None:
    text = "(state robot(Emil), robot (Pippi))\n"
    d = reader_error(text)
    assert_rendered(d, text, 1, 21, "expected a fact such as (robot Pippi), found robot")
    assert d.hint is not None and "write robot(Pippi)" in d.hint


def test_a_syntax_error_anywhere_comes_before_a_wrong_form() -> None:
    """The reader builds each form as the parser closes it, but reports as if it
    had read the whole file first: a later syntax error before an earlier
    wrong form; of two wrong forms, both, in file order (check reports every
    problem; it used to say the first only)."""
    wrong = "(state (robot ?r))\n"
    text = wrong + '(state (robot Emil) "x")\n'
    assert_rendered(reader_error(text), text, 2, 21, "unexpected character '\"'")
    text = wrong + "(state Pippi)\n"
    with pytest.raises(CfgplanError) as info:
        parse(text, "t.lisp")
    first, second = info.value.diagnostics
    assert_rendered(first, text, 1, 8, "a fact holds no variables")
    assert_rendered(second, text, 2, 8, "expected a fact such as (robot Pippi), found Pippi")


def test_state_fact_with_variable() -> None:
    text = "(state (robot ?r))\n"
    d = reader_error(text)
    assert_rendered(d, text, 1, 8, "a fact holds no variables")


@pytest.mark.parametrize("text", ["", "\n\n", "   ; only a comment\n;; and another\n"])
def test_empty_file(text: str) -> None:
    d = reader_error(text)
    assert_rendered(d, text, 1, 1, "the file is empty")


def test_string_in_eval_is_refused_by_the_reader() -> None:
    text = "(make-config-method :name '(m ?r)\n  :precond '((eval (delete-file \"x\")))\n"
    text += "  :body '((?f1 (camera ?r))))\n"
    d = reader_error(FUNCTIONALITIES + text)
    assert_rendered(d, FUNCTIONALITIES + text, 4, 33, "unexpected character '\"'")
    assert d.hint is not None and "no strings" in d.hint


def test_deep_nesting_is_refused_without_recursion_error() -> None:
    depth = 20_000
    text = "(state " + "(" * depth + ")" * depth + ")\n"
    d = reader_error(text)  # a RecursionError would fail the test here
    assert d.span is not None and d.span.line == 1
    assert f"lists nest more than {MAX_NESTING} levels deep" in d.message
    # The innermost list deeper than the limit: MAX_NESTING + 1 levels from the bottom.
    column = len("(state ") + depth - MAX_NESTING
    assert_rendered(d, text, 1, column, "nest more than")


def test_deep_unclosed_nesting_is_refused_without_recursion_error() -> None:
    text = "(state " + "(" * 20_000
    d = reader_error(text)
    assert_rendered(d, text, 1, len(text) + 1, "a list is not closed")


def test_top_level_nesting_is_a_syntax_error() -> None:
    text = "(" * 20_000 + ")" * 20_000
    d = reader_error(text)
    assert_rendered(d, text, 1, 2, "unexpected '('")


def test_non_utf8_byte(tmp_path: Path) -> None:
    path = tmp_path / "bad.lisp"
    path.write_bytes(b"\xff")
    with pytest.raises(CfgplanError) as info:
        read_domain(path)
    (d,) = info.value.diagnostics
    assert d.span is not None
    assert (d.span.file, d.span.line, d.span.column) == (str(path), 1, 1)
    assert d.message == "invalid UTF-8 byte 0xff"
    out = render(d, {str(path): "\ufffd"}).splitlines()
    assert out[0] == f"{path}:1:1: error: invalid UTF-8 byte 0xff"
    assert out[1:3] == ["    1 | \ufffd", "      | ^"]


def test_non_utf8_byte_column_counts_characters(tmp_path: Path) -> None:
    # Line 2 holds a three-byte ’ before the bad byte: column 11 in bytes, 9 in characters.
    data = "(state (robot Pippi)\n  (in ’P".encode() + b"\xff" + b"))\n"
    path = tmp_path / "bad-state.lisp"
    path.write_bytes(data)
    with pytest.raises(CfgplanError) as info:
        read_state(path)
    (d,) = info.value.diagnostics
    assert d.span is not None and (d.span.line, d.span.column) == (2, 9)
    text = data.decode("utf-8", errors="replace")
    out = render(d, {str(path): text}).splitlines()
    assert out[1] == "    2 |   (in ’P\ufffd))"
    assert out[2].index("^") - len("    2 | ") == 8


# -- quotes and notations that must read the same --------------------------------


def test_typographic_quotes_read_as_plain_quotes() -> None:
    typographic = TYPOGRAPHIC.read_text("utf-8")
    assert "'" not in typographic and "’" in typographic and "‘" in typographic
    assert typographic.replace("’", "'").replace("‘", "'") == CROSS_DOOR.read_text("utf-8")
    original, _ = read_domain(CROSS_DOOR)
    copied, _ = read_domain(TYPOGRAPHIC)
    assert copied.model_dump() == original.model_dump()
    assert len(copied.methods) == 7 and len(copied.functionalities) == 9


@pytest.mark.parametrize("quote", ["'", "’", "‘"])
def test_an_unexpected_quote_is_named_as_written(quote: str) -> None:
    """The parser reads a curly quote as ' (``reader.as_lexed``); the message
    still names the character the file holds, at its place."""
    text = f"(make-functionality :name '{quote}(camera ?r))"
    d = reader_error(text)
    assert d.message.startswith(f"unexpected '{quote}'; expected")
    assert d.span is not None and (d.span.line, d.span.column, d.span.end_column) == (1, 28, 29)


STEP1_SEXPR = """\
(state (robot Pippi) (robot Emil) (door Door1) (camera Emil) (camera Pippi)
       (compass Pippi) (compass Emil) (in Pippi Room1) (in Emil Room1)
       (in Door1 Room1) (open Door1) (connects Door1 Room1 Room2))
(goal (do-cross-door Pippi Door1))
"""


def test_printed_notation_state_equals_sexpr_notation() -> None:
    printed, text = read_state(ROOT / "domains" / "cross-door" / "state-6.2.2-step1.lisp")
    assert "robot(Pippi)," in text  # the file really uses the printed notation
    written = state_from(parse(STEP1_SEXPR, "step1.lisp"))
    assert printed.model_dump() == written.model_dump()
    assert len(printed.facts) == 12 and printed.goal is not None


def test_quoted_argument_in_a_fact_is_named() -> None:
    """Text copied from the PDF may quote a symbol inside a fact: say so."""
    text = "(state (robot ’Pippi))"
    with pytest.raises(CfgplanError) as caught:
        parse(text, "s.lisp")
    (diag,) = caught.value.diagnostics
    assert diag.span is not None and (diag.span.line, diag.span.column) == (1, 15)
    assert "the arguments of an atom are not quoted" in diag.message
    assert diag.hint == "write Pippi without the quote"


def test_form_feed_does_not_start_a_line() -> None:
    """Lark counts lines at \\n only; the quoted line and caret must agree with it."""
    text = "(state\x0c(robot ?x))"
    with pytest.raises(CfgplanError) as caught:
        parse(text, "s.lisp")
    out = render(caught.value.diagnostics[0], {"s.lisp": text})
    assert out.splitlines()[0].startswith("s.lisp:1:8: error")
    rows = out.split("\n")
    # shown escaped (terminal safety), the caret still under "(robot" (column 8)
    assert rows[1] == "    1 | (state\\x0c(robot ?x))"
    assert rows[2].index("^") == rows[1].index("(robot")


@pytest.mark.parametrize(
    ("text", "column", "hint"),
    [
        ("(state (robot Pippi))\n(goal)\n", 6, "the goal is empty: it names a method instance"),
        ("(state (robot Pippi))\n(goal  )\n", 8, "the goal is empty"),
        ("(state (robot Pippi))\n(sequence)\n", 10, "the sequence is empty: it lists goals"),
    ],
)
def test_an_empty_goal_or_sequence_is_said_to_be_empty(text: str, column: int, hint: str) -> None:
    """Balanced, but nothing in it: a newcomer was told there was one ')' too many."""
    d = reader_error(text)
    assert_rendered(d, text, 2, column, "unexpected ')'")
    assert d.hint is not None and d.hint.startswith(hint)
