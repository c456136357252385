"""Wording and ordering of the checker's diagnostics (see :mod:`cfgplan.check.checker`)."""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from cfgplan.check.unify import Signature
from cfgplan.diagnostics import Diagnostic
from cfgplan.ir.model import Span


def args_text(n: int) -> str:
    """``1 argument``, ``2 arguments``."""
    return f"{n} argument" if n == 1 else f"{n} arguments"


def sig_text(sig: Signature) -> str:
    """``(camera ...) with 1 argument``."""
    return f"({sig[0]} ...) with {args_text(sig[1])}"


def alternatives(numbers: Iterable[int]) -> str:
    """``2 or 3 arguments``: the arities a name is defined with."""
    items = [str(n) for n in sorted(set(numbers))]
    text = items[0] if len(items) == 1 else ", ".join(items[:-1]) + " or " + items[-1]
    return text + (" argument" if items == ["1"] else " arguments")


def position(span: Span | None) -> tuple[int, int]:
    """Line and column, for sorting (no span sorts last)."""
    return (span.line, span.column) if span is not None else (1 << 30, 0)


def where(span: Span | None, here: Span | None) -> str:
    """``line 12`` when ``span`` is in the file of ``here``, else ``file:line:col``."""
    if span is None:
        return "elsewhere"
    if here is not None and here.file == span.file:
        return f"line {span.line}"
    return str(span)


def by_position(found: Sequence[Diagnostic], files: Sequence[str] = ()) -> list[Diagnostic]:
    """Diagnostics by file (``files`` first, then in order of first report), line and
    column; stable, and those without a span last."""
    rank: dict[str, int] = {name: i for i, name in enumerate(dict.fromkeys(files))}
    for d in found:
        if d.span is not None:
            rank.setdefault(d.span.file, len(rank))

    def key(item: tuple[int, Diagnostic]) -> tuple[int, int, int, int]:
        index, d = item
        file_rank = rank[d.span.file] if d.span is not None else len(rank)
        return (file_rank, *position(d.span), index)

    return [d for _, d in sorted(enumerate(found), key=key)]
