"""A robot's part of a configuration as plain data: what :func:`~cfgplan.runtime.build` runs.

The same information as the module ``cfgplan emit --lang python`` writes for
a robot (5.3): the channels in order (the ``LET``; CH-1 is index 0) and the
calls in sorted order (the ``LAMBDA``), each with the channel indexes feeding
its inputs and taking its outputs. Plain tuples and strings, so that a robot
runs a configuration without the planner, the IR or pydantic; the backends
build it (:func:`cfgplan.backends.part.runtime_part`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

from cfgplan.runtime.wire import is_number, name, names, whole

__all__ = ["CallSpec", "ChannelSpec", "Part", "part_from_json", "part_to_json"]


@dataclass(frozen=True)
class ChannelSpec:
    """``(make-local-channel 'R 'SRC 'DST '(data))`` or, with ``other``,
    ``(make-global-channel 'OTHER 'SRC 'DST '(data))`` (5.2.2)."""

    kind: Literal["local", "global"]
    source: str
    target: str
    data: tuple[str, ...]
    other: str | None = None


@dataclass(frozen=True)
class CallSpec:
    """One functionality of the cycle: ``(name 'obj ... CH-i ... (LIST CH-j ...) ...)``."""

    label: str
    name: str
    objects: tuple[str, ...]
    inputs: tuple[tuple[int, ...], ...]
    outputs: tuple[tuple[int, ...], ...]
    freq: float | None = None


@dataclass(frozen=True)
class Part:
    """One robot's executable individual configuration."""

    robot: str
    channels: tuple[ChannelSpec, ...]
    calls: tuple[CallSpec, ...]
    cost: float | None = None
    """The cost of the configuration this part belongs to (3.5), when the one
    who made the part knows it: recorded in the robot's ``start`` event, so
    that a report of the run can name it (not sent with a part at a switch:
    the ``switch`` event names the new cost)."""


def part_to_json(part: Part) -> dict[str, Any]:
    """``part`` as JSON-ready data: how a coordinator sends a robot its part (5.5)."""
    return {
        "robot": part.robot,
        "channels": [[c.kind, c.source, c.target, list(c.data), c.other] for c in part.channels],
        "calls": [
            [
                c.label,
                c.name,
                list(c.objects),
                [list(i) for i in c.inputs],
                [list(o) for o in c.outputs],
                c.freq,
            ]
            for c in part.calls
        ],
    }


def part_from_json(data: Any) -> Part:
    """The inverse of :func:`part_to_json`; ``ValueError`` when ``data`` is not a part.

    A part comes from another process: every value is checked for the type
    :func:`part_to_json` writes (names are strings, channel indexes whole
    numbers, a frequency a positive finite number), so that one that passes
    cannot fail later, when it is installed or run."""
    try:
        channels = tuple(
            ChannelSpec(
                _kind(kind),
                name(source),
                name(target),
                names(d),
                None if other is None else name(other),
            )
            for kind, source, target, d, other in data["channels"]
        )
        calls = tuple(
            CallSpec(
                name(label),
                name(call),
                names(objects),
                tuple(tuple(whole(i, "a channel index") for i in x) for x in inputs),
                tuple(tuple(whole(i, "a channel index") for i in x) for x in outputs),
                None if freq is None else _freq(freq),
            )
            for label, call, objects, inputs, outputs, freq in data["calls"]
        )
        robot = name(data["robot"])
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"not a part of a configuration: {exc}") from None
    for c in channels:
        if (c.kind == "global") != (c.other is not None):
            raise ValueError(f"not a channel: {c}")
    width = len(channels)
    if any(i >= width or i < 0 for c in calls for x in (*c.inputs, *c.outputs) for i in x):
        raise ValueError("a call names a channel the part does not have")
    return Part(robot, channels, calls)


def _kind(value: Any) -> Literal["local", "global"]:
    if value == "local":
        return "local"
    if value == "global":
        return "global"
    raise ValueError(f"{value!r} is not a kind of channel")


def _freq(value: Any) -> float:
    if not is_number(value):
        raise ValueError(f"{value!r} is not a frequency")
    if not math.isfinite(value) or value <= 0:
        raise ValueError(f"{value!r} Hz is not a frequency a functionality can run at")
    return float(value)
