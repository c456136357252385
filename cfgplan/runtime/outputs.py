"""What a call writes (5.2.1): the implementation's result split into its
outputs, and the JSON of each output that goes to another robot, checked
against the value rule and the size rule (:mod:`cfgplan.runtime.values`)
before anything is written, so that a call either writes all its outputs or
fails as a whole."""

from __future__ import annotations

from collections.abc import Sequence

from cfgplan.notation import call_text
from cfgplan.runtime.channel import Channel
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.events import Data
from cfgplan.runtime.values import ValueRuleError, encode, safe_repr, size_problem, type_name

__all__ = ["encoded_for", "split"]


def split(result: object, n: int) -> list[object]:
    """The outputs in :out order (one value when there is one output)."""
    if n == 0:
        return []
    if n == 1:
        return [result]
    if result is None:
        return [None] * n
    if not isinstance(result, tuple | list) or len(result) != n:
        raise RunError(
            f"the implementation must return {n} outputs "
            f"(a tuple in :out order), not {safe_repr(result, 80)[0]}"
        )
    return list(result)


def encoded_for(value: object, channels: Sequence[Channel], data: Data, limit: int) -> str | None:
    """The JSON of output ``data`` when it goes to another robot (``None`` when
    it does not); :class:`RunError` when it cannot travel, or when it is over
    ``limit`` bytes (0: any)."""
    if value is None or not any(c.remote for c in channels):
        return None
    try:
        text = encode(value)
    except ValueRuleError as exc:
        raise RunError(
            f"output {call_text(data)} goes to "
            f"another robot, but {exc.message} (type {type_name(value)})",
            hint=exc.hint,
        ) from None
    problem = size_problem(len(text.encode()), limit)
    if problem is not None:
        raise RunError(
            f"output {call_text(data)} goes to another robot, but {problem}; not sent",
            hint="send less (a summary, a smaller image), or raise --max-value-bytes",
        )
    return text
