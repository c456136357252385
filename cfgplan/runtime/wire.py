"""Reading JSON that another process wrote: the types its writers use,
checked before anything acts on them (a switch message, a robot's part, a
detection, a channel's envelope). JSON's ``true`` reads as a Python bool,
which is also an int, and ``1e999`` as an infinite float: neither is an id,
an index or a time."""

from __future__ import annotations

from typing import TypeGuard

__all__ = ["is_number", "is_whole", "name", "names", "whole"]


def is_whole(value: object) -> TypeGuard[int]:
    """A whole JSON number (not ``true``, not ``1.0``)."""
    return isinstance(value, int) and not isinstance(value, bool)


def is_number(value: object) -> TypeGuard[int | float]:
    """A JSON number (not ``true``); it may be infinite (``1e999``)."""
    return isinstance(value, int | float) and not isinstance(value, bool)


def whole(value: object, what: str) -> int:
    """``value`` as :func:`is_whole` reads it; ``ValueError`` naming ``what`` it is not."""
    if not is_whole(value):
        raise ValueError(f"{value!r} is not {what}")
    return value


def name(value: object) -> str:
    """A name: a JSON string (``ValueError`` else)."""
    if not isinstance(value, str):
        raise ValueError(f"{value!r} is not a name")
    return value


def names(values: object) -> tuple[str, ...]:
    """A JSON list of names (``ValueError`` else)."""
    if not isinstance(values, list) or not all(isinstance(v, str) for v in values):
        raise ValueError(f"{values!r} is not a list of names")
    return tuple(values)
