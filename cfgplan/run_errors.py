"""What goes wrong while running a configuration, said without a traceback (chapter 5).

The runtime is imported by robots that have no planner, so it does not use
:mod:`cfgplan.diagnostics` (which brings the IR and pydantic). A
:class:`RunError` carries the same parts — a message, optionally a place in
a file and a hint — and renders itself compiler style; ``cfgplan run`` turns
it into a diagnostic, emitted robot programs print :meth:`RunError.render`.

A module of its own, at the top of the package: the runtime raises it, and so
does the security package (keys, TLS, rate limits), which the runtime uses;
neither imports the other for it (:mod:`cfgplan.runtime.errors` names it for
the runtime's modules).
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["RunError", "location"]


class RunError(Exception):
    """A user error while running: implementations, options, files, values."""

    def __init__(
        self,
        message: str,
        *,
        hint: str | None = None,
        file: str | None = None,
        line: int | None = None,
        column: int | None = None,
    ) -> None:
        super().__init__(message)
        self.message = message
        self.hint = hint
        self.file = file
        self.line = line
        self.column = column

    def __str__(self) -> str:
        return self.message

    def render(self) -> str:
        """``impl.py:3:9: error: message``, the line quoted with a caret, the hint."""
        if self.file is None:
            out = [f"error: {self.message}"]
        else:
            where = ":".join(str(x) for x in (self.file, self.line, self.column) if x is not None)
            out = [f"{where}: error: {self.message}"]
            quoted = _quote(self.file, self.line, self.column)
            out += quoted
        if self.hint:
            out.append(f"  hint: {self.hint}")
        return "\n".join(out)


def _quote(file: str, line: int | None, column: int | None) -> list[str]:
    if line is None:
        return []
    try:
        lines = Path(file).read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError:
        return []
    if not 1 <= line <= len(lines):
        return []
    text = printable(lines[line - 1].expandtabs(1)[:160])
    gutter = f"{line:>5} | "
    out = [gutter + text]
    if column is not None and 1 <= column <= len(text) + 1:
        out.append(" " * (len(gutter) - 2) + "| " + " " * (column - 1) + "^")
    return out


def printable(text: str) -> str:
    """``text`` with control characters escaped, so that nothing an
    implementation or an input file holds reaches the terminal raw."""
    return "".join(
        c if c.isprintable() or c == " " else c.encode("unicode_escape").decode("ascii")
        for c in text
    )


def location(path: str | Path, line: int | None) -> str:
    """``impl.py:12``: a place in a file, for messages."""
    return f"{path}:{line}" if line is not None else str(path)
