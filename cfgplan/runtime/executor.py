"""Running individual configurations (chapter 5): robots, cycles and societies.

A :class:`Robot` is one robot's executable configuration: the channels it
creates (the ``LET`` of 5.3) and a *cycle* that calls the wrappers of its
functionalities in sorted order (the ``LAMBDA``). It is configured either by
the code ``cfgplan emit --lang python`` writes (a ``configure(robot)``
function) or from a :class:`~cfgplan.runtime.part.Part` by :func:`build`.

A robot runs its cycle whenever one of its functionalities is due: each runs
at its ``:freq`` (3.2) or else at the robot's rate, so the cycle comes at the
highest of these rates, and with rate 0 every functionality runs in every
cycle, with no pause. A :class:`Society` runs one or more robots of this
process in one loop (:meth:`Society.run`); robots of one process share an
:class:`~cfgplan.runtime.transport.InProcessTransport`, a robot program of
its own talks to the others through Zenoh.

**Extension point (monitoring, 5.5).** :meth:`Robot.subscribe` (or
:meth:`Society.subscribe`) registers a listener that receives every
:class:`~cfgplan.runtime.events.Event` as it happens, on the robot's thread:
calls and their outcome, messages sent and received, inputs going stale and
fresh, robots seen and lost, start and stop. The robot keeps only the last
:data:`EVENTS_KEPT` events (:attr:`Robot.events`); per-functionality counts
(:attr:`Wrapper.stats`) are kept whole; the full record goes to listeners
such as ``--trace``.
"""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import replace

from cfgplan.runtime.channel import Channel, make_local_channel
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.events import Call, Event, Lifecycle, Presence, Transfer
from cfgplan.runtime.part import Part
from cfgplan.runtime.registry import Registry
from cfgplan.runtime.transport import InProcessTransport, Transport
from cfgplan.runtime.wrapper import Input, Wrapper

__all__ = [
    "DEFAULT_BUDGET",
    "EVENTS_KEPT",
    "POLL",
    "Configure",
    "Cycle",
    "Listener",
    "Robot",
    "Society",
    "assemble",
    "build",
    "society",
]

Cycle = Callable[[], None]
"""One pass over a robot's functionalities (the LAMBDA of 5.3)."""

Listener = Callable[[Event], None]
"""Receives every event of a robot as it happens."""

EVENTS_KEPT = 1000
"""Events a robot keeps in memory (the newest); the rest only reach listeners."""

DEFAULT_BUDGET = 1.0
"""Seconds one call of an implementation may take before it is reported as blocked."""

POLL = 0.05
"""At most this long between two looks at the network, however slow the rates."""


class Robot:
    """One robot's executable configuration."""

    def __init__(
        self,
        name: str,
        registry: Registry,
        transport: Transport | None = None,
        *,
        clock: Callable[[], float] = time.monotonic,
        keep: int = EVENTS_KEPT,
    ) -> None:
        self.name = name
        self.registry = registry
        self.transport: Transport = transport if transport is not None else InProcessTransport()
        self.clock = clock
        self.channels: list[Channel] = []
        self.wrappers: list[Wrapper] = []
        self.events: deque[Event] = deque(maxlen=keep)
        self.listeners: list[Listener] = []
        self.cycles = 0
        self.now = clock()  # the time of the current cycle
        self._cycle: Cycle | None = None

    def subscribe(self, listener: Listener) -> None:
        """Give ``listener`` every event of this robot from now on."""
        self.listeners.append(listener)

    def local_channel(self, source: str, target: str, data: Sequence[str]) -> Channel:
        """``(make-local-channel 'ROBOT 'SRC 'DST '(data ...))`` on this robot."""
        channel = make_local_channel(self.name, source, target, data)
        self.channels.append(channel)
        return channel

    def global_channel(self, other: str, source: str, target: str, data: Sequence[str]) -> Channel:
        """``(make-global-channel 'OTHER 'SRC 'DST '(data ...))``: this robot's end."""
        channel = Channel(
            "global", self.name, source, target, data, other=other, transport=self.transport
        )
        if channel.remote:
            self.transport.attach(self.name, channel.key, lambda p: self._receive(channel, p))
        self.channels.append(channel)
        return channel

    def wrapper(
        self, label: str, name: str, objects: Sequence[str] = (), *, freq: float | None = None
    ) -> Wrapper:
        """The wrapper of functionality ``label``, run at ``freq`` per second if
        given (3.2); fails at once if ``name`` has no implementation."""
        wrapper = Wrapper(
            self.name,
            label,
            name,
            objects,
            self.registry.lookup(name),
            self._record,
            freq=freq,
            clock=self._now,
        )
        self.wrappers.append(wrapper)
        return wrapper

    def configure(self, configure: Configure) -> Robot:
        """Create the channels and wrappers; ``configure`` returns the cycle."""
        self._cycle = configure(self)
        return self

    @property
    def partners(self) -> list[str]:
        """The robots this one exchanges data with, by name."""
        return sorted({c.other for c in self.channels if c.remote and c.other is not None})

    def start(
        self,
        now: float,
        rate: float,
        budget: float | None = DEFAULT_BUDGET,
        stale_periods: float = 3.0,
    ) -> None:
        """Schedule every functionality from ``now`` and watch the partners."""
        self.now = now
        for w in self.wrappers:
            w.schedule(rate, now, budget, stale_periods)
        self._record(
            Lifecycle(
                robot=self.name,
                t=time.time(),
                what="start",
                info=(
                    ("transport", type(self.transport).__name__),
                    ("partners", self.partners),
                    ("rate", rate),
                ),
            )
        )
        self.transport.watch(self.name, self.partners, self._presence)

    def due(self, now: float) -> bool:
        return any(w.due(now) for w in self.wrappers)

    def next_due(self) -> float | None:
        """When the next functionality is due (``None``: every cycle, no pause)."""
        times = [w.next_due for w in self.wrappers if w.period is not None]
        if len(times) < len(self.wrappers):
            return None
        return min(times, default=math.inf)  # no functionality: never due

    def step(self, now: float | None = None) -> None:
        """Run one cycle at ``now`` (default: the clock's time): each
        functionality that is due then, in sorted order."""
        if self._cycle is None:
            raise RunError(f"robot {self.name} has no configuration to run")
        self.now = self.clock() if now is None else now
        self.cycles += 1
        self._cycle()

    def _now(self) -> float:
        return self.now

    def stop(self, reason: str) -> None:
        self._record(
            Lifecycle(robot=self.name, t=time.time(), what="stop", info=(("reason", reason),))
        )

    def _record(self, event: Event) -> Event:
        event = replace(event, cycle=self.cycles)
        self.events.append(event)
        for listener in self.listeners:
            listener(event)
        return event

    def _receive(self, channel: Channel, payload: bytes) -> None:
        try:
            message = channel.receive(payload, self.clock())
        except RunError as exc:
            self._record(
                Lifecycle(
                    robot=self.name,
                    t=time.time(),
                    what="error",
                    info=(("message", f"channel {channel.key}: {exc.message}; dropped"),),
                )
            )
            return
        self._record(
            Transfer(
                robot=self.name,
                t=time.time(),
                direction="receive",
                channel=channel.key,
                other=message.sender,
                value=message.value,
                seq=message.seq,
                sent=message.t,
            )
        )

    def _presence(self, other: str, alive: bool) -> None:
        self._record(Presence(robot=self.name, t=time.time(), other=other, alive=alive))


