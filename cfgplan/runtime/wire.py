"""Reading JSON that another process wrote: the types its writers use,
checked before anything acts on them (a switch message, a robot's part, a
detection, a channel's envelope). JSON's ``true`` reads as a Python bool,
which is also an int, and ``1e999`` as an infinite float: neither is an id,
an index or a time. JSON has no ``NaN`` nor ``Infinity``: Python's reader
takes them, :func:`loads` does not."""

from __future__ import annotations

import json
import math
from typing import TypeGuard

__all__ = ["finite", "is_number", "is_whole", "loads", "name", "names", "whole"]


def _not_json(constant: str) -> object:
    raise ValueError(f"{constant} is not JSON")


def loads(payload: bytes | str) -> object:
    """``payload`` read as JSON, strictly: ``NaN``, ``Infinity`` and
    ``-Infinity`` (which Python's :func:`json.loads` takes) are a
    ``ValueError``, as is anything else that is not JSON."""
    return json.loads(payload, parse_constant=_not_json)


def finite(value: object) -> object:
    """``value`` with every float that is not finite written as a string
    (``"NaN"``, ``"Infinity"``, ``"-Infinity"``, as JavaScript prints them),
    so that :func:`json.dumps` writes JSON; lists, tuples and dicts are copied
    only where they hold one."""
    if isinstance(value, float):
        if math.isfinite(value):
            return value
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    if isinstance(value, dict):
        return {k: finite(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [finite(v) for v in value]
    return value


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
