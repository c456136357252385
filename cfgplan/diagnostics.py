"""Diagnostics: ``file:line:col: error: message``, the source line, and a caret.

Every user-facing error of cfgplan is a :class:`Diagnostic`; a stage that
cannot go on raises :class:`CfgplanError` carrying one or more of them. The CLI
renders them with :func:`render` and exits with code 1, never a traceback.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Literal

from cfgplan.ir.model import Span

Severity = Literal["error", "warning", "note"]


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


def lines_of(text: str) -> list[str]:
    """Lines as Lark counts them: split at "\\n" only (a form feed or a
    "\\r" alone does not start a line), without the line breaks."""
    return [line.removesuffix("\r") for line in text.split("\n")]


def source_line(text: str, line: int) -> str:
    """The 1-based ``line`` of ``text``, without its line break ('' if absent)."""
    lines = lines_of(text)
    if 1 <= line <= len(lines):
        return lines[line - 1]
    return ""


def render(diagnostic: Diagnostic, sources: Mapping[str, str]) -> str:
    """Format a diagnostic as the compiler-style block users read.

    ``sources`` maps file names to their text, to quote the offending line.
    """
    span = diagnostic.span
    head = f"{diagnostic.severity}: {diagnostic.message}"
    if span is None:
        out = [f"cfgplan: {head}"]
    else:
        out = [f"{span.file}:{span.line}:{span.column}: {head}"]
        text = sources.get(span.file)
        # Quote the line if the file has it (an empty file has an empty line 1).
        if text is not None and 1 <= span.line <= max(1, len(lines_of(text))):
            line = source_line(text, span.line).expandtabs(1)
            width = 1
            if span.end_line == span.line and span.end_column > span.column:
                width = span.end_column - span.column
            width = max(1, min(width, len(line) - span.column + 1))
            gutter = f"{span.line:>5} | "
            out.append(gutter + line)
            out.append(" " * (len(gutter) - 2) + "| " + " " * (span.column - 1) + "^" * width)
    if diagnostic.hint:
        out.append(f"  hint: {diagnostic.hint}")
    return "\n".join(out)


def render_all(diagnostics: Iterable[Diagnostic], sources: Mapping[str, str]) -> str:
    return "\n".join(render(d, sources) for d in diagnostics)
