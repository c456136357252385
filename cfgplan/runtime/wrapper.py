"""The wrapper function of 5.2.1: the standard interface of a functionality.

The configuration calls the wrapper once a cycle with the functionality's
channels: one entry per input, one list of channels per output, as the LISP
call of 5.3 passes them. If every input has fresh data and the precondition
holds, the wrapper reads the inputs, runs the actual function and writes each
output to all of its channels; otherwise it returns without running it.

An input entry is a channel, a list of channels (several feed it; it is fresh
when one of them is, and the first fresh one in the list gives the value, all
fresh ones being read) or ``None`` (nothing feeds it: the function never runs).
Each call returns an :class:`Event` saying what happened.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, replace
from typing import Literal

from cfgplan.diagnostics import CfgplanError, error
from cfgplan.runtime.channel import Channel
from cfgplan.runtime.registry import Implementation

__all__ = ["Event", "Input", "Wrapper", "current_robot"]

Input = Channel | Sequence[Channel] | None
Data = tuple[str, ...]
Status = Literal["ran", "waiting", "precondition"]

_robot: ContextVar[str] = ContextVar("cfgplan_robot")


def current_robot() -> str:
    """The robot whose functionality is running (for implementations)."""
    try:
        return _robot.get()
    except LookupError:
        raise error("current_robot() is only known while a functionality runs") from None


@contextmanager
def running_on(robot: str) -> Iterator[None]:
    token = _robot.set(robot)
    try:
        yield
    finally:
        _robot.reset(token)


@dataclass(frozen=True)
class Event:
    """One call of a wrapper: what ran, or what it waited for.

    ``inputs`` pairs each input's descriptor with the value read (``ran``);
    ``waiting`` lists the descriptors without fresh data; ``outputs`` pairs
    each output's descriptor with the value written (``None``: not written).
    """

    robot: str
    label: str
    name: str
    args: tuple[str, ...]
    status: Status
    inputs: tuple[tuple[Data, object], ...] = ()
    waiting: tuple[Data, ...] = ()
    outputs: tuple[tuple[Data, object], ...] = ()
    action: bool = False
    cycle: int = 0


def _channels(entry: Input) -> list[Channel]:
    if entry is None:
        return []
    if isinstance(entry, Channel):
        return [entry]
    return list(entry)


def _data(channels: Sequence[Channel], what: str, k: int) -> Data:
    return channels[0].data if channels else (f"{what}-{k + 1}",)


class Wrapper:
    """The wrapper of functionality ``label`` (``name``) on ``robot``."""

    def __init__(
        self,
        robot: str,
        label: str,
        name: str,
        objects: Sequence[str],
        implementation: Implementation,
        record: Callable[[Event], Event] | None = None,
    ) -> None:
        self.robot = robot
        self.label = label
        self.name = name
        self.objects = tuple(objects)
        self.implementation = implementation
        self.record = record  # sees (and may complete) every event, e.g. with the cycle

    def __call__(self, inputs: Sequence[Input], outputs: Sequence[Sequence[Channel]]) -> Event:
        event = self._call(inputs, outputs)
        return event if self.record is None else self.record(event)

    def __str__(self) -> str:
        return f"{self.label}: {self.name}({', '.join((self.robot, *self.objects))})"

    def _call(self, inputs: Sequence[Input], outputs: Sequence[Sequence[Channel]]) -> Event:
        feeds = [_channels(x) for x in inputs]
        data = [_data(chs, "input", k) for k, chs in enumerate(feeds)]
        out_data = [_data(chs, "output", k) for k, chs in enumerate(outputs)]
        base = Event(
            self.robot,
            self.label,
            self.name,
            (self.robot, *self.objects),
            "waiting",
            action=not outputs,
        )
        stale = tuple(
            d for d, chs in zip(data, feeds, strict=True) if not any(c.fresh for c in chs)
        )
        if stale:
            return replace(base, waiting=stale)
        with running_on(self.robot):
            try:
                if not self.implementation.allowed(*self.objects):
                    return replace(base, status="precondition")
                values = [_read(chs) for chs in feeds]
                result = self.implementation(*self.objects, *values)
            except CfgplanError:
                raise
            except Exception as exc:
                raise error(
                    f"{self} on {self.robot}: the implementation or its precondition raised "
                    f"{type(exc).__name__}: {exc}"
                ) from exc
        produced = self._split(result, len(outputs))
        for value, channels in zip(produced, outputs, strict=True):
            if value is not None:
                for ch in channels:
                    ch.write(value)
        return replace(
            base,
            status="ran",
            inputs=tuple(zip(data, values, strict=True)),
            outputs=tuple(zip(out_data, produced, strict=True)),
        )

    def _split(self, result: object, n: int) -> list[object]:
        """The outputs in :out order (one value when there is one output)."""
        if n == 0:
            return []
        if n == 1:
            return [result]
        if result is None:
            return [None] * n
        if not isinstance(result, tuple | list) or len(result) != n:
            raise error(
                f"{self} on {self.robot}: the implementation must return {n} outputs "
                f"(a tuple in :out order), not {result!r}"
            )
        return list(result)


def _read(channels: Sequence[Channel]) -> object:
    fresh = [c for c in channels if c.fresh]
    values = [c.read() for c in fresh]
    return values[0]
