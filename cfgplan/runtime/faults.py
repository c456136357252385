"""Faults a running configuration can meet, and how implementations say so (5.5).

* :class:`ResourceFailure` — raised by an implementation when its resource has
  failed: a compass disturbed by a magnetic field (6.2.2 step 3), a laser that
  stopped (6.3.2). The call is reported like any failing call, and the monitor
  takes it as the failure of that functionality instance: the configuration is
  no longer admissible. Any *other* exception is a fault of that call only
  (a bug, a glitch): nothing is written, what depends on it waits or goes
  stale — and if it stays silent, staleness points at it.
* :data:`ACHIEVED` — returned by an action when its task is accomplished
  (6.2.2: "she signals that the task is accomplished"): the configuration's
  postconditions become true and it is played out.
* :func:`parse_injection` — scripted faults for tests and demos
  (``cfgplan run --inject``); :mod:`cfgplan.runtime.inject` applies them;
  :func:`misaimed` says when one aims at no robot or functionality of the
  society (a typo would make a fault test a silent no-op).

Injection syntax (one fault per ``--inject``)::

    fail NAME(ARGS) at cycle N      # that instance fails from the robot's cycle N on
    fail NAME(ARGS) at 2.5s         # ... from 2.5 s after the robot started
    recover NAME(ARGS) at ...       # it works again
    kill ROBOT at ...               # the robot is gone (its process ends)
    recover ROBOT at ...            # in one process: the robot is back
    retract FACT at ...             # the operator removes a fact, e.g. (compass Emil)
    assert FACT at ...              # the operator adds one

An instance is written ``compass(Emil)`` or ``(compass Emil)``, its robot
first, as in a configuration; a fact either way too.
"""

from __future__ import annotations

import re
import traceback
from collections.abc import Collection
from dataclasses import dataclass
from typing import Literal

from cfgplan.notation import call_text
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.values import safe_repr

__all__ = [
    "ACHIEVED",
    "Failed",
    "Injection",
    "ResourceFailure",
    "failed",
    "fault",
    "misaimed",
    "parse_injection",
    "term_text",
    "where",
]


class ResourceFailure(Exception):
    """An implementation's resource has failed (raise it from the implementation)."""


def where(exc: BaseException) -> str:
    """`` (impl.py:70 in camera)``: where an exception was raised."""
    frames = traceback.extract_tb(exc.__traceback__)
    if not frames:
        return ""
    last = frames[-1]
    return f" ({last.filename}:{last.lineno} in {last.name})"


def fault(exc: BaseException) -> str:
    """What an implementation's exception says, in one line."""
    if isinstance(exc, SystemExit):
        return f"the implementation called sys.exit({safe_repr(exc.code)[0]})"
    text = safe_repr(exc)[0] if not str(exc) else str(exc)
    return f"the implementation raised {type(exc).__name__}: {text}{where(exc)}"


@dataclass(frozen=True)
class Failed:
    """Why a call failed, and whether its resource did (``failure``)."""

    message: str
    failure: Literal["", "reported", "injected"] = ""

    def __str__(self) -> str:
        return self.message


def failed(exc: BaseException) -> Failed:
    """A failing call: a :class:`ResourceFailure` is the resource's failure."""
    return Failed(fault(exc), "reported" if isinstance(exc, ResourceFailure) else "")


class _Achieved:
    """The type of :data:`ACHIEVED`."""

    def __repr__(self) -> str:
        return "ACHIEVED"


ACHIEVED = _Achieved()
"""What an action returns when its task is accomplished."""

Action = Literal["fail", "recover", "kill", "assert", "retract"]

SYNTAX = (
    "fail NAME(ARGS) at cycle N | at 2.5s; recover NAME(ARGS) at ...; kill ROBOT at ...; "
    "recover ROBOT at ...; retract FACT at ...; assert FACT at ..."
)

_SPEC = re.compile(
    r"^\s*(?P<action>fail|recover|kill|assert|retract)\s+(?P<target>.+?)\s+at\s+"
    r"(?:cycle\s+(?P<cycle>\S+)|(?P<seconds>\S+?)\s*s)\s*$"
)
_CALL = re.compile(r"^(?P<name>[^\s(),;'\"]+)\((?P<args>[^()]*)\)$")
_LIST = re.compile(r"^\((?P<items>[^()]+)\)$")
_NAME = re.compile(r"^[^\s(),;'\":][^\s(),;'\"]*$")


