"""Printing the IR back as source text (thesis 4.4, Appendix A).

:func:`print_domain` writes ``make-functionality`` and ``make-config-method``
forms in the style of Appendix A; :func:`print_state` writes one ``(state ...)``
form and, when the state has one, its ``(goal ...)``. The output reads back
with :func:`cfgplan.syntax.reader.parse` into the same IR (equal
``model_dump()``), is deterministic and ends with a newline.

Layout: the ``:name`` stays on the form's first line, every other keyword
starts a line of its own, indented two spaces, in a fixed order; empty fields
are omitted. A list value that does not fit in :data:`WIDTH` columns is broken
and aligned under its first element: lists of atoms and conditions are filled,
a method's ports, channels and body entries go one a line. Quotes are the
ASCII ``'``. Forms are separated by a blank line. Comments and the layout of
the original file are not kept.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from decimal import Decimal

from cfgplan.ir.model import (
    Atom,
    BodyItem,
    ChannelSpec,
    Condition,
    Domain,
    Effect,
    Eval,
    Functionality,
    Medium,
    Method,
    Negation,
    Port,
    SExpr,
    State,
)
from cfgplan.notation import atom_text, sexpr_text

__all__ = [
    "WIDTH",
    "format_atom",
    "format_body_item",
    "format_channel",
    "format_condition",
    "format_functionality",
    "format_medium",
    "format_method",
    "format_port",
    "format_quantity",
    "format_sexpr",
    "print_domain",
    "print_state",
]

WIDTH = 80
"""A list value longer than this (with its indentation) is broken one element a line."""

_INDENT = "  "

# A numeral that reads back as infinity (float() overflows past ~1.8e308); the
# grammar has no literal for it, yet the reader can produce it from a long numeral.
_HUGE = "1" + "0" * 309 + ".0"


# --- numbers ---------------------------------------------------------------


def _positional(x: float) -> str:
    """A finite float as a plain decimal numeral with a point (no exponent),
    shortest digits that read back as the same float."""
    text = repr(x)
    if "e" in text or "E" in text:
        text = format(Decimal(text), "f")
    if "." not in text:
        text += ".0"
    return text


def _float_text(x: float) -> str:
    """A float that reads back as itself via ``float()`` of a NUMBER token."""
    if math.isnan(x):
        raise ValueError("NaN has no source notation")
    if math.isinf(x):
        return _HUGE if x > 0 else "-" + _HUGE
    return _positional(x)


def format_quantity(x: float) -> str:
    """A bandwidth, cost, frequency or capacity: ``20`` rather than ``20.0``."""
    if isinstance(x, int):
        return str(x)
    if math.isfinite(x) and x.is_integer():
        return str(int(x))
    return _float_text(x)


# --- s-expressions and atoms ----------------------------------------------


def _leaf(item: str | int | float) -> str:
    if isinstance(item, bool):  # not produced by the reader; be explicit
        return "t" if item else "nil"
    if isinstance(item, float):
        return _float_text(item)
    return str(item)


def format_sexpr(expr: SExpr) -> str:
    """An ``(eval EXPR)`` expression: symbols, numbers and nested lists.

    Integers print as integers and floats always with a decimal point, so the
    reader gives back the same Python types. ``['quote', x]`` prints as
    ``(quote x)``. Iterative, so deep nesting cannot overflow the stack.
    """
    return sexpr_text(expr, _leaf)


def format_atom(atom: Atom) -> str:
    """``(predicate arg ...)``, e.g. ``(camera ?r)``."""
    return atom_text((atom.predicate, *atom.args))


def format_condition(cond: Condition | Effect) -> str:
    """An atom, ``(not ATOM)`` or ``(eval EXPR)``."""
    if isinstance(cond, Negation):
        return f"(not {format_atom(cond.atom)})"
    if isinstance(cond, Eval):
        return f"(eval {format_sexpr(cond.expr)})"
    return format_atom(cond)


def _with_bandwidth(parts: list[str], bandwidth: float | None) -> str:
    if bandwidth is not None:
        parts.append(format_quantity(bandwidth))
    return atom_text(parts)


def format_port(port: Port) -> str:
    """A method ``:in``/``:out`` entry: ``(?f2 (pos ?r ?d) 20)``."""
    return _with_bandwidth([port.label, format_atom(port.data)], port.bandwidth)


def format_channel(channel: ChannelSpec) -> str:
    """``((local ?r) ?f1 ?f2 (image ?r) 50)`` or ``((global ?a ?b) ...)``."""
    kind = atom_text((channel.kind, *channel.robots))
    parts = [kind, channel.source, channel.target, format_atom(channel.data)]
    return _with_bandwidth(parts, channel.bandwidth)


def format_body_item(item: BodyItem) -> str:
    """``(?f1 (camera ?r))``."""
    return f"({item.label} {format_atom(item.call)})"


# --- layout ----------------------------------------------------------------


def _fill(prefix: str, items: Sequence[str], closer: str) -> str:
    """Items after ``prefix``, as many a line as fit in :data:`WIDTH`, aligned."""
    if not items:
        return prefix.rstrip() + closer
    pad = " " * len(prefix)
    lines: list[str] = []
    current = prefix + items[0]
    for item in items[1:]:
        if len(current) + 1 + len(item) <= WIDTH:
            current += " " + item
        else:
            lines.append(current)
            current = pad + item
    lines.append(current + closer)
    return "\n".join(lines)


def _list_value(prefix: str, items: Sequence[str], fill: bool) -> str:
    """``prefix'(item item ...)`` on one line if it fits; otherwise filled (as many
    items a line as fit) or one item a line, aligned under the first item."""
    one_line = prefix + "'(" + " ".join(items) + ")"
    if len(one_line) <= WIDTH or len(items) < 2:
        return one_line
    if fill:
        return _fill(prefix + "'(", items, ")")
    pad = "\n" + " " * (len(prefix) + 2)
    return prefix + "'(" + pad.join(items) + ")"


_Field = tuple[str, Sequence[str] | str]
"""A keyword and its value: a list's printed elements, or a bare number."""

