"""Where a key of a TOML file is written, for messages with a caret.

:mod:`tomllib` reports syntax errors with a line and a column but keeps no
positions for the values it returns, so a message about a value (``robots.
Pippi.at``: three numbers expected) finds its key again in the text: the
table whose header (``[robots.Pippi]``, or the n-th ``[[events]]``) is the
longest prefix of the key's path, then the rest of the path inside that
table — a dotted key, or a key of an inline table on one line. When the
whole path cannot be found, the deepest part of it that can is pointed at.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from cfgplan.diagnostics import lines_of
from cfgplan.ir.model import Span

__all__ = ["locate", "span_at"]

Path = Sequence[str | int]

_HEADER = re.compile(r"^\s*(\[\[?)\s*([^\]]+?)\s*\]\]?\s*(#.*)?$")
_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def span_at(file: str, line: int, column: int, width: int = 1) -> Span:
    return Span(file=file, line=line, column=column, end_line=line, end_column=column + width)


def _quoted(key: str) -> str:
    return re.escape(key) if _BARE.match(key) else f'"{re.escape(key)}"'


def _tables(lines: list[str]) -> list[tuple[list[str | int], int, int]]:
    """Each table: its path (an array of tables adds its index), first and
    last line (0-based, the header's line first; the root table has none)."""
    tables: list[tuple[list[str | int], int, int]] = [([], -1, len(lines))]
    counts: dict[tuple[str, ...], int] = {}
    for i, line in enumerate(lines):
        m = _HEADER.match(line)
        if not m:
            continue
        keys = [k.strip().strip('"') for k in m.group(2).split(".")]
        path: list[str | int] = list(keys)
        if m.group(1) == "[[":
            index = counts.get(tuple(keys), 0)
            counts[tuple(keys)] = index + 1
            path.append(index)
        path_, first, _ = tables[-1]
        tables[-1] = (path_, first, i)
        tables.append((path, i, len(lines)))
    return tables


def _find(lines: list[str], path: Path) -> tuple[int, int, int] | None:
    best: tuple[int, int, int] | None = None
    best_depth = -1
    for table, first, last in _tables(lines):
        n = len(table)
        if n > len(path) or list(path[:n]) != table or n <= best_depth:
            continue
        if n == len(path) and first >= 0:
            line = lines[first]
            key = str(table[-2] if isinstance(table[-1], int) else table[-1])
            return first + 1, max(1, line.find(key) + 1), len(key)
        keys = [k for k in path[n:] if isinstance(k, str)]
        found = _key(lines, first + 1, last, keys) if keys else None
        if found is not None:
            best, best_depth = found, n
    return best


def _key(lines: list[str], first: int, last: int, keys: list[str]) -> tuple[int, int, int] | None:
    """The deepest of ``keys`` written in lines[first:last]: as a dotted key
    ``a.b = ...``, or inside an inline table ``a = { b = ... }``."""
    whole = re.compile(r"^\s*" + r"\s*\.\s*".join(_quoted(k) for k in keys) + r"\s*=")
    for i in range(first, last):
        if whole.match(lines[i]):
            return i + 1, lines[i].find(keys[0]) + 1, len(".".join(keys))
    head = re.compile(r"^\s*" + _quoted(keys[0]) + r"\s*=")
    for i in range(first, last):
        if head.match(lines[i]):
            for key in reversed(keys[1:]):
                inner = re.search(r"[{,]\s*(" + _quoted(key) + r")\s*=", lines[i])
                if inner:
                    return i + 1, inner.start(1) + 1, len(key)
            return i + 1, lines[i].find(keys[0]) + 1, len(keys[0])
    return _key(lines, first, last, keys[:-1]) if len(keys) > 1 else None


def locate(text: str, file: str, path: Path) -> Span | None:
    """The span of the key at ``path`` (strings are keys, integers indices
    of arrays), or of the deepest part of it that is written, or ``None``."""
    lines = lines_of(text)
    for depth in range(len(path), 0, -1):
        found = _find(lines, path[:depth])
        if found is not None:
            return span_at(file, *found)
    return None
