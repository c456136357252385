"""Running individual configurations (chapter 5): robots, cycles and societies.

A :class:`Robot` is one robot's executable configuration: the channels it
creates (the ``LET`` of 5.3) and a *cycle* that calls the wrappers of its
functionalities in sorted order (the ``LAMBDA``). It is configured either by
the code ``cfgplan emit --lang python`` writes (a ``configure(robot)``
function) or straight from a deployed configuration by :func:`build`.

A :class:`Society` runs several robots in one process, one cycle of each in
turn, their global channels joined by one
:class:`~cfgplan.runtime.transport.InProcessTransport`.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
import time
import traceback
from collections.abc import Callable, Sequence
from dataclasses import replace

from cfgplan.backends.wiring import RobotPart
from cfgplan.diagnostics import CfgplanError, error
from cfgplan.runtime.channel import Channel, make_global_channel, make_local_channel
from cfgplan.runtime.registry import Registry
from cfgplan.runtime.trace import describe, summary
from cfgplan.runtime.transport import InProcessTransport, Transport
from cfgplan.runtime.wrapper import Event, Input, Wrapper

__all__ = [
    "Configure",
    "Cycle",
    "Robot",
    "Society",
    "assemble",
    "build",
    "robot_main",
    "society",
    "society_main",
]

Cycle = Callable[[], None]
"""One pass over a robot's functionalities (the LAMBDA of 5.3)."""


class Robot:
    """One robot's executable configuration."""

    def __init__(self, name: str, registry: Registry, transport: Transport | None = None) -> None:
        self.name = name
        self.registry = registry
        self.transport: Transport = transport if transport is not None else InProcessTransport()
        self.channels: list[Channel] = []
        self.wrappers: list[Wrapper] = []
        self.events: list[Event] = []
        self.cycles = 0
        self.on_event: Callable[[Event], None] | None = None
        self._cycle: Cycle | None = None

    def local_channel(self, source: str, target: str, data: Sequence[str]) -> Channel:
        """``(make-local-channel 'ROBOT 'SRC 'DST '(data ...))`` on this robot."""
        channel = make_local_channel(self.name, source, target, data)
        self.channels.append(channel)
        return channel

    def global_channel(self, other: str, source: str, target: str, data: Sequence[str]) -> Channel:
        """``(make-global-channel 'OTHER 'SRC 'DST '(data ...))``: this robot's end."""
        channel = make_global_channel(
            other, source, target, data, robot=self.name, transport=self.transport
        )
        self.channels.append(channel)
        return channel

    def wrapper(self, label: str, name: str, objects: Sequence[str] = ()) -> Wrapper:
        """The wrapper of functionality ``label``; fails at once if ``name`` has
        no implementation."""
        wrapper = Wrapper(self.name, label, name, objects, self.registry.lookup(name), self._record)
        self.wrappers.append(wrapper)
        return wrapper

    def configure(self, configure: Configure) -> Robot:
        """Create the channels and wrappers; ``configure`` returns the cycle."""
        self._cycle = configure(self)
        return self

    def step(self) -> None:
        """Run one cycle."""
        if self._cycle is None:
            raise error(f"robot {self.name} has no configuration to run")
        self.cycles += 1
        self._cycle()

    def _record(self, event: Event) -> Event:
        event = replace(event, cycle=self.cycles)
        self.events.append(event)
        if self.on_event is not None:
            self.on_event(event)
        return event


Configure = Callable[[Robot], Cycle]
"""What emitted code provides: create a robot's channels and wrappers, return its cycle."""