@dataclass(frozen=True)
class Injection:
    """One scripted fault: ``action`` on ``target`` at a cycle or a time."""

    action: Action
    target: tuple[str, ...]
    """An instance ``("compass", "Emil")``, a robot ``("Emil",)`` or a fact."""
    cycle: int | None
    seconds: float | None
    text: str

    @property
    def on_robot(self) -> bool:
        """Whether it targets a robot rather than a functionality instance."""
        return self.action == "kill" or (self.action == "recover" and len(self.target) == 1)

    @property
    def on_facts(self) -> bool:
        return self.action in ("assert", "retract")

    @property
    def robot(self) -> str | None:
        """Where it takes effect: the instance's or the robot's robot (``None``
        for a state update, which the planning side takes)."""
        if self.on_facts:
            return None
        return self.target[0] if self.on_robot else self.target[1]

    def due(self, cycle: int, elapsed: float) -> bool:
        """Whether it is time: the robot is about to run ``cycle``, ``elapsed``
        seconds after it started."""
        if self.cycle is not None:
            return cycle >= self.cycle
        return self.seconds is not None and elapsed >= self.seconds


def term_text(term: tuple[str, ...]) -> str:
    """``compass(Emil)`` for an instance or fact, ``Emil`` for a robot."""
    if len(term) == 1:
        return term[0]
    return call_text(term)


def _term(text: str) -> tuple[str, ...] | None:
    text = text.strip()
    call = _CALL.match(text)
    if call:
        args = (
            [a.strip() for a in call.group("args").split(",")] if call.group("args").strip() else []
        )
        items = (call.group("name"), *args)
    else:
        listed = _LIST.match(text)
        if listed:
            items = tuple(listed.group("items").split())
        elif _NAME.match(text):
            items = (text,)
        else:
            return None
    return items if all(_NAME.match(i) for i in items) else None


def parse_injection(text: str) -> Injection:
    """Read one ``--inject`` value; :class:`RunError` saying what is expected."""
    found = _SPEC.match(text)
    if found is None:
        raise RunError(f"--inject {text!r}: not a fault I can inject", hint=f"write {SYNTAX}")
    action: Action = found.group("action")  # type: ignore[assignment]
    target = _term(found.group("target"))
    if target is None:
        raise RunError(
            f"--inject {text!r}: {found.group('target')!r} is neither NAME(ARGS), (NAME ARGS) "
            "nor a robot's name",
            hint=f"write {SYNTAX}",
        )
    single = len(target) == 1
    if action == "fail" and single:
        raise RunError(
            f"--inject {text!r}: fail takes a functionality instance such as compass(Emil)",
            hint="to take a whole robot away, write kill ROBOT at ...",
        )
    if action == "kill" and not single:
        raise RunError(f"--inject {text!r}: kill takes a robot's name, e.g. kill Emil at cycle 20")
    if action in ("assert", "retract") and single:
        raise RunError(f"--inject {text!r}: {action} takes a fact such as (compass Emil)")
    cycle, seconds = _when(text, found.group("cycle"), found.group("seconds"))
    return Injection(action, target, cycle, seconds, " ".join(text.split()))


def _when(text: str, cycle: str | None, seconds: str | None) -> tuple[int | None, float | None]:
    if cycle is not None:
        if not cycle.isdigit() or int(cycle) < 1:
            raise RunError(
                f"--inject {text!r}: the cycle must be a whole number from 1, not {cycle!r}"
            )
        return int(cycle), None
    assert seconds is not None
    try:
        value = float(seconds)
    except ValueError:
        value = float("nan")
    if not (value >= 0 and value != float("inf")):
        raise RunError(
            f"--inject {text!r}: the time must be seconds such as 2.5s, not {seconds!r}s"
        )
    return None, value


def misaimed(
    injection: Injection,
    agents: Collection[str],
    functionalities: Collection[tuple[str, int]] | None = None,
) -> RunError | None:
    """Why ``injection`` aims at nothing of the society, or ``None`` when it
    aims well: its robot (a ``kill``'s or ``recover``'s, an instance's first
    argument) must be one of ``agents``, the society's robots and devices; an
    instance, when ``functionalities`` (their signatures, name and number of
    arguments, as a task keys them) are known, one of them. A state update
    (``assert``, ``retract``) may name any fact."""
    if injection.on_facts:
        return None
    text = f"--inject {injection.text!r}"
    robot = injection.robot or ""
    if robot not in agents:
        return RunError(
            f"{text}: no robot {robot} in this society",
            hint=_near(robot, agents, "its robots"),
        )
    if injection.on_robot or functionalities is None:
        return None
    name, *args = injection.target
    if (name, len(args)) in functionalities:
        return None
    arities = [n for known, n in functionalities if known == name]
    if not arities:
        names = list(dict.fromkeys(known for known, _ in functionalities))
        return RunError(
            f"{text}: no functionality {name} in the domain",
            hint=_near(name, names, "its functionalities"),
        )
    return RunError(
        f"{text}: {name} takes {' or '.join(map(str, arities))} argument(s), not {len(args)}",
        hint="its robot first, as in a configuration: compass(Emil)",
    )


def _near(name: str, known: Collection[str], what: str) -> str:
    """``did you mean Emil?``, else the names known (a robot loads this only
    for an injection that aims at nothing)."""
    from cfgplan.diagnostics import did_you_mean

    return did_you_mean(name, known) or f"{what}: {', '.join(known)}"
