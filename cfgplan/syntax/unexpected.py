"""What the reader says about text the grammar does not accept (thesis 4.4).

Lark's ``UnexpectedInput`` becomes one :class:`~cfgplan.diagnostics.Diagnostic`
with a span, what was expected, and a hint where the mistake is a common one.
A missing ``)`` is the commonest, and Lark notices it only later — at the end
of the file, at the next keyword, at the next form — so the hint names the
``(`` that is not closed: the outermost one at the end of the file; the
form before when a form starts at column 1 inside another (Lisp style puts
top-level forms, and only them, at column 1; the error is then placed
there, near the mistake, not at the end of the file); the keyword's list
when a keyword turns up inside a list.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from lark import Token
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from cfgplan.diagnostics import CfgplanError, did_you_mean, error, lines_of
from cfgplan.ir.model import Span

__all__ = ["syntax_error", "unclosed"]

_TERMINAL_NAMES = {
    "LPAR": '"("',
    "ATOMS": '"("',  # a list of atoms on one line, one token (the grammar): its "("
    "RPAR": '")"',
    "COMMA": '","',
    "QUOTE": "a quote '",
    "KEYWORD": "a keyword such as :name",
    "SYMBOL": "a symbol",
    "NUMBER": "a number",
    "CALL_NAME": "a name followed by (",
    "MAKE_FUNCTIONALITY": "make-functionality",
    "MAKE_CONFIG_METHOD": "make-config-method",
    "STATE": "state",
    "GOAL": "goal",
    "SEQUENCE": "sequence",
    "$END": "end of file",
}

OTHER_LINE_BREAKS = frozenset("\x0b\x1c\x1d\x1e\x85\u2028\u2029")
"""What Unicode (and ``str.splitlines``) also counts as line breaks; the
grammar does not, and refuses them where they would end a comment."""

_MISSING = "every '(' needs a matching ')'"


@dataclass(frozen=True)
class _Open:
    """A ``(`` not yet closed: where it stands (1-based) and its offset."""

    line: int
    column: int
    offset: int

    def __str__(self) -> str:
        return f"line {self.line}, column {self.column}"


def _scan(text: str, upto: int | None = None) -> tuple[list[_Open], _Open | None, _Open | None]:
    """The ``(`` still open at offset ``upto`` (default: the end), outermost
    first, comments skipped; and the first ``(`` at column 1 opened while a
    form was still open, with the outermost ``(`` open then."""
    stack: list[_Open] = []
    inner: _Open | None = None
    outer: _Open | None = None
    line, column, in_comment = 1, 0, False
    for offset, char in enumerate(text[:upto]):
        column += 1
        if char == "\n":
            line, column, in_comment = line + 1, 0, False
        elif in_comment:
            continue
        elif char == ";":
            in_comment = True
        elif char == "(":
            here = _Open(line, column, offset)
            if column == 1 and stack and inner is None:
                inner, outer = here, stack[0]
            stack.append(here)
        elif char == ")" and stack:
            stack.pop()
    return stack, inner, outer


def unclosed(text: str) -> tuple[int, int] | None:
    """The line and column of the first ``(`` of ``text`` never closed, or
    ``None`` (for a text read wrapped in a form, such as ``--goal``'s, whose
    own ``)`` would close it)."""
    stack, _, _ = _scan(text)
    return (stack[0].line, stack[0].column) if stack else None


def _at(filename: str, line: int, column: int, end_column: int | None = None) -> Span:
    end = end_column if end_column is not None else column + 1
    return Span(file=filename, line=line, column=column, end_line=line, end_column=end)


def syntax_error(exc: UnexpectedInput, filename: str, text: str) -> CfgplanError:
    """The diagnostic for a syntax error Lark raised while reading ``text``."""
    offset = getattr(exc, "pos_in_stream", None)
    if isinstance(exc, UnexpectedToken) and exc.token.type != "$END":
        offset = exc.token.start_pos
    at_end = isinstance(exc, UnexpectedEOF) or (
        isinstance(exc, UnexpectedToken) and exc.token.type == "$END"
    )
    upto = None if at_end else (offset or 0) + 1
    open_then, inner, outer = _scan(text, upto)
    if inner is not None and outer in open_then:  # a form inside a form not yet closed
        return error(
            "a form starts here, but the form before it is not closed (missing ')')",
            _at(filename, inner.line, inner.column),
            f"{_MISSING}; the '(' at {outer} is not closed before this form",
        )
    if at_end:
        return _end_of_file(filename, text)
    if isinstance(exc, UnexpectedToken):
        return _unexpected_token(exc, filename, text)
    assert isinstance(exc, UnexpectedCharacters)
    return _unexpected_character(exc, filename, text)


def _end_of_file(filename: str, text: str) -> CfgplanError:
    lines = lines_of(text)
    while len(lines) > 1 and not lines[-1].strip():
        lines.pop()  # point at the end of the last line with text
    line, column = len(lines), len(lines[-1]) + 1
    advice = _MISSING
    stack, _, _ = _scan(text)
    if stack:
        advice += f"; the '(' at {stack[0]} is never closed"
    return error(
        "unexpected end of file: a list is not closed (missing ')')",
        _at(filename, line, column),
        advice,
    )


def _describe_expected(expected: set[str]) -> str:
    names = sorted({_TERMINAL_NAMES.get(e, e) for e in expected})
    if not names:
        return ""
    if len(names) == 1:
        return names[0]
    return ", ".join(names[:-1]) + " or " + names[-1]


def _unexpected_token(exc: UnexpectedToken, filename: str, text: str) -> CfgplanError:
    tok: Token = exc.token
    if tok.type == "ATOMS":  # a one-line list where no list may stand: its "(" is unexpected
        start, column = tok.start_pos or 0, tok.column or 1
        tok = Token("LPAR", "(", start, tok.line, column, tok.line, column + 1, start + 1)
    line = tok.line or 1
    column = tok.column or 1
    end_column = (tok.end_column or column + 1) if tok.end_line == tok.line else column + 1
    span = _at(filename, line, column, end_column)
    if tok.type == "KEYWORD" and "RPAR" in exc.expected:
        stack, _, _ = _scan(text, tok.start_pos)
        if len(stack) > 1:  # inside a form: the keyword's list lacks its ')'
            return error(
                f"a list is not closed before '{tok}' (missing ')')",
                span,
                f"{_MISSING}; the '(' at {stack[1]} is not closed before {tok}",
            )
    written = text[tok.start_pos : tok.end_pos] if tok.start_pos is not None else str(tok)
    # As written: the parser reads a curly quote as ' (reader.as_lexed).
    message = f"unexpected '{written}'; expected {_describe_expected(set(exc.expected))}"
    hint: str | None = None
    empty = _EMPTY.search(text[: tok.start_pos or 0]) if tok.type == "RPAR" else None
    if empty is not None:  # (goal) or (sequence): balanced, but nothing in it
        hint = _EMPTY_HINTS[empty.group(1)]
    elif tok.type == "RPAR" and "RPAR" not in exc.expected:
        hint = "there is one ')' too many, or an opening '(' is missing"
    elif tok.type == "LPAR" and "KEYWORD" in exc.expected:
        hint = "a form holds :keyword value pairs; if the form before ends here, it lacks a ')'"
    elif tok.type == "SYMBOL" and {"MAKE_FUNCTIONALITY", "STATE"} & set(exc.expected):
        hint = _form_hint(str(tok))
    return error(message, span, hint)


_EMPTY = re.compile(r"\(\s*(goal|sequence)\s*$")
"""A goal or a sequence opened just before the ``)`` at the end of the text."""

_EMPTY_HINTS = {
    "goal": "the goal is empty: it names a method instance, (goal (do-cross-door Pippi Door1))",
    "sequence": "the sequence is empty: it lists goals, (sequence (do-a Pippi) (do-b Emil))",
}


def _unexpected_character(exc: UnexpectedCharacters, filename: str, text: str) -> CfgplanError:
    line = exc.line or 1
    column = exc.column or 1
    pos = exc.pos_in_stream
    char = text[pos] if pos is not None and pos < len(text) else "?"
    hint = None
    if char == '"':
        hint = "cfgplan has no strings: write a symbol, or (quote symbol) inside (eval ...)"
    elif char in OTHER_LINE_BREAKS:
        hint = (
            "a line break other than \\n, \\r\\n or \\r (vertical tab, NEL, U+2028 ...): "
            "cfgplan does not read it as one; replace it with a newline"
        )
    return error(f"unexpected character {char!r}", _at(filename, line, column), hint)


def _form_hint(word: str) -> str:
    known = ("make-functionality", "make-config-method", "state", "goal", "sequence")
    for k in known:
        if word.lower() == k:
            return f"symbols are case-sensitive: write {k}"
    near = did_you_mean(word, known)
    if near is not None:  # make-functonality
        return near
    return (
        "a file holds (make-functionality ...), (make-config-method ...), (state ...) or (goal ...)"
    )
