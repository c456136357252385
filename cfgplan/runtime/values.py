"""Which values may travel on a global channel, and how (5.2.2: data copied to the other robot).

The value rule: a value written on a global channel must be JSON —
``None``, ``bool``, ``int``, ``float``, ``str``, a ``list`` or ``tuple`` of
values, or a ``dict`` with ``str`` keys and values — at most
:data:`MAX_DEPTH` levels deep and without referring to itself. Subclasses
count as their base type (``numpy.float64`` is a ``float``). It arrives as
JSON reads back: a tuple as a list, a subclass as its base type. ``NaN`` and
``±Infinity`` are allowed and written as Python's :mod:`json` writes them.
The rule holds for every transport, in-process too, so that what runs in one
process runs the same across processes.

A message on the wire is one JSON object, the *envelope*::

    {"from": "Emil", "seq": 17, "t": 1712345678.25, "period": 0.1, "value": ...}

``seq`` counts the channel's writes (gaps are messages the one slot or the
network lost), ``t`` is the sender's clock (seconds since the epoch) and
``period`` the sender's period in seconds (``null``: none), from which the
receiver judges staleness (3.2).

The size rule: a value's JSON may be at most ``max_value_bytes`` bytes
(:data:`MAX_VALUE_BYTES`, 1 MiB, unless ``--max-value-bytes`` says otherwise;
0: no limit). A bigger output is the call's error (:func:`size_problem`); a
bigger message from the network (its envelope over the limit and
:data:`ENVELOPE_ROOM`) is dropped unread (:func:`oversized`).
"""

from __future__ import annotations

import hashlib
import json
import math
from typing import NamedTuple

from cfgplan.runtime.errors import RunError, printable
from cfgplan.runtime.wire import is_number, is_whole, loads

__all__ = [
    "ENVELOPE_ROOM",
    "MAX_DEPTH",
    "MAX_VALUE_BYTES",
    "Envelope",
    "ValueRuleError",
    "check",
    "elide",
    "encode",
    "envelope",
    "jsonable",
    "open_envelope",
    "oversized",
    "safe_repr",
    "size_problem",
]

MAX_DEPTH = 64
MAX_VALUE_BYTES = 1 << 20
"""The default limit on one value's JSON, in bytes (``--max-value-bytes``): 1 MiB."""
ENVELOPE_ROOM = 4096
"""Bytes a received message may have beyond the value limit: the envelope's other fields."""
RULE = "JSON: None, bool, int, float, str, list, tuple, dict with str keys"
_SCALARS = frozenset({type(None), bool, int, float, str})


class ValueRuleError(RunError):
    """A value that cannot travel on a global channel."""

    def __init__(self, message: str, type_name: str) -> None:
        super().__init__(message, hint=f"a global channel carries {RULE}")
        self.type_name = type_name


def type_name(value: object) -> str:
    kind = type(value)
    module = kind.__module__
    return kind.__qualname__ if module == "builtins" else f"{module}.{kind.__qualname__}"


def check(value: object) -> None:
    """Raise :class:`ValueRuleError` (naming the type and where it sits) unless
    ``value`` follows the value rule. Iterative: deep values cannot overflow."""
    stack: list[tuple[object, str, int]] = [(value, "", 0)]
    open_ids: set[int] = set()
    while stack:
        item, path, depth = stack.pop()
        if depth < 0:  # leaving a container
            open_ids.discard(-depth - 1)
            continue
        if item is None or isinstance(item, bool | int | float | str):
            continue
        where = f" at value{path}" if path else ""
        if not isinstance(item, list | tuple | dict):
            hint = _conversion(item)
            raise ValueRuleError(
                f"a value of type {type_name(item)}{where} cannot travel as JSON{hint}",
                type_name(item),
            )
        if id(item) in open_ids:
            raise ValueRuleError(f"the value refers to itself{where}", type_name(item))
        if depth >= MAX_DEPTH:
            raise ValueRuleError(
                f"the value is nested deeper than {MAX_DEPTH} levels{where}", type_name(item)
            )
        open_ids.add(id(item))
        stack.append((None, "", -id(item) - 1))
        if isinstance(item, dict):
            for key, sub in item.items():
                if not isinstance(key, str):
                    raise ValueRuleError(
                        f"a dict key of type {type_name(key)}{where} cannot travel as JSON "
                        "(keys must be str)",
                        type_name(key),
                    )
                if type(sub) not in _SCALARS:
                    stack.append((sub, f"{path}[{key!r}]", depth + 1))
        else:
            for k, sub in enumerate(item):
                if type(sub) not in _SCALARS:  # the common case costs one look-up
                    stack.append((sub, f"{path}[{k}]", depth + 1))


def _conversion(item: object) -> str:
    for method in ("tolist", "item"):
        if callable(getattr(item, method, None)):
            return f" (convert it with .{method}())"
    return ""


def encode(value: object) -> str:
    """The JSON text of ``value``; :class:`ValueRuleError` when it cannot travel."""
    check(value)
    try:
        return json.dumps(value, separators=(",", ":"), allow_nan=False)
    except ValueError:  # NaN or an infinity somewhere: JSON has neither
        raise ValueRuleError(
            "a float that is not finite (NaN or an infinity) cannot travel as JSON", "float"
        ) from None


