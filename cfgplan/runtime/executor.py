"""Running individual configurations (chapter 5): robots and their cycles.

A :class:`Robot` is one robot's executable configuration: the channels it
creates (the ``LET`` of 5.3) and a *cycle* that calls the wrappers of its
functionalities in sorted order (the ``LAMBDA``). It is configured either by
the code ``cfgplan emit --lang python`` writes (a ``configure(robot)``
function) or from a :class:`~cfgplan.runtime.part.Part` by :func:`build`.

A robot runs its cycle whenever one of its functionalities is due: each runs
at its ``:freq`` (3.2) or else at the robot's rate, so the cycle comes at the
highest of these rates, and with rate 0 every functionality runs in every
cycle, with no pause. A :class:`~cfgplan.runtime.society.Society` runs one
or more robots of this process in one loop. A running robot can be given
another part of a configuration (:func:`cfgplan.runtime.install.install`).

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
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import replace

from cfgplan.notation import instance_text
from cfgplan.runtime.channel import Channel, make_local_channel
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.events import Event, Lifecycle, Presence, Transfer
from cfgplan.runtime.part import Part
from cfgplan.runtime.registry import Registry
from cfgplan.runtime.transport import InProcessTransport, Transport
from cfgplan.runtime.values import MAX_VALUE_BYTES, oversized
from cfgplan.runtime.wrapper import Input, Wrapper

__all__ = [
    "DEFAULT_BUDGET",
    "EVENTS_KEPT",
    "POLL",
    "Configure",
    "Cycle",
    "Listener",
    "Robot",
    "wired",
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
        cost: float | None = None,
    ) -> None:
        self.name = name
        self.cost = cost
        """The cost of the configuration it starts with, if known (its ``start`` event says it)."""
        self.registry = registry
        self.transport: Transport = transport if transport is not None else InProcessTransport()
        self.clock = clock
        self.channels: list[Channel] = []
        self.wrappers: list[Wrapper] = []
        self.retired: list[Wrapper] = []
        """Wrappers a switch stopped (kept for the summary)."""
        self.events: deque[Event] = deque(maxlen=keep)
        self.listeners: list[Listener] = []
        self.cycles = 0
        self.now = clock()  # the time of the current cycle
        self.alive = True  # False once killed (a scripted fault): it runs no more
        self.started_at: float | None = None  # clock time of start()
        self.rate = 0.0
        self.budget: float | None = DEFAULT_BUDGET
        self.stale_periods = 3.0
        self.max_value_bytes = MAX_VALUE_BYTES
        """The size rule (:mod:`cfgplan.runtime.values`): bytes of JSON per value, 0: any."""
        self.faults: dict[tuple[str, ...], str] = {}
        """Scripted faults in effect, by functionality instance (5.5)."""
        self.before: list[Callable[[Robot], None]] = []
        """Called before each cycle (fault injection, probes): see :meth:`step`."""
        self.released = False
        """The run is over: robots that leave are not lost (:meth:`release`)."""
        self._idle_next = 0.0  # with no functionality, the cycle still ticks at the rate
        self._cycle: Cycle | None = None

    def subscribe(self, listener: Listener) -> None:
        """Give ``listener`` every event of this robot from now on."""
        self.listeners.append(listener)

    def record(self, event: Event) -> Event:
        """Stamp ``event`` with this robot's cycle, keep it, give it to the listeners."""
        return self._record(event)

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
            self.transport.attach(
                self.name, channel.key, lambda p: self._receive(channel, p), other
            )
        self.channels.append(channel)
        return channel

    def wrapper(
        self,
        label: str,
        name: str,
        objects: Sequence[str] = (),
        *,
        freq: float | None = None,
        inputs: int | None = None,
    ) -> Wrapper:
        """The wrapper of functionality ``label``, run at ``freq`` per second if
        given (3.2); fails at once if ``name`` has no implementation, or one
        that cannot take the ``objects`` and ``inputs`` inputs."""
        implementation = self.registry.lookup(name)
        implementation.check(
            instance_text(label, name, (self.name, *objects)), len(objects), inputs
        )
        wrapper = Wrapper(
            self.name,
            label,
            name,
            objects,
            implementation,
            self._record,
            freq=freq,
            clock=self._now,
        )
        wrapper.injected = self.faults.get((name, self.name, *objects))
        if self.started_at is not None:  # joining a running robot: on its beat
            wrapper.schedule(
                self.rate,
                self.started_at,
                self.budget,
                self.stale_periods,
                max_value_bytes=self.max_value_bytes,
            )
            if wrapper.period is not None and self.now > self.started_at:
                beats = math.ceil((self.now - self.started_at) / wrapper.period - 1e-9)
                wrapper.next_due = self.started_at + beats * wrapper.period
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
        *,
        max_value_bytes: int = MAX_VALUE_BYTES,
    ) -> None:
        """Schedule every functionality from ``now`` and watch the partners;
        a value may be ``max_value_bytes`` of JSON (0: any), sent or received."""
        self.now = self.started_at = self._idle_next = now
        self.rate, self.budget, self.stale_periods = rate, budget, stale_periods
        self.max_value_bytes = max_value_bytes
        for w in self.wrappers:
            w.schedule(rate, now, budget, stale_periods, max_value_bytes=max_value_bytes)
        self._record(
            Lifecycle(
                robot=self.name,
                t=time.time(),
                what="start",
                info=(
                    ("transport", type(self.transport).__name__),
                    ("partners", self.partners),
                    ("rate", rate),
                    *(() if self.cost is None else (("cost", self.cost),)),
                ),
            )
        )
        self.transport.watch(self.name, self.partners, self._presence)

    def watch(self) -> None:
        """Watch the partners of the configuration now installed (after a switch)."""
        if self.started_at is not None:
            self.transport.watch(self.name, self.partners, self._presence)

    def release(self) -> None:
        """The society's run is over (its task accomplished): the others leave
        as they finish, which is no loss, so no robot is reported lost from now on."""
        self.released = True

    def due(self, now: float) -> bool:
        if not self.alive:
            return False
        if not self.wrappers:
            return self.rate <= 0 or now >= self._idle_next - 1e-9
        return any(w.due(now) for w in self.wrappers)

    def next_due(self) -> float | None:
        """When the next functionality is due (``None``: every cycle, no pause).
        A robot with nothing to run still ticks at its rate, so that its
        cycles, scripted faults and probes go on (a dead robot: never)."""
        if not self.alive:
            return math.inf
        if not self.wrappers:
            return None if self.rate <= 0 else self._idle_next
        times = [w.next_due for w in self.wrappers if w.period is not None]
        if len(times) < len(self.wrappers):
            return None
        return min(times)

    def step(self, now: float | None = None) -> None:
        """Run one cycle at ``now`` (default: the clock's time): the
        :attr:`before` hooks, then each functionality due then, in sorted order."""
        if self._cycle is None:
            raise RunError(f"robot {self.name} has no configuration to run")
        self.now = self.clock() if now is None else now
        for hook in list(self.before):
            hook(self)
        if not self.alive:
            return
        self.cycles += 1
        if not self.wrappers and self.rate > 0:
            period = 1.0 / self.rate
            self._idle_next += period
            if self._idle_next <= self.now:
                self._idle_next += (math.floor((self.now - self._idle_next) / period) + 1) * period
        self._cycle()

    def _now(self) -> float:
        return self.now

    def stop(self, reason: str) -> None:
        self._record(
            Lifecycle(robot=self.name, t=time.time(), what="stop", info=(("reason", reason),))
        )

    def _record(self, event: Event) -> Event:
        if not event.cycle:  # an event may name its cycle (a fault injected before it)
            event = replace(event, cycle=self.cycles)
        self.events.append(event)
        for listener in self.listeners:
            listener(event)
        return event

    def _receive(self, channel: Channel, payload: bytes) -> None:
        if oversized(payload, self.max_value_bytes):  # dropped unread: never parsed
            size, limit = len(payload), self.max_value_bytes
            self._record(
                Lifecycle(
                    robot=self.name,
                    t=time.time(),
                    what="error",
                    info=(
                        (
                            "message",
                            f"channel {channel.key}: a message of {size:,} bytes, over the "
                            f"limit of {limit:,} bytes (--max-value-bytes); dropped unread",
                        ),
                        ("channel", str(channel.key)),
                        ("bytes", size),
                        ("limit", limit),
                    ),
                )
            )
            return
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
        if self.released:
            return
        self._record(Presence(robot=self.name, t=time.time(), other=other, alive=alive))


Configure = Callable[[Robot], Cycle]
"""What emitted code provides: create a robot's channels and wrappers, return its cycle."""


def wired(robot: Robot, part: Part, channels: Sequence[Channel]) -> Cycle:
    """The cycle of ``part`` on ``robot``: its wrappers (made or found by
    label) called in sorted order with the given ``channels`` (CH-1 first)."""
    by_label = {w.label: w for w in robot.wrappers}
    calls = [
        (
            by_label[c.label],
            [_entry([channels[i] for i in x]) for x in c.inputs],
            [[channels[i] for i in x] for x in c.outputs],
        )
        for c in part.calls
    ]

    def cycle() -> None:
        for wrapper, inputs, outputs in calls:
            wrapper(inputs, outputs)

    return cycle


def _entry(channels: list[Channel]) -> Input:
    if not channels:
        return None
    return channels[0] if len(channels) == 1 else channels
