"""Raw s-expressions with source spans: what the grammar's generic rules produce.

The form rules of the grammar (``make-functionality`` and friends) receive
their keyword values as :class:`Sx` trees and interpret them in
:mod:`cfgplan.syntax.forms`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from cfgplan.ir.model import SExpr, Span

SxKind = Literal["symbol", "number", "list"]


@dataclass(frozen=True, slots=True)
class Sx:
    """A symbol, a number or a list, with where it was read.

    ``text`` is the token as written (symbols and numbers); ``items`` the
    elements of a list; ``depth`` the list nesting below and including this node.
    """

    kind: SxKind
    span: Span
    text: str = ""
    items: tuple[Sx, ...] = ()
    depth: int = 0

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
