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

Exit status: 0 when the run ended as asked; 1 when a functionality failed
(raised, exited, returned what could not be written, overran its budget) or
the trace could not be written.
"""

from __future__ import annotations

import signal
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from types import FrameType
from typing import TextIO

from cfgplan.runtime.events import Call, Event, Lifecycle
from cfgplan.runtime.executor import DEFAULT_BUDGET, Society
from cfgplan.runtime.trace import describe, notice, summary
from cfgplan.runtime.tracefile import TraceFile, open_trace

__all__ = ["FAULTS_SHOWN", "Printer", "RunOptions", "execute"]

FAULTS_SHOWN = 3
"""Failures printed per functionality; later ones are only counted."""


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

    def __init__(self, verbose: bool, source: str, out: TextIO, err: TextIO) -> None:
        self.verbose = verbose
        self.source = source
        self.out = out
        self.err = err
        self.failed = False
        self._faults: dict[str, int] = {}
        self._warned: set[tuple[str, str]] = set()

    def __call__(self, event: Event) -> None:
        if isinstance(event, Call):
            self._call(event)
            return
        if isinstance(event, Lifecycle) and event.what == "error":
            print(f"cfgplan: {notice(event)}", file=self.err, flush=True)
            return
        line = notice(event)
        if line is not None:
            print(line, file=self.out, flush=True)

    def _call(self, event: Call) -> None:
        if event.status in ("error", "timeout"):
            self.failed = True
            self._fault(event)
            return
        if not (self.verbose or (event.action and event.status == "ran")):
            return
        problems: list[str] = []
        line = describe(event, problems)
        print(line, file=self.out, flush=True)
        for problem in problems:
            if (event.label, problem) not in self._warned:
                self._warned.add((event.label, problem))
                print(
                    f"cfgplan: warning: {event.label} {event.name} on {event.robot}: {problem} "
                    f"(implementations: {self.source})",
                    file=self.err,
                    flush=True,
                )

    def _fault(self, event: Call) -> None:
        key = f"{event.robot} {event.label}"
        seen = self._faults.get(key, 0) + 1
        self._faults[key] = seen
        if seen <= FAULTS_SHOWN:
            print(f"cfgplan: {describe(event)} [{self.source}]", file=self.err, flush=True)
        if seen == FAULTS_SHOWN:
            print(
                f"cfgplan: further failures of {event.label} {event.name} on {event.robot} "
                "are only counted (summary; --trace has each)",
                file=self.err,
                flush=True,
            )


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
) -> int:
    """Run ``society`` as ``options`` say; print the summary; the exit status.

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
    printer = Printer(options.verbose, source, out, err)
    if trace is not None:
        society.subscribe(trace)
    society.subscribe(printer)
    stop = threading.Event()
    why: list[str] = []
    reason = "interrupted"
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
            )
    except KeyboardInterrupt:
        reason = "interrupted"
    finally:
        society.close(why[0] if why else reason)
        if trace is not None:
            trace.close()
    for line in summary(society.wrappers):
        print(line, file=out)
    transport = society.transport
    if transport is not None and transport.undelivered:
        print(
            f"note: {transport.undelivered} value(s) sent to robots not in this process were "
            "dropped (the in-process transport joins only robots run together)",
            file=err,
        )
    if trace is not None and trace.failed:
        print(f"cfgplan: error: {trace.failed}", file=err)
        return 1
    return 1 if printer.failed else 0
