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
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar

_deadline: ContextVar[float | None] = ContextVar("cfgplan_deadline", default=None)


class OutOfTime(Exception):
    """The time limit has passed; the search stops with what it has."""


@contextmanager
def limit(deadline: float | None) -> Iterator[None]:
    """Run the block under ``deadline`` (a :func:`time.perf_counter` value; None: no limit)."""
    token = _deadline.set(deadline)
    try:
        yield
    finally:
        _deadline.reset(token)


def check() -> None:
    """Raise :class:`OutOfTime` if the current deadline has passed."""
    deadline = _deadline.get()
    if deadline is not None and time.perf_counter() > deadline:
        raise OutOfTime


def remaining() -> float | None:
    """Seconds left before the current deadline (None: no limit)."""
    deadline = _deadline.get()
    return None if deadline is None else deadline - time.perf_counter()
