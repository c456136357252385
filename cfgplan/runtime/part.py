"""A robot's part of a configuration as plain data: what :func:`~cfgplan.runtime.build` runs.

The same information as the module ``cfgplan emit --lang python`` writes for
a robot (5.3): the channels in order (the ``LET``; CH-1 is index 0) and the
calls in sorted order (the ``LAMBDA``), each with the channel indexes feeding
its inputs and taking its outputs. Plain tuples and strings, so that a robot
runs a configuration without the planner, the IR or pydantic; the backends
build it (:func:`cfgplan.backends.part.runtime_part`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

__all__ = ["CallSpec", "ChannelSpec", "Part"]


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