def build(part: RobotPart, registry: Registry, transport: Transport | None = None) -> Robot:
    """A robot configured straight from its part of a deployed configuration."""
    robot = Robot(part.robot, registry, transport)

    def configure(robot: Robot) -> Cycle:
        channels = []
        for ch in part.individual.channels:
            if ch.kind == "local":
                channels.append(robot.local_channel(ch.source, ch.target, ch.data))
            else:
                other = ch.target_robot if ch.source_robot == robot.name else ch.source_robot
                channels.append(robot.global_channel(other, ch.source, ch.target, ch.data))
        calls = [
            (
                robot.wrapper(c.functionality.label, c.functionality.name, c.objects),
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
    """Robots run in one process, a cycle of each in turn."""

    def __init__(
        self, robots: Sequence[Robot], transport: InProcessTransport | None = None
    ) -> None:
        self.robots = list(robots)
        self.transport = transport  # the one joining them, when they share one

    def run(self, cycles: int, rate: float = 0.0) -> None:
        """``cycles`` cycles (0: until interrupted), ``rate`` per second (0: no pause)."""
        done = 0
        while cycles == 0 or done < cycles:
            started = time.monotonic()
            for robot in self.robots:
                robot.step()
            done += 1
            if rate > 0:
                time.sleep(max(0.0, 1.0 / rate - (time.monotonic() - started)))

    @property
    def events(self) -> list[Event]:
        """Every event in the order it happened."""
        merged = [e for r in self.robots for e in r.events]
        index = {r.name: i for i, r in enumerate(self.robots)}
        return sorted(merged, key=lambda e: (e.cycle, index[e.robot]))


def society(parts: Sequence[RobotPart], registry: Registry) -> Society:
    """Every robot of a deployed configuration, joined in process."""
    registry.require(c.functionality.name for p in parts for c in p.calls)
    transport = InProcessTransport()
    return Society([build(p, registry, transport) for p in parts], transport)


def assemble(programs: Sequence[tuple[str, Configure]], registry: Registry) -> Society:
    """Robots configured by emitted code (name, configure), joined in process."""
    transport = InProcessTransport()
    robots = [Robot(name, registry, transport).configure(c) for name, c in programs]
    return Society(robots, transport)


# --- the command line of emitted code -------------------------------------------------------


def _arguments(description: str, argv: Sequence[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument(
        "--impl",
        required=True,
        help="where the implementations come from: a module name (pkg.impl) or a .py file",
    )
    parser.add_argument(
        "--cycles", type=int, default=0, help="how many cycles (default 0: until interrupted)"
    )
    parser.add_argument(
        "--rate", type=float, default=10.0, help="cycles per second (default 10; 0: no pause)"
    )
    parser.add_argument(
        "--trace", action="store_true", help="print every call, not only what actions received"
    )
    return parser.parse_args(argv)


def robot_main(name: str, configure: Configure, argv: Sequence[str] | None = None) -> int:
    """``python emil.py``: run one robot; its global channels reach no other robot
    (the in-process transport only joins robots of one process)."""
    args = _arguments(f"Run {name}'s part of a configuration (cfgplan, thesis 5.3).", argv)
    return _main([(name, configure)], args)


def society_main(
    programs: Sequence[tuple[str, Configure]], argv: Sequence[str] | None = None
) -> int:
    """``python run_all.py``: run every robot in this process."""
    names = ", ".join(name for name, _ in programs)
    args = _arguments(f"Run {names} in one process (cfgplan, thesis 5.3).", argv)
    return _main(programs, args)


def _main(programs: Sequence[tuple[str, Configure]], args: argparse.Namespace) -> int:
    try:
        running = assemble(programs, Registry.load(args.impl))
        for robot in running.robots:
            robot.on_event = lambda e: _print_event(e, args.trace)
        with contextlib.suppress(KeyboardInterrupt):
            running.run(args.cycles, args.rate)
    except CfgplanError as exc:
        if exc.__cause__ is not None:
            traceback.print_exception(exc.__cause__)
        print(f"error: {exc}", file=sys.stderr)
        return 1
    for line in summary(running.events):
        print(line)
    if running.transport is not None and running.transport.undelivered:
        print(
            f"note: {running.transport.undelivered} value(s) sent to robots not in this "
            "process were dropped (the in-process transport joins only robots run together)",
            file=sys.stderr,
        )
    return 0


def _print_event(event: Event, trace: bool) -> None:
    if trace or (event.action and event.status == "ran"):
        print(describe(event), flush=True)
