"""Translating an individual configuration into the LISP form of 5.3.

The algorithm of 5.3: a ``LET`` binds the robot's channels, labelled CH-1 ..
CH-n by their position in its channel list, each made by
``(make-local-channel 'ROBOT 'SRC 'DST '(data ...))`` or
``(make-global-channel 'OTHER 'SRC 'DST '(data ...))`` with the other robot
first; a ``LAMBDA`` encloses a ``PROGN`` of one call per functionality in
sorted order. A call passes the object arguments quoted (the robot is
implicit), then one channel per ``:in`` descriptor in ``:in`` order, then one
``(LIST ...)`` per ``:out`` descriptor in ``:out`` order (5.2.1)::

    (measure-door 'Door1 CH-4 (LIST CH-5) (LIST CH-6))

Where the thesis is silent: when several channels feed one input the call
passes ``(LIST CH-a CH-b)`` in that position, an input without a channel is
``NIL`` and an output without one ``(LIST)``. Symbols keep the domain's case;
``LET``, ``LAMBDA``, ``PROGN``, ``LIST`` and ``NIL`` are upper case as the
thesis prints them. The layout is that of 5.4, one channel a line.

A name is written bare, as the thesis writes it (``'Door1``), when a Common
Lisp reader reads it as one symbol (folding its case, as for the thesis's
code): it starts with a letter and holds only letters, digits and
``-_+*/<>=!?$%&.``; a number stays a number. Any other
name is written between bars with ``\\`` and ``|`` escaped (``'|#\\|Door1|``),
so that no name can open a comment (``#|``), a string, a package prefix
(``:``) or end the form. Comments show unsafe characters escaped.

Of Common Lisp the file uses only :data:`RESERVED` (``'x`` reads as ``(QUOTE
x)``): a name that folds to one of them (``list``, ``Nil``) is written between
bars too, so that it reads as itself, not as the operator; a functionality
named exactly ``LIST`` (or ``LET`` ...) cannot be called in this form at all,
and is an error (emit ``--lang python``, or rename it).
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from cfgplan.backends.wiring import Call, RobotPart
from cfgplan.configuration.model import Channel
from cfgplan.diagnostics import error, printable

__all__ = ["RESERVED", "call_form", "channel_name", "lisp_symbol", "make_channel", "to_lisp"]

_PLAIN = re.compile(r"[A-Za-z][A-Za-z0-9\-_+*/<>=!?$%&.]*|[-+]?[0-9]+(\.[0-9]+)?")


RESERVED = frozenset({"LET", "LAMBDA", "PROGN", "LIST", "NIL", "QUOTE"})
"""The Common Lisp symbols the form of 5.3 is made of."""


def lisp_symbol(name: str) -> str:
    """``name`` as a Common Lisp reader reads it back: as it is when it is plain
    (``Door1``, ``measure-door``, ``20``) and folds to none of :data:`RESERVED`,
    else ``|...|`` with ``\\`` and ``|`` escaped."""
    if _PLAIN.fullmatch(name) and (name.upper() not in RESERVED or name.isupper()):
        return name
    return "|" + name.replace("\\", "\\\\").replace("|", "\\|") + "|"


def channel_name(index: int) -> str:
    """``CH-1`` for the first channel (``index`` is 0-based)."""
    return f"CH-{index + 1}"


def make_channel(robot: str, ch: Channel) -> str:
    """The form that creates ``ch`` on ``robot`` (5.2.2)."""
    data = "'(" + " ".join(lisp_symbol(x) for x in ch.data) + ")"
    ends = f"'{lisp_symbol(ch.source)} '{lisp_symbol(ch.target)} {data}"
    if ch.kind == "local":
        return f"(make-local-channel '{lisp_symbol(ch.source_robot)} {ends})"
    other = ch.target_robot if ch.source_robot == robot else ch.source_robot
    return f"(make-global-channel '{lisp_symbol(other)} {ends})"


def _input(channels: Sequence[int]) -> str:
    if not channels:
        return "NIL"
    if len(channels) == 1:
        return channel_name(channels[0])
    return "(LIST " + " ".join(channel_name(i) for i in channels) + ")"


def _output(channels: Sequence[int]) -> str:
    return "(LIST" + "".join(" " + channel_name(i) for i in channels) + ")"


def call_form(call: Call) -> str:
    """``(measure-door 'Door1 CH-4 (LIST CH-5) (LIST CH-6))`` (5.2.1)."""
    name = call.functionality.name
    if name in RESERVED:
        raise error(
            f"the functionality {name} cannot be called in the LISP of 5.3: "
            f"{name} is Common Lisp's, which the form is made of",
            hint="emit --lang python, or rename the functionality in the domain",
        )
    parts = [lisp_symbol(name)]
    parts += [f"'{lisp_symbol(x)}" for x in call.objects]
    parts += [_input(x) for x in call.inputs]
    parts += [_output(x) for x in call.outputs]
    return "(" + " ".join(parts) + ")"


def to_lisp(part: RobotPart, comments: Sequence[str] = ()) -> str:
    """The executable individual configuration of ``part`` (5.3, 5.4), with
    ``comments`` as leading ``;;`` lines; ends with a newline."""
    lines = [f";; {printable(c)}".rstrip() for c in comments]
    channels = [
        f"({channel_name(i)} {make_channel(part.robot, ch)})"
        for i, ch in enumerate(part.individual.channels)
    ]
    if not channels:
        lines.append("(LET ()")
    else:
        for i, text in enumerate(channels):
            head = "(LET (" if i == 0 else "      "
            tail = ")" if i == len(channels) - 1 else ""
            lines.append(head + text + tail)
    lines.append("  (LAMBDA NIL")
    calls = [call_form(c) for c in part.calls]
    if not calls:
        lines.append("    (PROGN)))")
    for i, text in enumerate(calls):
        head = "    (PROGN " if i == 0 else "           "
        tail = ")))" if i == len(calls) - 1 else ""
        lines.append(head + text + tail)
    return "\n".join(lines) + "\n"