def size_problem(size: int, limit: int) -> str | None:
    """What is wrong with a value whose JSON is ``size`` bytes under a limit of
    ``limit`` bytes (0: none); ``None`` when nothing is."""
    if not limit or size <= limit:
        return None
    return f"its JSON is {size:,} bytes, over the limit of {limit:,} bytes (--max-value-bytes)"


def oversized(payload: bytes, limit: int) -> bool:
    """A received message too big to read under a value limit of ``limit`` (0: none)."""
    return bool(limit) and len(payload) > limit + ENVELOPE_ROOM


def envelope(sender: str, seq: int, t: float, period: float | None, encoded: str) -> bytes:
    """The message of one write on a global channel (``encoded``: the value's JSON)."""
    head = json.dumps({"from": sender, "seq": seq, "t": t, "period": period})
    return (head[:-1] + ', "value": ' + encoded + "}").encode()


MAX_PERIOD = 60.0
"""The longest period (seconds) a message may claim for its sender: a
staleness limit is a few periods, and a forged ``1e9`` would switch
detection off. A functionality slower than once a minute is not
what a configuration's channels are for."""


class Envelope(NamedTuple):
    sender: str
    seq: int
    t: float
    period: float | None
    value: object


def open_envelope(payload: bytes) -> Envelope:
    """Read a message; :class:`RunError` when it is not a cfgplan envelope."""
    try:
        data = loads(payload)
    except (ValueError, RecursionError) as exc:
        raise RunError(f"a message that is not JSON ({exc})") from None
    if not isinstance(data, dict) or "value" not in data:
        raise RunError("a message that is not a cfgplan envelope (no value)")
    sender, seq, t, period = (data.get(k) for k in ("from", "seq", "t", "period"))
    if not isinstance(sender, str) or not is_whole(seq):
        raise RunError("a message whose envelope lacks its sender or sequence number")
    if not is_number(t) or not math.isfinite(t):
        raise RunError("a message whose envelope lacks its time")
    if period is not None and (not is_number(period) or not 0 < period <= MAX_PERIOD):
        raise RunError(
            f"a message whose period is not a number of seconds from 0 to {MAX_PERIOD:g}: "
            f"{period!r}"
        )
    return Envelope(sender, seq, float(t), None if period is None else float(period), data["value"])


def safe_repr(value: object, limit: int = 200) -> tuple[str, str | None]:
    """``repr(value)`` cut to ``limit`` characters with control characters
    escaped, and ``None``; or a placeholder and what went wrong when its
    ``__repr__`` raises (or recurses without end)."""
    try:
        text = repr(value)
    except Exception as exc:  # an implementation's __repr__: anything may happen
        problem = f"its __repr__ raised {type(exc).__name__}: {_message(exc)}"
        return f"<{type(value).__name__} object; {problem}>", problem
    text = printable(text)
    return (text if len(text) <= limit else text[: limit - 1] + "…"), None


def _message(exc: BaseException) -> str:
    try:
        text = str(exc)
    except Exception:
        return "(unprintable)"
    return printable(text[:120])


def elide(value: object, limit: int) -> object:
    """``value`` as a trace records it when its JSON may be ``limit``
    characters at most (0: any): the value itself, or in place of a longer one
    ``{"$elided": type, "$bytes": size, "$sha256": digest}``, the size and the
    first 16 hex digits of the SHA-256 of its compact JSON (what a global
    channel sends: a value sent and received has one digest). The one rule of
    the run's ``--trace`` and the simulator's ``trace.jsonl``."""
    if not limit or value is None or isinstance(value, bool | int | float):
        return value
    # a character escapes to at most 12 of JSON (a pair of \\uXXXX beyond the basic plane)
    if isinstance(value, str) and len(value) <= limit // 12 - 2:  # escaped, still short
        return value
    try:
        text = json.dumps(value, separators=(",", ":"))
    except (TypeError, ValueError, RecursionError):  # not JSON: as the trace writes it
        text = json.dumps(jsonable(value), separators=(",", ":"))
    if len(text) <= limit:
        return value
    data = text.encode()
    return {
        "$elided": type(value).__name__,
        "$bytes": len(data),
        "$sha256": hashlib.sha256(data).hexdigest()[:16],
    }


def jsonable(value: object) -> object:
    """``value`` as a trace writes it: JSON as it is (tuples as lists), and in
    place of anything else — or of what nests deeper than :data:`MAX_DEPTH`
    or contains itself — ``{"$type": ..., "$repr": ...}``."""
    return _jsonable(value, set(), 0)


def _jsonable(value: object, open_ids: set[int], depth: int) -> object:
    if value is None or isinstance(value, bool | int | float | str):
        return value
    if isinstance(value, list | tuple | dict) and depth < MAX_DEPTH and id(value) not in open_ids:
        open_ids.add(id(value))
        try:
            if isinstance(value, dict):
                if all(isinstance(k, str) for k in value):
                    return {k: _jsonable(v, open_ids, depth + 1) for k, v in value.items()}
            else:
                return [_jsonable(v, open_ids, depth + 1) for v in value]
        finally:
            open_ids.discard(id(value))
    if isinstance(value, list | tuple | dict):
        text = "..." if id(value) in open_ids or depth >= MAX_DEPTH else safe_repr(value)[0]
    else:
        text = safe_repr(value)[0]
    return {"$type": type_name(value), "$repr": text}
