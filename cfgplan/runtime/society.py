"""A society: robots run in one process and one loop (chapter 5, 5.5).

A :class:`Society` runs one or more robots of this process
(:class:`~cfgplan.runtime.executor.Robot`) in one loop (:meth:`Society.run`):
a cycle of each robot that is due, in turn, at the highest rate any of them
needs. Robots of one process share an
:class:`~cfgplan.runtime.transport.InProcessTransport`; a robot program of its
own talks to the others through Zenoh. Between two cycles (the ``between``
hook) is where monitoring and reconfiguration act: a switch is installed
there, so no cycle runs half of two configurations; before a cycle (the
``before`` hook) scripted faults take effect. Robots may join a running
society (a configuration needs a robot not yet running), be killed (a
scripted fault) and come back.

**Extension point (simulation).** A society runs on a ``clock`` (default: the
first robot's, ``time.monotonic``); every robot it makes or takes in later
should share it. With ``paced=False`` the loop never pauses: a simulated
clock, advanced by the ``between`` hook (one fixed step per pass), makes each
run deterministic and as fast as the machine allows (:mod:`cfgplan.sim`).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Sequence

from cfgplan.runtime.events import Call, Event
from cfgplan.runtime.executor import (
    DEFAULT_BUDGET,
    POLL,
    Configure,
    Listener,
    Robot,
)
from cfgplan.runtime.install import build
from cfgplan.runtime.part import Part
from cfgplan.runtime.registry import Registry
from cfgplan.runtime.transport import InProcessTransport, Transport
from cfgplan.runtime.values import MAX_VALUE_BYTES
from cfgplan.runtime.wrapper import Wrapper

__all__ = ["Hook", "Society", "assemble", "society"]


Hook = Callable[[int, float], None]
"""Called with the number of the cycle about to run (or just run) and the
seconds since the run began: fault injection, reconfiguration (5.5)."""


class Society:
    """Robots run in one process and one loop, a cycle of each in turn.

    Robots may join while it runs (:meth:`add`: a configuration that needs a
    robot not yet running) and be killed (:meth:`kill`: a scripted fault; the
    others see it lost) or come back (:meth:`revive`).
    """

    def __init__(
        self,
        robots: Sequence[Robot],
        transport: InProcessTransport | None = None,
        *,
        clock: Callable[[], float] | None = None,
        paced: bool = True,
    ) -> None:
        self.robots = list(robots)
        self.transport = transport  # the one joining them, when they share one
        self.clock: Callable[[], float] = clock or (
            self.robots[0].clock if self.robots else time.monotonic
        )
        """The society's time: its robots', and that of the robots that join it."""
        self.paced = paced
        """False: the loop never waits for the next robot to be due (a simulated clock)."""
        self.listeners: list[Listener] = []
        self.cycles = 0  # cycles run so far, over every run
        self._settings: tuple[float, float, float | None, float, int] | None = None

    def subscribe(self, listener: Listener) -> None:
        """Give ``listener`` every event of every robot, those added later too."""
        self.listeners.append(listener)
        for robot in self.robots:
            robot.subscribe(listener)

    def robot(self, name: str) -> Robot | None:
        return next((r for r in self.robots if r.name == name), None)

    def add(self, robot: Robot) -> Robot:
        """Let ``robot`` join: it gets the listeners and, if the society is
        running, starts now with the run's rate, budget and staleness."""
        self.robots.append(robot)
        for listener in self.listeners:
            robot.subscribe(listener)
        if self._settings is not None:
            _, rate, budget, stale_periods, limit = self._settings
            robot.start(robot.clock(), rate, budget, stale_periods, max_value_bytes=limit)
        return robot

    def kill(self, name: str) -> None:
        """Robot ``name`` is gone: it runs no more and the others see it lost."""
        robot = self.robot(name)
        if robot is None or not robot.alive:
            return
        robot.alive = False
        robot.stop("killed")
        if isinstance(robot.transport, InProcessTransport):
            robot.transport.leave(name)

    def revive(self, name: str) -> None:
        """Robot ``name`` is back (with the configuration it had): seen again."""
        robot = self.robot(name)
        if robot is None or robot.alive:
            return
        robot.alive = True
        if isinstance(robot.transport, InProcessTransport):
            robot.transport.join(name)

    @property
    def wrappers(self) -> list[Wrapper]:
        return [w for r in self.robots for w in r.wrappers]

    @property
    def every_wrapper(self) -> list[Wrapper]:
        """The running wrappers, then those switches stopped (for the summary)."""
        return [w for r in self.robots for w in (*r.wrappers, *r.retired)]

    def run(
        self,
        cycles: int = 0,
        rate: float = 0.0,
        *,
        duration: float | None = None,
        budget: float | None = DEFAULT_BUDGET,
        stale_periods: float = 3.0,
        max_value_bytes: int = MAX_VALUE_BYTES,
        stop: threading.Event | None = None,
        after_cycle: Callable[[], None] | None = None,
        before: Hook | None = None,
        between: Hook | None = None,
        lead: str | None = None,
    ) -> str:
        """Run until ``cycles`` cycles (0: no limit) or ``duration`` seconds
        have passed, or ``stop`` is set; ``rate`` per second (0: no pause).
        ``before`` is called before each cycle, ``between`` after each pass of
        the loop (every robot that was due has run its cycle: the moment a
        switch may be installed, never half-way through a cycle).
        Returns why it stopped: ``cycles``, ``duration`` or ``stopped``.

        ``cycles`` counts the cycles of robot ``lead`` (the goal's robot,
        ``cfgplan run``), whatever robots join: a robot that joins a running
        society keeps a beat of its own, so passes of the loop outnumber the
        lead's cycles. While ``lead`` is not running (``None``, not in the
        society, killed) every pass in which a robot ran counts."""
        clock = self.clock
        begin = clock()
        self._settings = (begin, rate, budget, stale_periods, max_value_bytes)
        for robot in self.robots:
            robot.start(begin, rate, budget, stale_periods, max_value_bytes=max_value_bytes)
        done = 0
        while True:
            if stop is not None and stop.is_set():
                return "stopped"
            now = clock()
            if duration is not None and now - begin >= duration:
                return "duration"
            for transport in self._transports():
                transport.poll()
            if before is not None and any(r.due(now) for r in self.robots):
                before(self.cycles + 1, now - begin)
            ran = False
            leader = None if lead is None else self.robot(lead)
            lead_cycles = 0 if leader is None else leader.cycles
            for robot in list(self.robots):
                if robot.due(now):
                    robot.step(now)
                    ran = True
            if ran:
                if leader is None or not leader.alive or leader.cycles > lead_cycles:
                    done += 1
                self.cycles += 1
                if after_cycle is not None:
                    after_cycle()
            if between is not None:
                between(self.cycles, clock() - begin)
            if ran and cycles and done >= cycles:
                return "cycles"
            self._pause(clock, begin, duration, stop)

    def _pause(
        self,
        clock: Callable[[], float],
        begin: float,
        duration: float | None,
        stop: threading.Event | None,
    ) -> None:
        due = [r.next_due() for r in self.robots]
        if not self.paced or any(d is None for d in due):
            return  # rate 0, or a simulated clock: no pause
        wake = min(d for d in due if d is not None)
        now = clock()
        wait = min(max(0.0, wake - now), POLL)
        if duration is not None:
            wait = min(wait, max(0.0, begin + duration - now))
        if wait <= 0:
            return
        transports = self._transports()
        arrival = getattr(transports[0], "wait", None) if len(transports) == 1 else None
        if arrival is not None and (stop is None or not stop.is_set()):
            arrival(wait)  # a message wakes the loop: switches go through at once
        elif stop is not None:
            stop.wait(wait)
        else:
            time.sleep(wait)

    def _transports(self) -> list[Transport]:
        seen: dict[int, Transport] = {}
        for robot in self.robots:
            seen.setdefault(id(robot.transport), robot.transport)
        return list(seen.values())

    def close(self, reason: str) -> None:
        """Record the stop and close every transport."""
        for robot in self.robots:
            robot.stop(reason)
        for transport in self._transports():
            transport.close()

    @property
    def events(self) -> list[Event]:
        """The events kept, in the order they happened (cycle by cycle, robot by robot)."""
        merged = [e for r in self.robots for e in r.events]
        index = {r.name: i for i, r in enumerate(self.robots)}
        return sorted(merged, key=lambda e: (e.cycle, index[e.robot]))

    @property
    def calls(self) -> list[Call]:
        """The wrapper calls among :attr:`events`."""
        return [e for e in self.events if isinstance(e, Call)]


def society(
    parts: Sequence[Part],
    registry: Registry,
    *,
    clock: Callable[[], float] = time.monotonic,
    paced: bool = True,
) -> Society:
    """Every robot of a configuration, joined in process (on ``clock``)."""
    registry.require(c.name for p in parts for c in p.calls)
    transport = InProcessTransport()
    robots = [build(p, registry, transport, clock=clock) for p in parts]
    return Society(robots, transport, clock=clock, paced=paced)


def assemble(programs: Sequence[tuple[str, Configure]], registry: Registry) -> Society:
    """Robots configured by emitted code (name, configure), joined in process."""
    transport = InProcessTransport()
    robots = [Robot(name, registry, transport).configure(c) for name, c in programs]
    return Society(robots, transport)
