"""What a running configuration did, as lines of text (``cfgplan run``, emitted code).

Values are shown compactly and deterministically: floats with three
decimals, tuples, lists and dicts element by element, anything else by its
``repr``.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from cfgplan.configuration.describe import call_text
from cfgplan.runtime.wrapper import Event

__all__ = ["describe", "show", "summary"]


def show(value: object) -> str:
    """``(1.500, -0.250)`` for a pair of floats; ``{'Door1': (...)}`` for a dict."""
    if isinstance(value, bool) or value is None:
        return repr(value)
    if isinstance(value, float):
        text = f"{value:.3f}"
        return "0.000" if text == "-0.000" else text
    if isinstance(value, tuple):
        inner = ", ".join(show(v) for v in value)
        return f"({inner},)" if len(value) == 1 else f"({inner})"
    if isinstance(value, list):
        return "[" + ", ".join(show(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{show(k)}: {show(v)}" for k, v in value.items()) + "}"
    return repr(value)


def _pairs(pairs: Iterable[tuple[tuple[str, ...], object]]) -> str:
    return ", ".join(f"{call_text(d)} = {'(no data)' if v is None else show(v)}" for d, v in pairs)


def describe(event: Event) -> str:
    """One line: ``cycle 2: Pippi F3 cross-door(Pippi, Door1) received pos(...) = ...``."""
    head = (
        f"cycle {event.cycle}: {event.robot} {event.label} {call_text((event.name, *event.args))}"
    )
    if event.status == "waiting":
        return f"{head} waits for " + ", ".join(call_text(d) for d in event.waiting)
    if event.status == "precondition":
        return f"{head} does not run: precondition false"
    if event.action:
        return f"{head} received {_pairs(event.inputs)}".rstrip()
    parts = []
    if event.inputs:
        parts.append(f"read {_pairs(event.inputs)}")
    parts.append(f"wrote {_pairs(event.outputs)}")
    return f"{head} " + "; ".join(parts)


def summary(events: Sequence[Event]) -> list[str]:
    """Per functionality, in order of first call: how many cycles it ran."""
    order: dict[tuple[str, str], list[Event]] = {}
    for e in events:
        order.setdefault((e.robot, e.label), []).append(e)
    lines = []
    for seen in order.values():
        last = seen[-1]
        ran = sum(1 for e in seen if e.status == "ran")
        line = f"{last.robot} {last.label} {call_text((last.name, *last.args))}: "
        line += f"ran in {ran} of {len(seen)} cycles"
        if ran == 0 and last.status == "waiting":
            line += "; waits for " + ", ".join(call_text(d) for d in last.waiting)
        elif ran == 0 and last.status == "precondition":
            line += "; precondition false"
        lines.append(line)
    return lines
