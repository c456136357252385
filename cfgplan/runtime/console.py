"""The console of a run (``cfgplan run``, the emitted programs): what matters, as it happens.

A :class:`Printer` listens to every robot of a run and shows:

* every loss, stale input, failure, recovery, state update and switch, with
  its cause, as one line each (:func:`~cfgplan.runtime.trace.notice`); a
  functionality's failures on stderr, the first few of each, then only
  counted, tagged with the implementations' file or ``[injected]``;
* what an action receives: the first time it runs, and again each time it
  runs after it did not (waiting for data, stale input, a switch): not every
  cycle, which ``--verbose`` shows (every call of every functionality);
* a compact status (:func:`~cfgplan.runtime.trace.status_parts`): each
  robot's cycles, each action's runs and last input, switches, failures. On
  a terminal (stdout and stderr both one) it is a line at the bottom, updated
  in place (rich); else a plain line every ``status_every`` cycles of the
  run's lead robot, so that what is piped or logged is the same from one run
  to the next (no timings, no control characters).

The words are all in :mod:`cfgplan.runtime.trace`; here is which event is
shown where. rich is imported only for a terminal: a robot's program in a
pipe or a log starts without it.
"""

from __future__ import annotations

import contextlib
import os
import sys
import time
from typing import TYPE_CHECKING, Any, TextIO

from cfgplan.runtime.errors import printable
from cfgplan.runtime.events import Adaptation, Call, Event, Lifecycle, Presence, Staleness
from cfgplan.runtime.trace import (
    describe,
    fault,
    further_faults,
    notice,
    runs_again,
    status_parts,
    value_warning,
    waits,
)

if TYPE_CHECKING:
    from cfgplan.runtime.society import Society

__all__ = ["FAULTS_SHOWN", "STATUS_EVERY", "WAIT_NOTICE", "Printer"]

FAULTS_SHOWN = 3
"""Failures printed per functionality; later ones are only counted."""

WAIT_NOTICE = 10
"""Calls in a row a functionality waits for data before the console says so
(1 s at the default rate): a robot whose partner has not started does not
look hung."""

ERROR_KINDS = 64
"""Kinds of ``error`` events the console counts apart (:meth:`Printer._error`)."""

STATUS_EVERY = 100
"""The default of :attr:`~cfgplan.runtime.launch.RunOptions.status_every`."""

REFRESH = 4
"""Times a second the status on a terminal is redrawn."""


