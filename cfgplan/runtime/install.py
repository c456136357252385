"""Installing a robot's part of a configuration on the running robot, with the least disruption.

The thesis deploys a configuration by starting it (5.3) and, in 6.2.2 step 3,
its operator aborts the running one and starts the next from scratch. Here a
running robot switches in place (5.5, 7.2): :func:`install` compares the
part it runs with the new one and

* **keeps** every channel (same kind, ends, data and other robot) and every
  functionality (same label, name and arguments) present in both, *with
  their state*: a kept channel keeps its last value, whether it was read and
  when it was refreshed; a kept functionality keeps its schedule, its counts
  and its thread;
* **stops** the others: a stopped functionality's ``stop`` hook is called
  (an action halts), its thread ends; a stopped global channel is detached
  from the transport, so nothing more is delivered to it;
* **starts** what is new, scheduled from now;
* **re-wires** the cycle: the calls in the new sorted order, each with the
  channels of the new part (a kept functionality may get an input from a
  new channel — re-wired, not restarted).

Labels make this work across configurations: the planning side gives the new
configuration the running labels for the instances both share
(:func:`cfgplan.reconfigure.switch.relabel`). Installing the part a robot
already runs changes nothing; installing an empty part stops everything
(the safe stop of 5.5), and the robot idles at its rate.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

from cfgplan.notation import instance_text
from cfgplan.runtime.channel import Channel
from cfgplan.runtime.executor import Robot, wired
from cfgplan.runtime.part import ChannelSpec, Part
from cfgplan.runtime.registry import Registry
from cfgplan.runtime.transport import Transport

__all__ = ["Installed", "build", "crash", "install"]

ChannelIdentity = tuple[str, str, str, tuple[str, ...], str | None]


def _identity(ch: Channel) -> ChannelIdentity:
    other = ch.other if ch.kind == "global" else None
    return (ch.kind, ch.source, ch.target, ch.data, other)


def _spec_identity(spec: ChannelSpec) -> ChannelIdentity:
    return (spec.kind, spec.source, spec.target, spec.data, spec.other)


@dataclass(frozen=True)
class Installed:
    """What :func:`install` kept, stopped and started on one robot (wrappers as
    ``F3: cross-door(Emil, Door1)``, channels as ``F7->F3 (pos Emil Door1)``),
    and what went wrong in stop hooks."""

    kept: tuple[str, ...] = ()
    stopped: tuple[str, ...] = ()
    started: tuple[str, ...] = ()
    kept_channels: tuple[str, ...] = ()
    stopped_channels: tuple[str, ...] = ()
    started_channels: tuple[str, ...] = ()
    problems: tuple[str, ...] = ()

    @property
    def changed(self) -> bool:
        return bool(self.stopped or self.started or self.stopped_channels or self.started_channels)

    def record(self) -> tuple[tuple[str, object], ...]:
        """The fields of an ``install`` trace event."""
        return (
            ("kept", list(self.kept)),
            ("stopped", list(self.stopped)),
            ("started", list(self.started)),
            ("kept_channels", len(self.kept_channels)),
            ("stopped_channels", list(self.stopped_channels)),
            ("started_channels", list(self.started_channels)),
            *((("problems", list(self.problems)),) if self.problems else ()),
        )


def runnable(robot: Robot, part: Part) -> None:
    """Refuse a part ``robot`` cannot run, before anything changes: a part of
    another robot (``ValueError``), a functionality without implementation,
    or one whose implementation cannot take its arguments
    (:class:`~cfgplan.runtime.errors.RunError`). What :func:`install` checks,
    so that a robot that answered a prepare ``ready`` installs at commit."""
    if part.robot != robot.name:
        raise ValueError(f"a part of {part.robot}, not of {robot.name}")
    registry = robot.registry
    registry.require(c.name for c in part.calls)
    for call in part.calls:
        registry.lookup(call.name).check(
            instance_text(call.label, call.name, (robot.name, *call.objects)),
            len(call.objects),
            len(call.inputs),
        )


def build(
    part: Part,
    registry: Registry,
    transport: Transport | None = None,
    *,
    clock: Callable[[], float] = time.monotonic,
) -> Robot:
    """A robot configured from its part of a configuration (the same as its
    emitted module), on ``clock``: a new robot, its part installed. Here, not
    in :mod:`cfgplan.runtime.executor`, which knows nothing of installing: the
    robot is the lower layer, installing (and switching) is built on it."""
    robot = Robot(part.robot, registry, transport, clock=clock, cost=part.cost)
    install(robot, part)
    return robot


def install(robot: Robot, part: Part) -> Installed:
    """Make ``robot`` run ``part``, keeping what both share (module docstring);
    a part it cannot run (:func:`runnable`) is refused before anything changes."""
    runnable(robot, part)
    partners = robot.partners
    old_channels = {_identity(c): c for c in robot.channels}
    wanted = {_spec_identity(spec) for spec in part.channels}
    # The ends that go are detached first: a new channel may have the key of
    # one that goes (its other end moved to another robot).
    gone = {identity: c for identity, c in old_channels.items() if identity not in wanted}
    staying = {identity: c for identity, c in old_channels.items() if identity in wanted}
    for channel in gone.values():
        if channel.remote:
            robot.transport.detach(robot.name, channel.key)
    channels: list[Channel] = []
    started_channels: list[str] = []
    robot.channels = []
    for spec in part.channels:
        found = staying.pop(_spec_identity(spec), None)
        if found is None:
            found = (
                robot.local_channel(spec.source, spec.target, spec.data)
                if spec.other is None
                else robot.global_channel(spec.other, spec.source, spec.target, spec.data)
            )
            started_channels.append(found.id)
        channels.append(found)
    robot.channels = channels

    old_wrappers = {(w.label, w.name, w.objects): w for w in robot.wrappers}
    wrappers = []
    kept: list[str] = []
    started: list[str] = []
    robot.wrappers = []
    for call in part.calls:
        wrapper = old_wrappers.pop((call.label, call.name, call.objects), None)
        if wrapper is None:
            wrapper = robot.wrapper(
                call.label, call.name, call.objects, freq=call.freq, inputs=len(call.inputs)
            )
            started.append(str(wrapper))
        else:
            kept.append(str(wrapper))
        wrappers.append(wrapper)
    problems = []
    for stopped in old_wrappers.values():
        robot.retired.append(stopped)
        problem = stopped.stop()
        if problem is not None:
            problems.append(f"{stopped}: {problem}")
    robot.wrappers = wrappers
    robot.configure(lambda r: wired(r, part, channels))
    if robot.partners != partners:
        robot.watch()
    return Installed(
        kept=tuple(kept),
        stopped=tuple(str(w) for w in old_wrappers.values()),
        started=tuple(started),
        kept_channels=tuple(c.id for c in channels if c.id not in started_channels),
        stopped_channels=tuple(c.id for c in gone.values()),
        started_channels=tuple(started_channels),
        problems=tuple(problems),
    )


def crash(robot: Robot) -> None:
    """``robot`` lost everything at once (its process died): no stop hooks,
    its global channels detached; it comes back empty (:meth:`Society.revive`)."""
    for channel in robot.channels:
        if channel.remote:
            robot.transport.detach(robot.name, channel.key)
    for wrapper in robot.wrappers:
        wrapper.stopped = True
        robot.retired.append(wrapper)
    robot.channels, robot.wrappers = [], []
    robot.configure(lambda r: lambda: None)
