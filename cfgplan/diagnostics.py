"""Diagnostics: ``file:line:col: error: message``, the source line, and a caret.

Every user-facing error of cfgplan is a :class:`Diagnostic`; a stage that
cannot go on raises :class:`CfgplanError` carrying one or more of them. The CLI
renders them with :func:`render` and exits with code 1, never a traceback.

What is printed is safe for a terminal whatever the input holds: control,
format and line-separator characters (ESC, BEL, NUL, bidirectional overrides,
U+2028) are shown escaped as ``\\x1b``, ``\\u202e``; a long quoted line is cut
to a window around the caret, and a very long word of a message (a 100,000
character symbol) is shortened in its middle.
"""

from __future__ import annotations

import re
import unicodedata
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal

if TYPE_CHECKING:  # only named in annotations: pydantic is not loaded for a message
    from cfgplan.ir.model import Span
    from cfgplan.runtime.errors import RunError

Severity = Literal["error", "warning", "note"]

WINDOW = 100
"""Display columns of a quoted source line; a longer line is cut around the caret."""
CONTEXT = 40
"""Columns kept before the caret when a quoted line is cut."""
LONG_WORD = 80
"""A word of a message or hint longer than this is shortened in its middle."""

_UNSAFE = frozenset({"Cc", "Cf", "Zl", "Zp", "Cs"})
_LINE_BREAK = re.compile(r"\r\n|\r|\n")
_LONG_WORD = re.compile(r"\S{" + str(LONG_WORD + 1) + ",}")


@dataclass(frozen=True)
class Diagnostic:
    """One message about one place in a source file (or about no place)."""

    severity: Severity
    message: str
    span: Span | None = None
    hint: str | None = None

    @property
    def is_error(self) -> bool:
        return self.severity == "error"


@dataclass
class CfgplanError(Exception):
    """A user error: bad input that cfgplan reports and refuses."""

    diagnostics: list[Diagnostic] = field(default_factory=list)

    def __str__(self) -> str:
        return "; ".join(d.message for d in self.diagnostics)


def error(message: str, span: Span | None = None, hint: str | None = None) -> CfgplanError:
    """Build a :class:`CfgplanError` holding a single error diagnostic."""
    return CfgplanError([Diagnostic("error", message, span, hint)])


def run_error(exc: RunError) -> CfgplanError:
    """A runtime error as the CLI reports errors: file:line:col and the line
    quoted with a caret when it has a place, and its hint."""
    span = None
    if exc.file is not None and exc.line is not None:
        from cfgplan.ir.model import Span  # pydantic: loaded only for a placed error

        column = exc.column or 1
        span = Span(
            file=exc.file, line=exc.line, column=column, end_line=exc.line, end_column=column + 1
        )
    return error(exc.message, span, exc.hint)


# -- did you mean ----------------------------------------------------------------

NEAR = 0.75
"""How alike two spellings must be (difflib's ratio) to be a likely slip."""


def near_names(name: str, known: Iterable[str]) -> tuple[list[str], bool]:
    """The ``known`` names ``name`` is likely a slip for, and whether they
    differ from it only in case (symbols are case-sensitive): those first;
    else at most two close in spelling (``detect-robt``, ``detect-robot``),
    the closest first. The one rule behind every "did you mean" of cfgplan."""
    names = sorted(set(known) - {name})
    same = [n for n in names if n.lower() == name.lower()]
    if same:
        return same, True
    import difflib  # only when a name is missing

    return difflib.get_close_matches(name, names, n=2, cutoff=NEAR), False


def did_you_mean(name: str, known: Iterable[str]) -> str | None:
    """``did you mean detect-robot?`` (``symbols are case-sensitive: did you
    mean camera?``) when ``name`` is likely a slip for a known name
    (:func:`near_names`); None when it is not."""
    close, case = near_names(name, known)
    if not close:
        return None
    prefix = "symbols are case-sensitive: " if case else ""
    return f"{prefix}did you mean {' or '.join(close)}?"


# -- terminal safety -------------------------------------------------------------


def is_unsafe(char: str) -> bool:
    """True for a character a terminal would act on or hide rather than show:
    controls (Cc), format characters such as bidirectional overrides (Cf), line
    and paragraph separators (Zl, Zp) and surrogates (Cs)."""
    return unicodedata.category(char) in _UNSAFE


def escape_char(char: str) -> str:
    """``\\x1b``, ``\\u202e`` or ``\\U000e0001``: Python's escape for one character."""
    code = ord(char)
    if code < 0x100:
        return f"\\x{code:02x}"
    if code < 0x10000:
        return f"\\u{code:04x}"
    return f"\\U{code:08x}"


