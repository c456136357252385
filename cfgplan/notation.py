"""How atoms, calls and s-expressions are written in every message and output.

The thesis uses two notations, and cfgplan keeps both, each in its place:

* **s-expressions** (the domain language, 4.4, Appendix A): a fact, a
  precondition or a data descriptor as written in the files,
  ``(in Pippi Room1)``; :func:`atom_text`, :func:`sexpr_text`;
* **the printed call** (the configuration descriptions of 4.4 and 4.6):
  ``get-door-info(Pippi, Door1)`` for a method or functionality instance or a
  data descriptor; :func:`call_text`, and ``F3: cross-door(Pippi, Door1)``
  for a labelled instance, :func:`instance_text`.

This module imports nothing of cfgplan, so the runtime (which a robot runs
without the planner) shares it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

__all__ = ["atom_text", "call_text", "instance_text", "sexpr_text"]


def atom_text(atom: Sequence[str]) -> str:
    """``(in Pippi Room1)``: an atom (predicate first) as an s-expression."""
    return "(" + " ".join(atom) + ")"


def call_text(atom: Sequence[str]) -> str:
    """``get-door-info(Pippi, Door1)``: an instance or a data descriptor in the
    thesis's printed notation."""
    return f"{atom[0]}({', '.join(atom[1:])})"


def instance_text(label: str, name: str, args: Sequence[str]) -> str:
    """``F3: cross-door(Pippi, Door1)``: a labelled functionality instance (4.6)."""
    return f"{label}: {call_text((name, *args))}"


def sexpr_text(expr: object, leaf: Callable[[Any], str] = str) -> str:
    """An s-expression as written, e.g. ``(not (eql (quote ?r) (quote ?rh1)))``:
    ``expr`` is an :data:`cfgplan.ir.model.SExpr`, nested lists of symbols
    and numbers; ``leaf`` writes a symbol or a number (default: ``str``).
    Iterative, so that nesting thousands deep cannot overflow the stack.
    """
    out: list[str] = []
    # Work items: an expression to write, or a literal string (a 1-tuple) to emit.
    stack: list[object] = [expr]
    while stack:
        item = stack.pop()
        if isinstance(item, tuple):
            out.append(item[0])
        elif isinstance(item, list):
            out.append("(")
            stack.append((")",))
            for i in range(len(item) - 1, -1, -1):
                stack.append(item[i])
                if i > 0:
                    stack.append((" ",))
        else:
            out.append(leaf(item))
    return "".join(out)
