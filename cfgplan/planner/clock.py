"""The time limit of a search, checked wherever the planner may spend long.

``--time-limit S`` must end a run within S plus a moment, whatever it is
doing: expanding one node with thousands of bindings, summarising a deep
hierarchy, assigning channels to media. Rather than passing a deadline
through every call, :func:`limit` sets it for the search that runs in its
``with`` block, and the hot loops call :func:`check`, which raises
:class:`OutOfTime` once it has passed (a time read costs about 0.1 µs).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass

_deadline: ContextVar[float | None] = ContextVar("cfgplan_deadline", default=None)


@dataclass(eq=False, repr=False)
class Work:
    """The calls of :func:`check` in a :func:`counting` block: a measure of
    the search's work that, unlike time, is the same on every machine."""

    done: int = 0
    most: int | None = None
    """Past this many, :func:`check` raises :class:`OutOfWork` (None: never)."""


_work: ContextVar[Work | None] = ContextVar("cfgplan_work", default=None)

_beside: ContextVar[Callable[[], None] | None] = ContextVar("cfgplan_beside", default=None)
"""Called at every :func:`check` (:func:`beside`)."""


class OutOfTime(Exception):
    """The time limit has passed; the search stops with what it has."""


class OutOfWork(Exception):
    """The work allowed a look-ahead (:attr:`Work.most`) is spent."""


@contextmanager
def counting() -> Iterator[Work]:
    """Count the work of the block (:class:`Work`)."""
    work = Work()
    token = _work.set(work)
    try:
        yield work
    finally:
        _work.reset(token)


@contextmanager
def limit(deadline: float | None) -> Iterator[None]:
    """Run the block under ``deadline`` (a :func:`time.perf_counter` value; None: no limit)."""
    token = _deadline.set(deadline)
    try:
        yield
    finally:
        _deadline.reset(token)


@contextmanager
def beside(tick: Callable[[], None]) -> Iterator[None]:
    """Call ``tick`` at every :func:`check` of the block: what runs beside the
    search and may end it, by raising (the solver's process racing it,
    :mod:`cfgplan.planner.solver`)."""
    token = _beside.set(tick)
    try:
        yield
    finally:
        _beside.reset(token)


def check() -> None:
    """Raise :class:`OutOfTime` if the current deadline has passed, and
    :class:`OutOfWork` if the work allowed is spent (one step of it); call what
    runs :func:`beside` the block."""
    deadline = _deadline.get()
    if deadline is not None and time.perf_counter() > deadline:
        raise OutOfTime
    work = _work.get()
    if work is not None:
        work.done += 1
        if work.most is not None and work.done > work.most:
            raise OutOfWork
    tick = _beside.get()
    if tick is not None:
        tick()


def remaining() -> float | None:
    """Seconds left before the current deadline (None: no limit)."""
    deadline = _deadline.get()
    return None if deadline is None else deadline - time.perf_counter()
