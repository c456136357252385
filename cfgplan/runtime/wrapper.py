"""The wrapper function of 5.2.1: the standard interface of a functionality.

The configuration calls the wrapper once a cycle with the functionality's
channels: one entry per input, one list of channels per output, as the LISP
call of 5.3 passes them. If every input has fresh data and the precondition
holds, the wrapper reads the inputs, runs the actual function and writes each
output to all of its channels; otherwise it returns without running it.

An input entry is a channel, a list of channels (several feed it; it is fresh
when one of them is, and the first fresh one in the list gives the value, all
fresh ones being read) or ``None`` (nothing feeds it: the function never runs).

Beyond the thesis, for running on real robots:

* **Frequency (3.2, Freq).** A wrapper with a period runs only when it is
  due; with none (``--rate 0``) it runs in every cycle.
* **Staleness.** An input whose data has not been refreshed for more than
  ``stale_periods`` periods of its sender is *stale*: the wrapper does not run
  on it, and says so (a :class:`~cfgplan.runtime.events.Staleness` event when
  an input goes stale or is fresh again, and the call's status ``stale``).
* **Faults stay with their functionality.** An exception, ``sys.exit``, a
  wrong number of outputs or a value that cannot travel on a global channel
  is reported as the call's ``error``; nothing is written, so the
  functionality's outputs go stale, and the robot goes on.
* **Resource failures (5.5).** An implementation that raises
  :class:`~cfgplan.runtime.faults.ResourceFailure`, or a scripted fault
  (:attr:`Wrapper.injected`), fails the call with ``failure`` set: the
  monitor takes it as the resource failing. An action that returns
  :data:`~cfgplan.runtime.faults.ACHIEVED` says its task is accomplished.
* **Time budget.** With a budget the function runs on its own
  :class:`~cfgplan.runtime.worker.Worker` thread; a call over budget is
  reported (``timeout``) and the functionality is skipped (``busy``) until it
  returns. The ``stop`` hook has the same budget (:meth:`Wrapper.stop`).

Each call returns a :class:`~cfgplan.runtime.events.Call` saying what happened
(``None`` when the wrapper was not due).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field

from cfgplan.notation import instance_text
from cfgplan.runtime.channel import Channel
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.events import Call, Data, Event, Staleness, Status, Transfer
from cfgplan.runtime.faults import ACHIEVED, Failed, failed, fault
from cfgplan.runtime.outputs import encoded_for, split
from cfgplan.runtime.registry import Implementation
from cfgplan.runtime.values import MAX_VALUE_BYTES
from cfgplan.runtime.worker import Worker

__all__ = ["Input", "Stats", "Wrapper", "current_robot", "running_on"]

Input = Channel | Sequence[Channel] | None
Record = Callable[[Event], Event]

_robot: ContextVar[str] = ContextVar("cfgplan_robot")
_REFUSED = object()  # the precondition said no


def current_robot() -> str:
    """The robot whose functionality is running (for implementations)."""
    try:
        return _robot.get()
    except LookupError:
        raise RunError("current_robot() is only known while a functionality runs") from None


@contextmanager
def running_on(robot: str) -> Iterator[None]:
    token = _robot.set(robot)
    try:
        yield
    finally:
        _robot.reset(token)


@dataclass
class Stats:
    """How a wrapper's calls went, kept whole however long the run (the summary)."""

    calls: int = 0
    by_status: dict[str, int] = field(default_factory=dict)
    last: Call | None = None
    last_error: str = ""

    def count(self, event: Call) -> None:
        self.calls += 1
        self.by_status[event.status] = self.by_status.get(event.status, 0) + 1
        self.last = event
        if event.status == "error":
            self.last_error = event.error


def _channels(entry: Input) -> list[Channel]:
    if entry is None:
        return []
    if isinstance(entry, Channel):
        return [entry]
    return list(entry)


def _data(channels: Sequence[Channel], what: str, k: int) -> Data:
    return channels[0].data if channels else (f"{what}-{k + 1}",)


