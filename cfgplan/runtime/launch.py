"""Running a society until it is done or told to stop: options, console, trace, signals.

Shared by ``cfgplan run`` and the programs ``cfgplan emit --lang python``
writes, so both behave the same. :func:`execute` runs the loop of
:meth:`~cfgplan.runtime.executor.Society.run` and:

* prints, as they happen, what each action received (with ``verbose``, every
  call), robots seen and lost, inputs going stale and fresh; on stderr, each
  functionality's failures (the first few of each, then only counted) and
  values whose ``__repr__`` fails, blaming the implementation;
* writes every event to the ``--trace`` file, if any;
* stops cleanly on Ctrl-C or SIGTERM (a second Ctrl-C interrupts at once),
  records the stop, closes the transport and prints the summary.

With :class:`Hooks` (monitoring and reconfiguration, 5.5) the society is
watched and reconfigured as it runs: a resource failure that is handled by a
switch is no longer a failing run.

Exit status: 0 when the run ended as asked; 1 when a functionality failed
(raised, exited, returned what could not be written, overran its budget) or
the trace or the console could not be written (the run goes on without them);
3 when, reconfiguring, the run ended with no admissible configuration left.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from types import FrameType
from typing import Protocol, TextIO

from cfgplan.notation import call_text
from cfgplan.runtime.events import Call, Event, Lifecycle
from cfgplan.runtime.executor import DEFAULT_BUDGET
from cfgplan.runtime.society import Society
from cfgplan.runtime.trace import describe, notice, summary
from cfgplan.runtime.tracefile import TraceFile, open_trace

__all__ = [
    "EXIT_NONE",
    "FAULTS_SHOWN",
    "WAIT_NOTICE",
    "Hooks",
    "Printer",
    "RunOptions",
    "execute",
]

FAULTS_SHOWN = 3
WAIT_NOTICE = 10
"""Calls in a row a functionality waits for data before the console says so
(1 s at the default rate): a robot whose partner has not started does not
look hung."""
"""Failures printed per functionality; later ones are only counted."""

EXIT_NONE = 3
"""Exit status of a run that ends with no admissible configuration (as ``cfgplan plan``)."""


class Hooks(Protocol):
    """What a self-reconfiguring run adds to the loop (:mod:`cfgplan.reconfigure.local`)."""

    def before(self, cycle: int, elapsed: float) -> None:
        """Before each cycle (scripted faults)."""

    def between(self, cycle: int, elapsed: float) -> None:
        """After each pass of the loop (detections, switches)."""

    @property
    def finished(self) -> str | None:
        """Why the run should end now (``achieved``), or ``None``."""

    @property
    def stopped(self) -> bool:
        """Nothing admissible is running."""

    @property
    def reconfigures(self) -> bool:
        """Resource failures are handled (by switching), not failures of the run."""

    def close(self) -> None:
        """The run is over: stop what ran beside it (the fallbacks' thread)."""


@dataclass(frozen=True)
class RunOptions:
    """How long and how fast to run, and what to record."""

    rate: float = 10.0
    cycles: int = 0  # 0: no limit
    duration: float | None = None  # seconds; None: no limit
    stale_periods: float = 3.0
    budget: float | None = DEFAULT_BUDGET  # None: no time budget
    trace: str | None = None
    force: bool = False
    verbose: bool = False


class Printer:
    """The console side of a run: a listener of every robot."""

    def __init__(
        self, verbose: bool, source: str, out: TextIO, err: TextIO, handled: bool = False
    ) -> None:
        self.verbose = verbose
        self.handled = handled  # resource failures are handled by reconfiguration
        self.source = source
        self.out = out
        self.err = err
        self.failed = False
        self.lost: str | None = None  # why the console could not be written to
        self._faults: dict[str, int] = {}
        self._warned: set[tuple[str, str]] = set()
        self._dead: set[int] = set()
        self._waits: dict[tuple[str, str], int] = {}  # calls in a row each one waited

    def say(self, text: str, stream: TextIO | None = None) -> None:
        """A line on ``stream`` (default: ``out``); a stream that cannot be
        written to (closed pipe, full disk) is given up, not fatal."""
        stream = self.out if stream is None else stream
        if id(stream) in self._dead:
            return
        try:
            print(text, file=stream, flush=True)
        except (OSError, ValueError) as exc:
            self._dead.add(id(stream))
            what = "standard output" if stream is self.out else "standard error"
            reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
            self.lost = self.lost or f"cannot write to {what}: {reason}"
            _silence(stream)

    def __call__(self, event: Event) -> None:
        if isinstance(event, Call):
            self._call(event)
            return
        if isinstance(event, Lifecycle) and event.what == "error":
            self.say(f"cfgplan: {notice(event)}", self.err)
            return
        line = notice(event)
        if line is not None:
            self.say(line)

    def _call(self, event: Call) -> None:
        if not self.verbose:
            self._waiting(event)
        if event.status in ("error", "timeout"):
            self.failed = self.failed or not (self.handled and event.failure)
            self._fault(event)
            return
        if not (self.verbose or (event.action and event.status == "ran")):
            return
        problems: list[str] = []
        self.say(describe(event, problems))
        for problem in problems:
            if (event.label, problem) not in self._warned:
                self._warned.add((event.label, problem))
                self.say(
                    f"cfgplan: warning: {event.label} {event.name} on {event.robot}: {problem} "
                    f"(implementations: {self.source})",
                    self.err,
                )

    def _waiting(self, event: Call) -> None:
        """Say when a functionality has waited :data:`WAIT_NOTICE` calls in a
        row for data, and for what; and when it runs again."""
        key = (event.robot, event.label)
        if event.status == "waiting":
            waited = self._waits.get(key, 0) + 1
            self._waits[key] = waited
            if waited == WAIT_NOTICE:
                self.say(f"{describe(event)} ({waited} calls in a row so far)")
            return
        waited = self._waits.pop(key, 0)
        if waited >= WAIT_NOTICE and event.status == "ran":
            shown = call_text((event.name, *event.args))
            self.say(f"cycle {event.cycle}: {event.robot} {event.label} {shown} runs again")

    def _fault(self, event: Call) -> None:
        key = f"{event.robot} {event.label}"
        seen = self._faults.get(key, 0) + 1
        self._faults[key] = seen
        if seen <= FAULTS_SHOWN:
            self.say(f"cfgplan: {describe(event)} [{self.source}]", self.err)
        if seen == FAULTS_SHOWN:
            self.say(
                f"cfgplan: further failures of {event.label} {event.name} on {event.robot} "
                "are only counted (summary; --trace has each)",
                self.err,
            )


def _silence(stream: TextIO) -> None:
    """Point a standard stream that failed at the null device, so that the
    interpreter's own flush at exit does not fail on it again."""
    if stream not in (sys.stdout, sys.stderr):
        return
    with contextlib.suppress(OSError, ValueError):
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, stream.fileno())
        os.close(null)