def printable(text: str, keep: str = "") -> str:
    """``text`` with every unsafe character (:func:`is_unsafe`) escaped, except
    those in ``keep`` (say ``"\\n"`` for text of several lines)."""
    if text.isprintable():
        return text
    return "".join(escape_char(c) if c not in keep and is_unsafe(c) else c for c in text)


def shorten(text: str) -> str:
    """``text`` with each word longer than :data:`LONG_WORD` characters cut in its
    middle (``aaaa…aaaa``), so that a huge symbol does not flood the terminal."""
    return _LONG_WORD.sub(lambda m: m.group(0)[:50] + "…" + m.group(0)[-20:], text)


def safe_text(text: str) -> str:
    """A message or hint as printed: long words shortened, unsafe characters escaped."""
    return printable(shorten(text))


# -- source lines ----------------------------------------------------------------


def lines_of(text: str) -> list[str]:
    """The lines of ``text``, without their line breaks: ``\\n``, ``\\r\\n`` and a
    ``\\r`` alone (old Mac files) each end a line, as the reader counts them."""
    return _LINE_BREAK.split(text)


def source_line(text: str, line: int) -> str:
    """The 1-based ``line`` of ``text``, without its line break ('' if absent)."""
    lines = lines_of(text)
    if 1 <= line <= len(lines):
        return lines[line - 1]
    return ""


def _cell(char: str) -> str:
    """How one source character is shown: a tab as one space (columns count it
    as one), an unsafe character escaped."""
    if char == "\t":
        return " "
    return escape_char(char) if is_unsafe(char) else char


def _width(cell: str) -> int:
    """Terminal columns of a shown character: 2 for wide East Asian ones and
    emoji, 0 for combining marks."""
    if len(cell) != 1:
        return len(cell)
    if unicodedata.combining(cell):
        return 0
    return 2 if unicodedata.east_asian_width(cell) in "WF" else 1


def quote_line(line: str, column: int, width: int) -> tuple[str, str]:
    """The shown source ``line`` and the caret row under ``width`` characters
    from 1-based ``column``; a line wider than :data:`WINDOW` is cut around
    the caret, with ``…`` where text was left out."""
    cells = [_cell(c) for c in line]
    offsets = [0]
    for cell in cells:
        offsets.append(offsets[-1] + _width(cell))
    first = min(max(column - 1, 0), len(cells))
    last = min(first + max(width, 1), len(cells))
    lo, hi = 0, len(cells)
    if offsets[-1] > WINDOW:
        left = max(0, min(offsets[first] - CONTEXT, offsets[-1] - WINDOW))
        while offsets[lo] < left:
            lo += 1
        hi = lo
        while hi < len(cells) and offsets[hi + 1] - offsets[lo] <= WINDOW:
            hi += 1
    before = "…" if lo > 0 else ""
    after = "…" if hi < len(cells) else ""
    shown = before + "".join(cells[lo:hi]) + after
    start = len(before) + offsets[first] - offsets[lo]
    span = offsets[min(last, hi)] - offsets[first]
    return shown, " " * start + "^" * max(span, 1)


def render(diagnostic: Diagnostic, sources: Mapping[str, str]) -> str:
    """Format a diagnostic as the compiler-style block users read.

    ``sources`` maps file names to their text, to quote the offending line.
    """
    span = diagnostic.span
    head = f"{diagnostic.severity}: {safe_text(diagnostic.message)}"
    if span is None:
        out = [f"cfgplan: {head}"]
    else:
        out = [f"{safe_text(span.file)}:{span.line}:{span.column}: {head}"]
        text = sources.get(span.file)
        # Quote the line if the file has it (an empty file has an empty line 1).
        if text is not None and 1 <= span.line <= max(1, len(lines_of(text))):
            line = source_line(text, span.line)
            width = 1
            if span.end_line == span.line and span.end_column > span.column:
                width = span.end_column - span.column
            shown, caret = quote_line(line, span.column, width)
            gutter = f"{span.line:>5} | "
            out.append(gutter + shown)
            out.append(" " * (len(gutter) - 2) + "| " + caret)
    if diagnostic.hint:
        out.append(f"  hint: {safe_text(diagnostic.hint)}")
    return "\n".join(out)


def render_all(diagnostics: Iterable[Diagnostic], sources: Mapping[str, str]) -> str:
    return "\n".join(render(d, sources) for d in diagnostics)
