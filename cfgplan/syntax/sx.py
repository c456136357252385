"""Raw s-expressions with source spans: what the grammar's generic rules produce.

The form rules of the grammar (``make-functionality`` and friends) receive
their keyword values as :class:`Sx` trees and interpret them in
:mod:`cfgplan.syntax.forms`.
"""

from __future__ import annotations

from typing import Literal, NamedTuple, Protocol

from cfgplan.ir.model import SExpr, Span

SxKind = Literal["symbol", "number", "list"]


class Located(Protocol):
    """Where a token was read: a Lark ``Token``, or a :class:`Place`."""

    @property
    def line(self) -> int | None: ...
    @property
    def column(self) -> int | None: ...
    @property
    def end_line(self) -> int | None: ...
    @property
    def end_column(self) -> int | None: ...


class Place(NamedTuple):
    """Where an atom of a one-line list (the grammar's ``ATOMS`` token) was
    read: Lark makes no token of its own for it. Lines and columns count
    from 1 as Lark's do; the end is just past the atom."""

    line: int
    column: int
    end_line: int
    end_column: int


def token_end(tok: Located) -> tuple[int, int]:
    """Line and column just past a token (Lark's positions; 0 where it has none)."""
    return tok.end_line or tok.line or 0, tok.end_column or tok.column or 0


def token_span(file: str, tok: Located) -> Span:
    """Where a token stands in ``file``."""
    end_line, end_column = token_end(tok)
    return Span(
        file=file,
        line=tok.line or 0,
        column=tok.column or 0,
        end_line=end_line,
        end_column=end_column,
    )


class Sx:
    """A symbol, a number or a list, with where it was read.

    ``text`` is the token as written (symbols and numbers); ``items`` the
    elements of a list; ``depth`` the list nesting below and including this node.

    A plain class with slots, not a frozen dataclass (whose ``__init__`` sets
    each field through ``object.__setattr__``): the reader makes one for each
    symbol, number and list of a file, 28,000 of them for a 150 KB domain.
    Treat it as immutable all the same.

    ``span`` is where it was read. A list's is made when the list is (the IR
    keeps it); a symbol's or number's only when asked for (:attr:`span`), from
    its token (``at``): only an error message asks. A Span is a pydantic
    model, validated when made: the reader made 47,000 of them for a 150 KB
    domain whose IR keeps 12,600. Safe: the Span made later is the one made
    at once before, from the same token and file name.
    """

    __slots__ = ("_at", "_file", "_span", "depth", "items", "kind", "text")

    def __init__(
        self,
        kind: SxKind,
        span: Span | None = None,
        text: str = "",
        items: tuple[Sx, ...] = (),
        depth: int = 0,
        *,
        at: Located | None = None,
        file: str = "<text>",
    ) -> None:
        if span is None and at is None:
            raise ValueError("an Sx needs a span or where it was read (a token, a Place)")
        self.kind = kind
        self._span = span
        self.text = text
        self.items = items
        self.depth = depth
        self._at = at
        self._file = file

    @property
    def span(self) -> Span:
        """Where it was read: a list's from its first to its last token, an
        atom's from its token (made now, :func:`token_span`)."""
        if self._span is not None:
            return self._span
        assert self._at is not None  # __init__ wants one or the other
        return token_span(self._file, self._at)

    @property
    def end(self) -> tuple[int, int]:
        """Line and column just past its end, without making a Span."""
        if self._span is not None:
            return self._span.end_line, self._span.end_column
        assert self._at is not None
        return token_end(self._at)

    def __repr__(self) -> str:
        return f"Sx({self.kind!r}, {self.span!r}, text={self.text!r}, depth={self.depth})"

    @property
    def is_symbol(self) -> bool:
        return self.kind == "symbol"

    @property
    def is_list(self) -> bool:
        return self.kind == "list"

    def head(self) -> str | None:
        """The leading symbol of a list, or None."""
        if self.kind == "list" and self.items and self.items[0].is_symbol:
            return self.items[0].text
        return None

    def to_sexpr(self) -> SExpr:
        """The plain value (numbers as int/float, symbols as str), iteratively."""
        if self.kind != "list":
            return _atom_value(self)
        root: list[SExpr] = []
        stack: list[tuple[Sx, list[SExpr]]] = [(self, root)]
        while stack:
            node, target = stack.pop()
            for item in node.items:
                if item.kind == "list":
                    child: list[SExpr] = []
                    target.append(child)
                    stack.append((item, child))
                else:
                    target.append(_atom_value(item))
        return root

    def __str__(self) -> str:
        if self.kind != "list":
            return self.text
        return "(" + " ".join(str(i) for i in self.items) + ")"


def _atom_value(node: Sx) -> SExpr:
    if node.kind == "number":
        text = node.text
        if len(text) > 4000:
            from cfgplan.diagnostics import error

            raise error("this number has more than 4000 characters", node.span)
        return float(text) if "." in text else int(text)
    return node.text
