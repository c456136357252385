"""The options of a run, defined once for ``cfgplan run`` and the emitted programs.

A robot's emitted module (``python emil.py``), ``run_all.py`` and ``cfgplan
run`` take the same options with the same meaning, defaults and wording
(5.2, 5.3): each :class:`Option` here gives an option's flag, metavariable,
default, help and parser. The emitted programs build their ``argparse``
parser from them (:mod:`cfgplan.runtime.main`), ``cfgplan run`` its typer
options (:mod:`cfgplan.cli.run`). A parser raises ``ValueError`` with the
message a user reads (``'two' is not a whole number``).

Light, like the rest of :mod:`cfgplan.runtime`: no typer, no pydantic.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from cfgplan.option_values import choice, number, whole
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.executor import DEFAULT_BUDGET
from cfgplan.runtime.faults import SYNTAX, parse_injection
from cfgplan.runtime.tracefile import MAX_BYTES as TRACE_LIMIT
from cfgplan.runtime.values import MAX_VALUE_BYTES as VALUE_LIMIT
from cfgplan.runtime.zenoh_config import DEFAULT_LEASE, DEFAULT_SOCIETY, endpoint_problem
from cfgplan.security.rates import RateLimits

__all__ = [
    "BUDGET",
    "CONNECT",
    "CYCLES",
    "DURATION",
    "FORCE",
    "IMPL",
    "INJECT",
    "KEYS",
    "LAUNCHED",
    "LEASE",
    "LISTEN",
    "MAX_VALUE_BYTES",
    "NETWORK_OPTIONS",
    "RATE",
    "RATE_ALLOWANCE",
    "RECORD",
    "RECORD_MAX_BYTES",
    "RESPAWN",
    "ROUTER",
    "RUN_OPTIONS",
    "SOCIETY",
    "STALE_PERIODS",
    "TRACE",
    "TRACE_MAX_BYTES",
    "UNTIL",
    "VERBOSE",
    "WITHOUT_COORDINATOR",
    "ZENOH_CONFIG",
    "Option",
    "choice",
    "endpoint",
    "how_long",
    "injection",
    "launched",
    "number",
    "whole",
]

T = TypeVar("T")

UNTIL = (
    "Runs until interrupted (Ctrl-C or SIGTERM), or for --cycles or --duration, "
    "or until the action's task is accomplished."
)
"""How long a run lasts: the same for ``cfgplan run`` and the emitted programs."""


def endpoint(text: str) -> str:
    """A Zenoh endpoint such as ``tcp/127.0.0.1:7447`` (its form only)."""
    problem = endpoint_problem(text)
    if problem:
        raise ValueError(problem)
    return text


def injection(text: str) -> str:
    """A scripted fault (:func:`cfgplan.runtime.faults.parse_injection`), kept as written."""
    try:
        parse_injection(text)
    except RunError as exc:
        raise ValueError(exc.message + (f" ({exc.hint})" if exc.hint else "")) from None
    return text


@dataclass(frozen=True)
class Option(Generic[T]):
    """One option: ``metavar`` ``None`` for a flag; ``repeat`` for one given
    several times (its default is then empty)."""

    flag: str
    metavar: str | None
    default: T
    help: str
    parse: Callable[[str], object] | None = None
    repeat: bool = False

    @property
    def dest(self) -> str:
        """The Python name of its value: ``--stale-periods`` -> ``stale_periods``."""
        return self.flag.lstrip("-").replace("-", "_")


IMPL: Option[str | None] = Option(
    "--impl",
    "IMPL",
    None,
    "The implementations: a module name (pkg.impl) or a .py file declaring them "
    "with @functionality (cfgplan.runtime).",
)
RATE = Option(
    "--rate",
    "HZ",
    10.0,
    "Cycles per second of functionalities without :freq (default 10; 0: every "
    "functionality in every cycle, no pause).",
    number(0),
)
CYCLES = Option(
    "--cycles",
    "N",
    0,
    "Stop after N cycles (cfgplan run: of the goal's robot, whatever switches happen; "
    "default 0: no limit).",
    whole(0),
)
DURATION: Option[float | None] = Option(
    "--duration", "S", None, "Stop after S seconds (default: no limit).", number(0, above=True)
)
STALE_PERIODS = Option(
    "--stale-periods",
    "K",
    3.0,
    "An input not refreshed for K periods of its sender is stale (default 3).",
    number(0, above=True),
)
BUDGET = Option(
    "--budget",
    "S",
    DEFAULT_BUDGET,
    f"Seconds one call, or a stop hook, may take before it is reported as blocked (default "
    f"{DEFAULT_BUDGET:g}; 0: no budget, calls run on the robot's thread).",
    number(0),
)
MAX_VALUE_BYTES = Option(
    "--max-value-bytes",
    "N",
    VALUE_LIMIT,
    f"Bytes of JSON one value on a global channel may have (default {VALUE_LIMIT}: 1 MiB; "
    "0: no limit): a bigger output is the call's error, a bigger message received is "
    "dropped unread.",
    whole(0),
)
TRACE: Option[str | None] = Option(
    "--trace", "FILE", None, "Write every event to FILE as JSON lines."
)
TRACE_MAX_BYTES = Option(
    "--trace-max-bytes",
    "N",
    TRACE_LIMIT,
    f"Cap of the --trace FILE in bytes (default {TRACE_LIMIT}: 64 MiB; 0: no cap): past it, "
    "FILE becomes FILE.1 (replacing an older one) and a new FILE begins, so the newest events "
    "are kept, in at most twice the cap.",
    whole(0),
)
RECORD: Option[str | None] = Option(
    "--record",
    "FILE",
    None,
    "Write every event to FILE as an MCAP recording that Foxglove opens, as the run goes "
    "(replaced only with --force; pip install 'cfgplan[record]'; docs: Record a run for "
    "Foxglove).",
)
RECORD_MAX_BYTES = Option(
    "--record-max-bytes",
    "N",
    TRACE_LIMIT,
    f"Cap of the --record FILE in bytes (default {TRACE_LIMIT}: 64 MiB; 0: no cap): past it, "
    "FILE is finished and becomes FILE.1 (replacing an older one) and a new FILE begins.",
    whole(0),
)
"""Only ``cfgplan run`` and ``cfgplan simulate`` record: not in :data:`RUN_OPTIONS`."""
FORCE = Option(
    "--force",
    None,
    False,
    "Overwrite the --trace FILE if it exists (cfgplan run: the --record FILE too).",
)
VERBOSE = Option(
    "--verbose",
    None,
    False,
    "Print every call of every functionality, each cycle (default: a compact status, what "
    "an action receives when it starts to, and every loss, stale input, failure and switch).",
)
INJECT: Option[list[str]] = Option(
    "--inject",
    "FAULT",
    [],
    f"A scripted fault (repeatable): {SYNTAX}; e.g. 'fail compass(Emil) at cycle 20'. "
    "A robot's own program applies those aimed at it.",
    injection,
    repeat=True,
)

SOCIETY = Option(
    "--society",
    "NAME",
    DEFAULT_SOCIETY,
    f"Keeps societies on one network apart (default {DEFAULT_SOCIETY}).",
)
LISTEN: Option[list[str]] = Option(
    "--listen",
    "ENDPOINT",
    [],
    "Listen on ENDPOINT, e.g. tcp/0.0.0.0:7447 (repeatable).",
    endpoint,
    repeat=True,
)
CONNECT: Option[list[str]] = Option(
    "--connect",
    "ENDPOINT",
    [],
    "Connect to ENDPOINT, e.g. tcp/192.168.1.7:7447 (repeatable); with --listen or "
    "--connect, multicast scouting is off.",
    endpoint,
    repeat=True,
)
ROUTER: Option[list[str]] = Option(
    "--router",
    "ENDPOINT",
    [],
    "Be a client of the Zenoh router at ENDPOINT (cfgplan router, zenohd or rmw_zenohd; "
    "repeatable: one of them), e.g. tcp/192.168.1.2:7447: the robot connects only there and "
    "listens nowhere, so the society's connections grow with its robots, not their square. "
    "Not with --listen or --connect; with --keys, the society's router (cfgplan router "
    "--keys), over TLS.",
    endpoint,
    repeat=True,
)
ZENOH_CONFIG: Option[str | None] = Option(
    "--zenoh-config",
    "FILE",
    None,
    "A Zenoh configuration file (JSON5) for anything else; cfgplan's lease and retry stay "
    "unless it sets them, and the options above go on top.",
)
LEASE: Option[float | None] = Option(
    "--lease",
    "S",
    None,
    f"Seconds after which a frozen robot is reported lost (default {DEFAULT_LEASE:g}).",
    number(0, above=True),
)

KEYS: Option[str | None] = Option(
    "--keys",
    "DIR",
    None,
    "The society's keys (made by cfgplan keys new): TLS with mutual authentication, and "
    "Zenoh access control by certificate name; tcp/ endpoints become tls/, and --society "
    "is the keys' unless given.",
)

RATE_ALLOWANCE = Option(
    "--rate-allowance",
    "K",
    RateLimits.allowance,
    f"Messages a robot takes per period of a channel's sender (default {RateLimits.allowance:g}; "
    f"at most {RateLimits.ceiling:g} a second): more are dropped, counted and recorded once a "
    "second, so that a robot flooding a channel cannot starve the receiver.",
    number(0, above=True),
)

WITHOUT_COORDINATOR = Option(
    "--without-coordinator",
    "stop|run",
    "stop",
    "What a robot that follows a coordinator does once the coordinator is gone (its process "
    "ended, or froze past the lease) for longer than the hold: stop (default: its part stops, "
    "every stop hook called, so an action halts its motors, until a coordinator sends it a "
    "part again) or run (on, with the inputs it still gets).",
    choice(("stop", "run"), "what a robot does without its coordinator"),
)

RESPAWN = Option(
    "--respawn",
    None,
    False,
    "Start a robot's process again when it dies (killed, crashed): after 1 s, twice as long "
    "with each death in a row (at most 30 s), a process that ran 10 s counting as the first "
    "death again. Its trace and recording go to files of their own (run-pippi-2.jsonl), its "
    "--inject faults are not run again.",
)

RUN_OPTIONS: tuple[Option[Any], ...] = (
    IMPL,
    RATE,
    CYCLES,
    DURATION,
    STALE_PERIODS,
    BUDGET,
    MAX_VALUE_BYTES,
    TRACE,
    TRACE_MAX_BYTES,
    FORCE,
    VERBOSE,
    INJECT,
)
"""Every run's options: ``cfgplan run``, a robot's module, ``run_all.py``."""

NETWORK_OPTIONS: tuple[Option[Any], ...] = (
    SOCIETY,
    LISTEN,
    CONNECT,
    ROUTER,
    ZENOH_CONFIG,
    LEASE,
    KEYS,
    RATE_ALLOWANCE,
    WITHOUT_COORDINATOR,
)
"""A robot on the network: ``cfgplan run --robot`` and a robot's module."""


LAUNCHED = "CFGPLAN_LAUNCHED"
"""The environment variable ``cfgplan launch`` sets for the robots it starts
(:mod:`cfgplan.runtime.spawn`): they run in a session of their own, so Ctrl-C
reaches the launch, not them, and the launch stops them."""


def launched() -> bool:
    """Whether this process is a robot ``cfgplan launch`` started."""
    return os.environ.get(LAUNCHED) == "1"


def how_long(cycles: int, duration: float | None, *, by_launch: bool | None = None) -> str:
    """``3 cycle(s)``, ``2.5 s``, or ``until interrupted (Ctrl-C)``: what a run
    says when it starts. A robot ``cfgplan launch`` started (``by_launch``; by
    default :func:`launched`) does not take Ctrl-C: it runs until the launch
    stops it."""
    limits = []
    if cycles:
        limits.append(f"{cycles} cycle(s)")
    if duration is not None:
        limits.append(f"{duration:g} s")
    if limits:
        return " or ".join(limits)
    if launched() if by_launch is None else by_launch:
        return "until the launch stops it"
    return "until interrupted (Ctrl-C)"
