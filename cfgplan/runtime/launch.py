"""Running a society until it is done or told to stop: options, console, trace, signals.

Shared by ``cfgplan run`` and the programs ``cfgplan emit --lang python``
writes, so both behave the same. :func:`execute` runs the loop of
:meth:`~cfgplan.runtime.executor.Society.run` and:

* shows what matters as it happens (:mod:`cfgplan.runtime.console`): a
  compact status, losses, stale inputs, failures and switches with their
  cause, what each action receives when it starts (with ``verbose``, every
  call); on stderr, each functionality's failures (the first few of each,
  then only counted) and values whose ``__repr__`` fails, blaming the
  implementation (or ``[injected]``, a scripted fault);
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

import signal
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from types import FrameType
from typing import Protocol, TextIO

from cfgplan.runtime.console import STATUS_EVERY, Printer
from cfgplan.runtime.executor import DEFAULT_BUDGET
from cfgplan.runtime.society import Society
from cfgplan.runtime.trace import summary, undelivered
from cfgplan.runtime.tracefile import MAX_BYTES as TRACE_MAX_BYTES
from cfgplan.runtime.tracefile import TraceFile, open_trace
from cfgplan.runtime.values import MAX_VALUE_BYTES

__all__ = ["EXIT_NONE", "REFUSED", "Hooks", "RunOptions", "execute"]

EXIT_NONE = 3
REFUSED = "refused"
"""Why a run ends whose process may not run at all (:attr:`Hooks.refusal`)."""
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
    def refusal(self) -> str | None:
        """Why this process may not run at all (a second process of a robot, a
        second coordinator of a society): the run ends (``finished`` is
        :data:`REFUSED`) with this message and exit status 1."""

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
    max_value_bytes: int = MAX_VALUE_BYTES  # a value's JSON on a global channel; 0: any
    trace: str | None = None
    trace_max_bytes: int = TRACE_MAX_BYTES  # then FILE.1; 0: no cap
    force: bool = False
    verbose: bool = False
    status_every: int = STATUS_EVERY
    """Without a terminal, the status line every this many cycles of the lead robot (0: never)."""


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
    lead: str | None = None,
) -> int:
    """Run ``society`` as ``options`` say; print ``heading`` first (who runs,
    how long) and the summary last; the exit status. ``options.cycles``
    counts the cycles of robot ``lead`` (the goal's robot), if given
    (:meth:`~cfgplan.runtime.society.Society.run`).

    Opens ``options.trace`` unless a ``trace`` is given; closes the
    transports whatever happens. A :class:`~cfgplan.runtime.errors.RunError`
    raised before the loop starts (e.g. the trace file) propagates.
    """
    out = out or sys.stdout
    err = err or sys.stderr
    try:
        if trace is None and options.trace is not None:
            trace = open_trace(options.trace, options.force, max_bytes=options.trace_max_bytes)
    except BaseException:
        society.close("not started")
        raise
    handled = hooks is not None and hooks.reconfigures
    printer = Printer(
        options.verbose, source, out, err, handled=handled, status_every=options.status_every
    )
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

    leader = None if lead is None else society.robot(lead)

    def after_cycle() -> None:
        if trace is not None:
            trace.flush()
        printer.cycle(society.cycles if leader is None else leader.cycles)

    try:
        printer.start(society)
        with _stopping(stop, why):
            reason = society.run(
                options.cycles,
                options.rate,
                duration=options.duration,
                budget=options.budget,
                stale_periods=options.stale_periods,
                max_value_bytes=options.max_value_bytes,
                stop=stop,
                after_cycle=after_cycle,
                before=None if hooks is None else hooks.before,
                between=None if hooks is None else between,
                lead=lead,
            )
    except KeyboardInterrupt:
        reason = "interrupted"
    finally:
        if hooks is not None:
            hooks.close()
        society.close(why[0] if why else reason)
        printer.stop()
        if trace is not None:
            trace.close()
    for line in summary(society.every_wrapper):
        printer.say(line)
    transport = society.transport
    if transport is not None and transport.undelivered:
        printer.say(undelivered(transport.undelivered), err)
    problems = [p for p in (trace.failed if trace else None, printer.lost) if p]
    if hooks is not None and hooks.refusal is not None:
        problems.append(hooks.refusal)
    for problem in problems:
        printer.say(f"cfgplan: error: {problem}", err)
    if problems or printer.failed:
        return 1
    return EXIT_NONE if hooks is not None and hooks.stopped else 0
