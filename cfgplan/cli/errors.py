"""Input errors as JSON: what ``--format json`` (and ``jsonl``) prints on
stdout when the input is refused, and what ``cfgplan check --format json``
prints. The models are the shape, defined once: the command line builds its
documents with them, and the documentation takes their JSON Schema.

Each diagnostic is the one printed on stderr (``file:line:col``, message,
hint), as data: see :mod:`cfgplan.diagnostics`. A document is one line,
every character outside ASCII escaped (``\\u001b``), so that it is safe on a
terminal whatever the input holds. The human message still goes to stderr.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

from cfgplan.diagnostics import Diagnostic

__all__ = ["CheckDocument", "DiagnosticEntry", "ErrorDocument", "dump"]


class _Closed(BaseModel):
    """A JSON object whose keys are all named here."""

    model_config = ConfigDict(extra="forbid", frozen=True)


class DiagnosticEntry(_Closed):
    """One error or warning, as stderr shows it: where, what, and a hint.
    ``file`` is ``--goal`` for the text of that option; the place is all
    null for a message about no place (a missing goal, an unwritable file)."""

    severity: Literal["error", "warning", "note"]
    message: str = Field(description="What is wrong, as on stderr.")
    hint: str | None = Field(description="What to do about it, or null.")
    file: str | None = Field(description="The file (or `--goal`), or null.")
    line: int | None = Field(description="1-based line of the start, or null.")
    column: int | None = Field(description="1-based column of the start, or null.")
    end_line: int | None = Field(description="Line of the end, or null.")
    end_column: int | None = Field(description="Column just past the end, or null.")

    @classmethod
    def of(cls, d: Diagnostic) -> DiagnosticEntry:
        span = d.span
        return cls(
            severity=d.severity,
            message=d.message,
            hint=d.hint,
            file=None if span is None else span.file,
            line=None if span is None else span.line,
            column=None if span is None else span.column,
            end_line=None if span is None else span.end_line,
            end_column=None if span is None else span.end_column,
        )


class ErrorDocument(_Closed):
    """The input was refused (exit 1; 3 for a ``--rank`` past the last):
    ``error`` is the first error, ``errors`` every one, in the order of
    stderr; ``warnings`` the warnings and notes found with them."""

    error: DiagnosticEntry = Field(description="The first error (also first in `errors`).")
    errors: list[DiagnosticEntry] = Field(description="Every error, by file position.")
    warnings: list[DiagnosticEntry] = Field(description="Warnings and notes, by file position.")

    @classmethod
    def of(cls, diagnostics: Sequence[Diagnostic]) -> ErrorDocument:
        """The document of ``diagnostics``, of which one at least is an error."""
        errors = [DiagnosticEntry.of(d) for d in diagnostics if d.is_error]
        others = [DiagnosticEntry.of(d) for d in diagnostics if not d.is_error]
        return cls(error=errors[0], errors=errors, warnings=others)


class CheckDocument(_Closed):
    """``cfgplan check --format json`` when there is no error (exit 0)."""

    ok: Literal[True] = Field(description="Always true: no error was found.")
    domain: str = Field(description="The domain file.")
    functionalities: int = Field(description="Functionalities it defines.")
    methods: int = Field(description="Methods it defines, by name and arity.")
    versions: int = Field(description="Method versions (a method may have several).")
    state: str | None = Field(description="The state file, or null.")
    facts: int | None = Field(description="Facts of the state, or null.")
    media: int | None = Field(description="Media of the state, or null.")
    goal: str | None = Field(description="The state's goal, or null.")
    warnings: list[DiagnosticEntry] = Field(description="Warnings and notes, by file position.")


def dump(document: BaseModel) -> str:
    """One line of JSON, ASCII only (deterministic: keys in model order)."""
    return json.dumps(document.model_dump(mode="json"), ensure_ascii=True) + "\n"