Configure = Callable[[Robot], Cycle]
"""What emitted code provides: create a robot's channels and wrappers, return its cycle."""


def build(part: Part, registry: Registry, transport: Transport | None = None) -> Robot:
    """A robot configured from its part of a configuration (the same as its emitted module)."""
    robot = Robot(part.robot, registry, transport)

    def configure(robot: Robot) -> Cycle:
        channels = [
            robot.local_channel(ch.source, ch.target, ch.data)
            if ch.other is None
            else robot.global_channel(ch.other, ch.source, ch.target, ch.data)
            for ch in part.channels
        ]
        calls = [
            (
                robot.wrapper(c.label, c.name, c.objects, freq=c.freq),
                [_entry([channels[i] for i in x]) for x in c.inputs],
                [[channels[i] for i in x] for x in c.outputs],
            )
            for c in part.calls
        ]

        def cycle() -> None:
            for wrapper, inputs, outputs in calls:
                wrapper(inputs, outputs)

        return cycle

    return robot.configure(configure)


def _entry(channels: list[Channel]) -> Input:
    if not channels:
        return None
    return channels[0] if len(channels) == 1 else channels


class Society:
    """Robots run in one process and one loop, a cycle of each in turn."""

    def __init__(
        self, robots: Sequence[Robot], transport: InProcessTransport | None = None
    ) -> None:
        self.robots = list(robots)
        self.transport = transport  # the one joining them, when they share one

    def subscribe(self, listener: Listener) -> None:
        for robot in self.robots:
            robot.subscribe(listener)

    @property
    def wrappers(self) -> list[Wrapper]:
        return [w for r in self.robots for w in r.wrappers]

    def run(
        self,
        cycles: int = 0,
        rate: float = 0.0,
        *,
        duration: float | None = None,
        budget: float | None = DEFAULT_BUDGET,
        stale_periods: float = 3.0,
        stop: threading.Event | None = None,
        after_cycle: Callable[[], None] | None = None,
    ) -> str:
        """Run until ``cycles`` cycles (0: no limit) or ``duration`` seconds
        have passed, or ``stop`` is set; ``rate`` per second (0: no pause).
        Returns why it stopped: ``cycles``, ``duration`` or ``stopped``."""
        clock = self.robots[0].clock if self.robots else time.monotonic
        begin = clock()
        for robot in self.robots:
            robot.start(begin, rate, budget, stale_periods)
        done = 0
        while True:
            if stop is not None and stop.is_set():
                return "stopped"
            now = clock()
            if duration is not None and now - begin >= duration:
                return "duration"
            for transport in self._transports():
                transport.poll()
            ran = False
            for robot in self.robots:
                if robot.due(now):
                    robot.step(now)
                    ran = True
            if ran:
                done += 1
                if after_cycle is not None:
                    after_cycle()
                if cycles and done >= cycles:
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
        if any(d is None for d in due):
            return  # rate 0: no pause
        wake = min(d for d in due if d is not None)
        now = clock()
        wait = min(max(0.0, wake - now), POLL)
        if duration is not None:
            wait = min(wait, max(0.0, begin + duration - now))
        if wait > 0:
            if stop is not None:
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


def society(parts: Sequence[Part], registry: Registry) -> Society:
    """Every robot of a configuration, joined in process."""
    registry.require(c.name for p in parts for c in p.calls)
    transport = InProcessTransport()
    return Society([build(p, registry, transport) for p in parts], transport)


def assemble(programs: Sequence[tuple[str, Configure]], registry: Registry) -> Society:
    """Robots configured by emitted code (name, configure), joined in process."""
    transport = InProcessTransport()
    robots = [Robot(name, registry, transport).configure(c) for name, c in programs]
    return Society(robots, transport)