class Printer:
    """The console side of a run: a listener of every robot."""

    def __init__(
        self,
        verbose: bool,
        source: str,
        out: TextIO,
        err: TextIO,
        handled: bool = False,
        *,
        status_every: int = STATUS_EVERY,
    ) -> None:
        self.verbose = verbose
        self.handled = handled  # resource failures are handled by reconfiguration
        self.source = source
        self.out = out
        self.err = err
        self.status_every = status_every
        self.failed = False
        self.lost: str | None = None  # why the console could not be written to
        self._faults: dict[str, int] = {}
        self._errors: dict[str, int] = {}  # error events per kind (_error)
        self._warned: set[tuple[str, str]] = set()
        self._dead: set[int] = set()
        self._waits: dict[tuple[str, str], int] = {}  # calls in a row each one waited
        self._running: set[tuple[str, str]] = set()  # actions whose last call ran
        # the status
        self._cycles: dict[str, int] = {}
        self._actions: dict[tuple[str, str], tuple[Call, int]] = {}  # last call, runs
        self._counts: dict[str, int] = {}
        self._cost: object = None
        self._shown_at = 0  # the lead's cycle of the last plain status line
        self._live: Any = None  # rich.live.Live on a terminal, while the run lasts
        self._began = 0.0
        self._society: Society | None = None

    # -- output -------------------------------------------------------------

    def say(self, text: str, stream: TextIO | None = None) -> None:
        """A line on ``stream`` (default: ``out``); a stream that cannot be
        written to (closed pipe, full disk) is given up, not fatal. What came
        from another process (a helper's error text, a refusal's reason) or
        from the input is shown with control characters escaped: nothing on
        the network can drive this terminal."""
        text = "\n".join(printable(line) for line in text.split("\n"))
        stream = self.out if stream is None or self._live is not None else stream
        if id(stream) in self._dead:
            return
        try:
            if self._live is not None:  # one terminal: every line above the status
                from rich.text import Text

                self._live.console.print(Text(text), soft_wrap=True)
            else:
                print(text, file=stream, flush=True)
        except (OSError, ValueError) as exc:
            self._dead.add(id(stream))
            what = "standard output" if stream is self.out else "standard error"
            reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
            self.lost = self.lost or f"cannot write to {what}: {reason}"
            if self._live is not None:
                self._stop_live()
            _silence(stream)

    def start(self, society: Society | None = None) -> None:
        """The run of ``society`` begins: on a terminal, show the status at the
        bottom, updated in place (each robot's cycles read from ``society``)."""
        self._began = time.monotonic()
        self._society = society
        if not _terminal(self.out, self.err):
            return
        from rich.console import Console
        from rich.live import Live

        console = Console(file=self.out, markup=False, highlight=False)
        self._live = Live(
            get_renderable=self._rendered,
            console=console,
            refresh_per_second=REFRESH,
            transient=True,
            redirect_stdout=False,
            redirect_stderr=False,
        )
        self._live.start()

    def stop(self) -> None:
        """The run is over: the status leaves the terminal (the summary follows)."""
        if self._live is not None:
            self._stop_live()

    def _stop_live(self) -> None:
        live, self._live = self._live, None
        with contextlib.suppress(OSError, ValueError):
            live.stop()

    def cycle(self, lead_cycles: int) -> None:
        """A pass of the loop ran, the lead robot at ``lead_cycles``: without a
        terminal, the status every ``status_every`` of its cycles."""
        every = self.status_every
        if self._live is not None or not every or lead_cycles < self._shown_at + every:
            return
        self._shown_at = lead_cycles - lead_cycles % every
        self.say(f"cycle {self._shown_at}: status: " + "; ".join(self._parts()))

    def _parts(self) -> list[str]:
        """The status's parts. rich redraws a live status on its own thread
        while the robots' thread adds actions and counts: read copies (each
        made by one C call, under the GIL), never the dicts themselves."""
        cycles = dict(self._cycles)
        if self._society is not None:  # robots that run nothing have cycles too
            cycles = {robot.name: robot.cycles for robot in list(self._society.robots)}
        actions = list(self._actions.values())
        return status_parts(cycles, actions, dict(self._counts), self._cost)

    def _rendered(self) -> Any:
        from rich.text import Text

        elapsed = time.monotonic() - self._began
        text = Text()
        text.append(f"{elapsed:.1f} s", style="bold")
        for part in self._parts():
            text.append(" │ ", style="dim")
            text.append(part)
        live = self._live
        width = live.console.width if live is not None else 80
        # one line, a few columns short of the terminal's, so that an echoed
        # ^C does not wrap it (the status could not then be erased)
        text.truncate(max(20, width - 4), overflow="ellipsis")
        text.no_wrap = True
        return text

    # -- events -------------------------------------------------------------

    def __call__(self, event: Event) -> None:
        if isinstance(event, Call):
            self._call(event)
            return
        self._count(event)
        if isinstance(event, Lifecycle) and event.what == "error":
            self._error(event)
            return
        line = notice(event)
        if line is not None:
            self.say(line)

    def _count(self, event: Event) -> None:
        """What the status counts: switches (and the cost now), stale inputs,
        losses; an action a switch stopped leaves it."""
        key = None
        if isinstance(event, Adaptation) and event.what in ("switch", "install"):
            stopped = event.field("stopped")
            if isinstance(stopped, dict):  # a switch: {"functionalities": [...], ...}
                stopped = stopped.get("functionalities")
            labels = {str(f).split(":")[0] for f in stopped} if isinstance(stopped, list) else ()
            self._actions = {k: v for k, v in self._actions.items() if k[1] not in labels}
        if isinstance(event, Adaptation) and event.what == "switch":
            key, self._cost = "switch", event.field("to_cost")
        elif isinstance(event, Staleness) and event.state == "stale":
            key = "stale"
        elif isinstance(event, Presence) and not event.alive:
            key = "lost"
        if key is not None:
            self._counts[key] = self._counts.get(key, 0) + 1

    def _call(self, event: Call) -> None:
        self._cycles[event.robot] = max(self._cycles.get(event.robot, 0), event.cycle)
        if event.action:
            _, ran = self._actions.get((event.robot, event.label), (event, 0))
            self._actions[(event.robot, event.label)] = (event, ran + (event.status == "ran"))
        if not self.verbose:
            self._waiting(event)
        if event.status in ("error", "timeout"):
            self._counts["failure"] = self._counts.get("failure", 0) + 1
            self.failed = self.failed or not (self.handled and event.failure)
            self._fault(event)
            self._running.discard((event.robot, event.label))
            return
        if self.verbose:
            self._show(event)
            return
        if not event.action:
            return
        key = (event.robot, event.label)
        if event.status != "ran":
            self._running.discard(key)
        elif key not in self._running:  # runs, for the first time or again: what it gets
            self._running.add(key)
            self._show(event)

    def _show(self, event: Call) -> None:
        problems: list[str] = []
        self.say(describe(event, problems))
        for problem in problems:
            if (event.label, problem) not in self._warned:
                self._warned.add((event.label, problem))
                self.say(value_warning(event, problem, self.source), self.err)

    def _waiting(self, event: Call) -> None:
        """Say when a functionality has waited :data:`WAIT_NOTICE` calls in a
        row for data, and for what; and when it runs again (an action says
        what it receives instead)."""
        key = (event.robot, event.label)
        if event.status == "waiting":
            waited = self._waits.get(key, 0) + 1
            self._waits[key] = waited
            if waited == WAIT_NOTICE:
                self.say(waits(event, waited))
            return
        waited = self._waits.pop(key, 0)
        if waited >= WAIT_NOTICE and event.status == "ran" and not event.action:
            self.say(runs_again(event))

    def _error(self, event: Lifecycle) -> None:
        """A message dropped, a helper's error: the first :data:`FAULTS_SHOWN`
        of each kind (the text before its first ``": "``: the channel, the
        helper's functionality) are printed, later ones only counted (the
        status; the trace has each). At most :data:`ERROR_KINDS` kinds are
        told apart: what comes from the network may name anything."""
        self._counts["error"] = self._counts.get("error", 0) + 1
        kind = str(dict(event.info).get("message", "")).split(": ", 1)[0]
        if kind not in self._errors and len(self._errors) >= ERROR_KINDS:
            kind = ""  # one kind for all the others
        seen = self._errors[kind] = self._errors.get(kind, 0) + 1
        if seen <= FAULTS_SHOWN:
            self.say(f"cfgplan: {notice(event)}", self.err)
        if seen == FAULTS_SHOWN:
            what = f"of {kind} " if kind else ""
            self.say(
                f"cfgplan: further errors {what}are only counted (status; --trace has each)",
                self.err,
            )

    def _fault(self, event: Call) -> None:
        key = f"{event.robot} {event.label}"
        seen = self._faults.get(key, 0) + 1
        self._faults[key] = seen
        if seen <= FAULTS_SHOWN:
            self.say(fault(event, self.source), self.err)
        if seen == FAULTS_SHOWN:
            self.say(further_faults(event), self.err)


def _terminal(out: TextIO, err: TextIO) -> bool:
    """Both streams are one terminal's (not a pipe, a file or a dumb terminal)."""
    if os.environ.get("TERM") == "dumb":
        return False
    try:
        return out.isatty() and err.isatty()
    except (AttributeError, ValueError):
        return False


def _silence(stream: TextIO) -> None:
    """Point a standard stream that failed at the null device, so that the
    interpreter's own flush at exit does not fail on it again."""
    if stream not in (sys.stdout, sys.stderr):
        return
    with contextlib.suppress(OSError, ValueError):
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, stream.fileno())
        os.close(null)