@contextmanager
def _stopping(stop: threading.Event, why: list[str]) -> Iterator[None]:
    """SIGINT and SIGTERM set ``stop``; a second SIGINT raises KeyboardInterrupt."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}

    def handler(signum: int, frame: FrameType | None) -> None:
        why.append("terminated" if signum == signal.SIGTERM else "interrupted")
        stop.set()
        signal.signal(signal.SIGINT, signal.default_int_handler)

    for s in previous:
        signal.signal(s, handler)
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def execute(
    society: Society,
    options: RunOptions,
    *,
    source: str = "",
    out: TextIO | None = None,
    err: TextIO | None = None,
    trace: TraceFile | None = None,
    hooks: Hooks | None = None,
    heading: str | None = None,
) -> int:
    """Run ``society`` as ``options`` say; print ``heading`` first (who runs,
    how long) and the summary last; the exit status.

    Opens ``options.trace`` unless a ``trace`` is given; closes the
    transports whatever happens. A :class:`~cfgplan.runtime.errors.RunError`
    raised before the loop starts (e.g. the trace file) propagates.
    """
    out = out or sys.stdout
    err = err or sys.stderr
    try:
        if trace is None and options.trace is not None:
            trace = open_trace(options.trace, options.force)
    except BaseException:
        society.close("not started")
        raise
    handled = hooks is not None and hooks.reconfigures
    printer = Printer(options.verbose, source, out, err, handled=handled)
    if heading is not None:
        printer.say(heading)
    if trace is not None:
        society.subscribe(trace)
    society.subscribe(printer)
    stop = threading.Event()
    why: list[str] = []
    reason = "interrupted"

    def between(cycle: int, elapsed: float) -> None:
        assert hooks is not None
        hooks.between(cycle, elapsed)
        if hooks.finished and not stop.is_set():
            why.append(hooks.finished)
            stop.set()

    try:
        with _stopping(stop, why):
            reason = society.run(
                options.cycles,
                options.rate,
                duration=options.duration,
                budget=options.budget,
                stale_periods=options.stale_periods,
                stop=stop,
                after_cycle=trace.flush if trace is not None else None,
                before=None if hooks is None else hooks.before,
                between=None if hooks is None else between,
            )
    except KeyboardInterrupt:
        reason = "interrupted"
    finally:
        if hooks is not None:
            hooks.close()
        society.close(why[0] if why else reason)
        if trace is not None:
            trace.close()
    for line in summary(society.every_wrapper):
        printer.say(line)
    transport = society.transport
    if transport is not None and transport.undelivered:
        printer.say(
            f"note: {transport.undelivered} value(s) sent to robots not in this process were "
            "dropped (the in-process transport joins only robots run together)",
            err,
        )
    problems = [p for p in (trace.failed if trace else None, printer.lost) if p]
    for problem in problems:
        printer.say(f"cfgplan: error: {problem}", err)
    if problems or printer.failed:
        return 1
    return EXIT_NONE if hooks is not None and hooks.stopped else 0