class Wrapper:
    """The wrapper of functionality ``label`` (``name``) on ``robot``."""

    def __init__(
        self,
        robot: str,
        label: str,
        name: str,
        objects: Sequence[str],
        implementation: Implementation,
        record: Record | None = None,
        *,
        freq: float | None = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.robot = robot
        self.label = label
        self.name = name
        self.objects = tuple(objects)
        self.implementation = implementation
        self.record = record  # sees (and may complete) every event, e.g. with the cycle
        self.freq = freq if freq is not None and freq > 0 else None
        self.clock = clock  # a robot's wrappers see the time of its cycle
        self.period: float | None = None  # None: runs in every cycle
        self.next_due = 0.0
        self.budget: float | None = None  # None: runs on the robot's thread
        self.stale_periods = 3.0
        self.max_value_bytes = MAX_VALUE_BYTES  # an output's JSON for another robot (0: any)
        self.stats = Stats()
        self.injected: str | None = None  # a scripted fault: every call fails (5.5)
        self.stopped = False  # switched out by a reconfiguration, or stopped safely
        self._worker: Worker | None = None

    def __str__(self) -> str:
        return instance_text(self.label, self.name, (self.robot, *self.objects))

    def schedule(
        self,
        rate: float,
        now: float,
        budget: float | None = None,
        stale_periods: float = 3.0,
        *,
        max_value_bytes: int = MAX_VALUE_BYTES,
    ) -> None:
        """Run at ``:freq`` or else ``rate`` per second from ``now`` (``rate`` 0:
        in every cycle); calls get ``budget`` seconds (``None``: no limit); an
        output for another robot may be ``max_value_bytes`` of JSON (0: any)."""
        self.period = None if rate <= 0 else 1.0 / (self.freq or rate)
        self.next_due = now
        self.budget = budget
        self.stale_periods = stale_periods
        self.max_value_bytes = max_value_bytes

    def due(self, now: float) -> bool:
        return self.period is None or now >= self.next_due - 1e-9

    def __call__(
        self, inputs: Sequence[Input], outputs: Sequence[Sequence[Channel]]
    ) -> Call | None:
        now = self.clock()
        if not self.due(now):
            return None
        if self.period is not None:
            self.next_due += self.period
            if self.next_due <= now:  # fell behind: skip the missed turns, keep the beat
                self.next_due += (math.floor((now - self.next_due) / self.period) + 1) * self.period
        event = self._call(inputs, outputs, now)
        self.stats.count(event)
        return self._emit(event)

    def _emit(self, event: Call) -> Call:
        if self.record is None:
            return event
        done = self.record(event)
        assert isinstance(done, Call)
        return done

    def _event(self, status: Status, **fields: object) -> Call:
        return Call(
            robot=self.robot,
            t=time.time(),
            label=self.label,
            name=self.name,
            args=(self.robot, *self.objects),
            status=status,
            **fields,  # type: ignore[arg-type]
        )

    def _call(
        self, inputs: Sequence[Input], outputs: Sequence[Sequence[Channel]], now: float
    ) -> Call:
        feeds = [_channels(x) for x in inputs]
        data = [_data(chs, "input", k) for k, chs in enumerate(feeds)]
        action = not outputs
        if self._worker is not None and self._worker.busy:
            return self._event("busy", action=action)
        stale = self._staleness(feeds, data, now)
        if stale:
            return self._event("stale", stale=stale, action=action)
        waiting = tuple(
            d for d, chs in zip(data, feeds, strict=True) if not any(c.fresh for c in chs)
        )
        if waiting:
            return self._event("waiting", waiting=waiting, action=action)
        fresh = [[c for c in chs if c.fresh] for chs in feeds]
        values = [chs[0].peek() for chs in fresh]
        status, result, duration = self._invoke(values)
        if status == "precondition":
            return self._event("precondition", action=action)
        for chs in fresh:  # the function has seen them: the last operation is a read
            for ch in chs:
                ch.read()
        read = tuple(zip(data, values, strict=True))
        if status != "ran":
            return self._event(
                status,
                inputs=read,
                action=action,
                error=str(result),
                duration=duration,
                failure=result.failure if isinstance(result, Failed) else "",
            )
        if action and result is ACHIEVED:
            return self._event("ran", inputs=read, action=action, duration=duration, achieved=True)
        out_data = [_data(chs, "output", k) for k, chs in enumerate(outputs)]
        try:
            produced = split(result, len(outputs))
            encoded = [
                encoded_for(v, chs, d, self.max_value_bytes)
                for v, chs, d in zip(produced, outputs, out_data, strict=True)
            ]
        except RunError as exc:
            return self._event(
                "error", inputs=read, action=action, error=exc.message, duration=duration
            )
        for value, text, channels in zip(produced, encoded, outputs, strict=True):
            if value is not None:
                for ch in channels:
                    ch.write(value, period=self.period, now=now, encoded=text)
                    if ch.remote and self.record is not None:
                        assert ch.other is not None
                        self.record(
                            Transfer(
                                robot=self.robot,
                                t=time.time(),
                                direction="send",
                                channel=ch.key,
                                other=ch.other,
                                value=value,
                                seq=ch.seq,
                            )
                        )
        return self._event(
            "ran",
            inputs=read,
            outputs=tuple(zip(out_data, produced, strict=True)),
            action=action,
            duration=duration,
        )

    def _staleness(
        self, feeds: list[list[Channel]], data: list[Data], now: float
    ) -> tuple[Data, ...]:
        """The inputs whose data is all stale; reports each channel going stale or fresh."""
        stale: list[Data] = []
        for d, chs in zip(data, feeds, strict=True):
            written = [c for c in chs if c.refreshed is not None]
            flags = [c.stale(now, self.stale_periods) for c in written]
            for ch, is_stale in zip(written, flags, strict=True):
                if is_stale != ch.stale_reported:
                    ch.stale_reported = is_stale
                    self._report_staleness(ch, now, is_stale)
            if written and all(flags):
                stale.append(d)
        return tuple(stale)

    def _report_staleness(self, ch: Channel, now: float, is_stale: bool) -> None:
        if self.record is None:
            return
        period = ch.period if ch.period is not None else 0.0
        self.record(
            Staleness(
                robot=self.robot,
                t=time.time(),
                state="stale" if is_stale else "fresh",
                label=self.label,
                channel=ch.key,
                source_robot=ch.other if ch.remote and ch.other else self.robot,
                age=ch.age(now) or 0.0,
                period=period,
                limit=self.stale_periods * period,
            )
        )

    def _invoke(self, values: list[object]) -> tuple[Status, object, float]:
        """Precondition and function; (status, result or :class:`Failed`, seconds)."""
        if self.injected is not None:
            return "error", Failed(f"injected fault ({self.injected})", "injected"), 0.0
        impl, objects = self.implementation, self.objects

        def job() -> object:
            if not impl.allowed(*objects):
                return _REFUSED
            return impl(*objects, *values)

        started = time.perf_counter()
        if self.budget is None:
            with running_on(self.robot):
                try:
                    result = job()
                except (Exception, SystemExit) as exc:
                    return "error", failed(exc), time.perf_counter() - started
        else:
            if self._worker is None:
                self._worker = Worker(f"cfgplan {self.robot} {self}", self._on_worker)
            kind, result = self._worker.run(job, self.budget)
            if kind == "overran":
                return (
                    "timeout",
                    f"the call took longer than its time budget of {self.budget:g} s; "
                    "skipped until it returns",
                    time.perf_counter() - started,
                )
            if kind == "raised":
                assert isinstance(result, BaseException)
                return "error", failed(result), time.perf_counter() - started
        if result is _REFUSED:
            return "precondition", None, 0.0
        return "ran", result, time.perf_counter() - started

    def probe(self) -> bool:
        """Whether a failed sensing resource works again (5.5): its function
        called with no inputs and its precondition, the outputs discarded; it
        works when it ran and gave data. Never while a scripted fault holds or
        an earlier call is still running."""
        if self.injected is not None or (self._worker is not None and self._worker.busy):
            return False
        status, result, _ = self._invoke([])
        return status == "ran" and result is not None

    def stop(self) -> str | None:
        """The functionality stops running (switched out, or a safe stop, 5.5):
        the implementation's ``stop`` hook, then its thread ends. What went
        wrong in the hook, if anything (also reported as a failed call of the
        functionality, status ``error`` or ``timeout``).

        The hook has the time budget of a call: one that blocks is abandoned
        after it (its thread, a daemon, is left to finish), so that a switch or
        a stop never freezes the robot. With no budget it runs on the robot's
        thread, as calls do."""
        self.stopped = True
        problem = self._stop_hook()
        if self._worker is not None:
            self._worker.close()
            self._worker = None
        return problem

    def _stop_hook(self) -> str | None:
        hook, objects = self.implementation.stop, self.objects
        if hook is None:
            return None
        started = time.perf_counter()
        status: Status = "error"
        problem = None
        if self.budget is None:
            with running_on(self.robot):
                try:
                    hook(*objects)
                except (Exception, SystemExit) as exc:
                    problem = f"its stop hook failed: {fault(exc)}"
        else:
            worker = Worker(f"cfgplan {self.robot} {self} stop", self._on_worker)
            kind, result = worker.run(lambda: hook(*objects), self.budget)
            worker.close()  # its thread ends when the hook returns, if ever
            if kind == "overran":
                status = "timeout"
                problem = (
                    f"its stop hook took longer than its time budget of {self.budget:g} s; "
                    "abandoned, the functionality may not have stopped"
                )
            elif kind == "raised":
                assert isinstance(result, BaseException)
                problem = f"its stop hook failed: {fault(result)}"
        if problem is not None:
            event = self._event(status, error=problem, duration=time.perf_counter() - started)
            self.stats.count(event)
            self._emit(event)
        return problem

    def _on_worker(self) -> None:
        """On the worker thread, before its first call: whose robot it is."""
        _robot.set(self.robot)