# Lists of atoms and conditions are filled; a method's ports, channels and body
# entries, which carry labels, go one a line when the list does not fit on one.
_FUNCTIONALITY_FILLED = frozenset({":precond", ":postcond", ":in", ":out"})
_METHOD_FILLED = frozenset({":precond", ":postcond"})


def _form(head: str, name: Atom, fields: list[_Field], filled: frozenset[str]) -> str:
    """``(head :name '(...)`` then one ``:keyword value`` a line; empty fields omitted."""
    lines = [f"({head} :name '{format_atom(name)}"]
    for keyword, value in fields:
        prefix = f"{_INDENT}{keyword} "
        if isinstance(value, str):
            lines.append(prefix + value)
        elif value:
            lines.append(_list_value(prefix, value, keyword in filled))
    return "\n".join(lines) + ")"


def format_functionality(f: Functionality) -> str:
    """A ``make-functionality`` form (3.2, 4.4; Appendix A).

    Order: ``:name :precond :postcond :in :out :cost :freq :reliability``.
    """
    fields: list[_Field] = [
        (":precond", [format_condition(c) for c in f.precond]),
        (":postcond", [format_condition(c) for c in f.postcond]),
        (":in", [format_atom(a) for a in f.inputs]),
        (":out", [format_atom(a) for a in f.outputs]),
    ]
    if f.cost is not None:
        fields.append((":cost", format_quantity(f.cost)))
    if f.freq is not None:
        fields.append((":freq", format_quantity(f.freq)))
    if f.reliability is not None:
        fields.append((":reliability", format_quantity(f.reliability)))
    return _form("make-functionality", f.name, fields, _FUNCTIONALITY_FILLED)


def format_method(m: Method) -> str:
    """A ``make-config-method`` form (4.4; Appendix A).

    Order: ``:name :precond :postcond :in :out :channels :body``.
    """
    return _form(
        "make-config-method",
        m.name,
        [
            (":precond", [format_condition(c) for c in m.precond]),
            (":postcond", [format_condition(c) for c in m.postcond]),
            (":in", [format_port(p) for p in m.inputs]),
            (":out", [format_port(p) for p in m.outputs]),
            (":channels", [format_channel(c) for c in m.channels]),
            (":body", [format_body_item(b) for b in m.body]),
        ],
        _METHOD_FILLED,
    )


def format_medium(medium: Medium) -> str:
    """``(medium socket Pippi Emil 200)`` (4.6)."""
    # The reader takes a capacity through float(), which also accepts "nan";
    # print it back the same way rather than refuse the state.
    capacity = "nan" if math.isnan(medium.capacity) else format_quantity(medium.capacity)
    parts = ["medium", medium.type, medium.sender, medium.receiver, capacity]
    if medium.reliability is not None:
        parts.append(format_quantity(medium.reliability))
    return atom_text(parts)


def print_domain(domain: Domain) -> str:
    """The domain as source text: its functionalities, then its methods, in order,
    one top-level form each, separated by blank lines (4.4, Appendix A)."""
    forms = [format_functionality(f) for f in domain.functionalities]
    forms += [format_method(m) for m in domain.methods]
    if not forms:
        return "; (empty domain)\n"
    return "\n\n".join(forms) + "\n"


def print_state(state: State) -> str:
    """The state as ``(state FACT ... (medium TYPE FROM TO CAPACITY) ...)``, facts
    first and media after, then ``(goal (...))`` if it has a goal (4.4, 4.6)."""
    items = [format_atom(f) for f in state.facts] + [format_medium(m) for m in state.media]
    text = _fill("(state ", items, ")")
    if state.goal is not None:
        text += f"\n\n(goal {format_atom(state.goal.call)})"
    if state.sequence:
        goals = "\n          ".join(format_atom(g.call) for g in state.sequence)
        text += f"\n\n(sequence {goals})"
    return text + "\n"
