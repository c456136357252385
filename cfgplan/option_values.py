"""Parsers of option values, shared by the command line (:mod:`cfgplan.cli.options`)
and the emitted programs (:mod:`cfgplan.runtime.options`).

A parser raises ``ValueError`` with the message a user reads (``'two' is not a
whole number``). Kept apart from both so that either imports it alone: the
command line does not load the runtime to parse ``-k``, and a robot does not
load the planner.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence


def whole(low: int) -> Callable[[str], int]:
    """A parser of whole numbers of at least ``low``."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise ValueError(f"{text!r} is not a whole number") from None
        if value < low:
            raise ValueError(f"{text}: must be {low} or more")
        return value

    return parse


def kept(text: str, value: float) -> bool:
    """Whether ``value``, ``float(text)``, is the number ``text`` writes: a float
    keeps 15 to 17 significant digits, and a number written with more that it
    cannot hold would be silently rounded (``99999999999999999999`` is
    ``1e+20``). ``0.1`` is kept: it reads back as ``0.1``."""
    from decimal import Decimal  # loaded by pydantic on the planner's side; light anyway

    return Decimal(text) == Decimal(repr(value))


def rounding(text: str, value: float) -> str:
    """The message for a number that :func:`kept` says would be rounded."""
    return f"{text} has more digits than a number keeps: it would be read as {value!r}"


def number(low: float, *, above: bool = False) -> Callable[[str], float]:
    """A parser of finite numbers of at least ``low`` (``above``: more than
    ``low``), kept as written (:func:`kept`)."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise ValueError(f"{text!r} is not a number") from None
        if not math.isfinite(value):
            raise ValueError(f"{text}: must be a finite number")
        if isinstance(text, str) and not kept(text.strip(), value):  # (typer: a default)
            raise ValueError(rounding(text, value))
        if value < low or (above and value == low):
            raise ValueError(f"{text}: must be {'more than' if above else 'at least'} {low:g}")
        return value

    return parse


def choice(values: Sequence[str], what: str) -> Callable[[str], str]:
    """A parser of one of ``values``: ``'yaml' is not a format: choose table, lisp or json``."""

    def parse(text: str) -> str:
        if text in values:
            return text
        shown = ", ".join(values[:-1]) + " or " + values[-1] if len(values) > 1 else values[0]
        raise ValueError(f"{text!r} is not {what}: choose {shown}")

    return parse
