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
"""

from __future__ import annotations

from collections.abc import Sequence

from cfgplan.backends.wiring import Call, RobotPart
from cfgplan.configuration.model import Channel

__all__ = ["call_form", "channel_name", "make_channel", "to_lisp"]


def channel_name(index: int) -> str:
    """``CH-1`` for the first channel (``index`` is 0-based)."""
    return f"CH-{index + 1}"


def make_channel(robot: str, ch: Channel) -> str:
    """The form that creates ``ch`` on ``robot`` (5.2.2)."""
    data = "'(" + " ".join(ch.data) + ")"
    if ch.kind == "local":
        return f"(make-local-channel '{ch.source_robot} '{ch.source} '{ch.target} {data})"
    other = ch.target_robot if ch.source_robot == robot else ch.source_robot
    return f"(make-global-channel '{other} '{ch.source} '{ch.target} {data})"


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
    parts = [call.functionality.name]
    parts += [f"'{x}" for x in call.objects]
    parts += [_input(x) for x in call.inputs]
    parts += [_output(x) for x in call.outputs]
    return "(" + " ".join(parts) + ")"


def to_lisp(part: RobotPart, comments: Sequence[str] = ()) -> str:
    """The executable individual configuration of ``part`` (5.3, 5.4), with
    ``comments`` as leading ``;;`` lines; ends with a newline."""
    lines = [f";; {c}".rstrip() for c in comments]
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
