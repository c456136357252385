"""The monitor of 5.5: what makes a running configuration inadmissible, as it happens.

The thesis leaves monitoring undone ("a way to detect when a configuration
becomes inadmissible is adequate", 5.5). A :class:`Monitor` listens to a
robot's events (:meth:`cfgplan.runtime.Robot.subscribe`) and turns each of
the following into a :class:`Detection`, for the planning side
(:mod:`cfgplan.reconfigure`) to turn into a change of the state:

1. **failure** — a call failed because its resource did: the implementation
   raised :class:`~cfgplan.runtime.faults.ResourceFailure` (``reported``) or
   a scripted fault holds (``injected``);
2. **stale** — an input has not been refreshed for ``--stale-periods``
   periods of its sender: the *sending* functionality is suspected
   (``fresh`` withdraws the suspicion). The planning side blames a suspect
   only if its input stays stale for a while and nothing upstream of it is
   suspected too (staleness flows downstream);
3. **lost** / **seen** — a robot this one exchanges data with disappeared
   (its liveliness went, 5.2.2) or came back;
4. **facts** — the state changed: an operator's update (``retract`` /
   ``assert``), or **achieved**: an action said its task is accomplished
   (its configuration's postconditions become true).

A failed *sensing* resource is then *probed* on its robot (:class:`Prober`):
called now and then with its outputs discarded, and reported **recovery**
once it has worked for a *hold* time without a failure. Each failure of the
same resource doubles its hold (up to :data:`HOLD_MAX`): a flickering sensor
earns ever longer probation — one half of the hysteresis that keeps the
society from flapping (the other, a minimum gain, is the planning side's).
A failed computation or action cannot be exercised off-line: it comes back
only when a scripted fault on it is lifted.

Detections are plain data (:meth:`Detection.message` is JSON), so a robot
of its own process sends them to the coordinator over the network.
"""

from __future__ import annotations

import json
import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from typing import Literal, get_args

from cfgplan.notation import atom_text
from cfgplan.runtime.events import Adaptation, Call, Event, Presence, Staleness
from cfgplan.runtime.executor import Robot
from cfgplan.runtime.faults import term_text
from cfgplan.runtime.wire import is_number, loads, names, whole
from cfgplan.runtime.wrapper import Wrapper

__all__ = ["HOLD", "HOLD_MAX", "PROBE", "Detection", "Monitor", "Prober", "doubled_hold"]

HOLD = 1.0
"""Seconds a failed resource must work again before it counts as recovered."""

HOLD_MAX = 30.0
"""The hold doubles with each failure of the same resource, up to this."""


def doubled_hold(hold: float, failures: int) -> float:
    """The hold after the ``failures``-th failure of one resource: ``hold``,
    then doubled with each further failure, up to :data:`HOLD_MAX` (no flapping)."""
    return min(hold * 2.0 ** (failures - 1), HOLD_MAX)


PROBE = 0.2
"""Seconds between two probes of a failed sensing resource."""

Kind = Literal["failure", "recovery", "stale", "fresh", "lost", "seen", "facts", "achieved"]
Term = tuple[str, ...]


@dataclass(frozen=True)
class Detection:
    """One thing the monitor saw on ``robot`` at ``t`` (seconds since the epoch)."""

    kind: Kind
    robot: str
    t: float
    instance: Term = ()  # failure, recovery: the functionality instance
    label: str = ""  # failure, achieved: its label; stale, fresh: the sender's label
    other: str = ""  # lost, seen: that robot; stale, fresh: the sender's robot
    how: str = ""  # reported, injected, probe, operator, postconditions, retry
    detail: str = ""
    added: tuple[Term, ...] = ()  # facts
    removed: tuple[Term, ...] = ()  # facts
    limit: float = 0.0  # stale: seconds without data that made it stale
    config: int = -1
    """The configuration the reporting robot ran when it sent this (its id in
    the switch protocol, :mod:`cfgplan.runtime.member`); -1: seen where it is
    read. Robots' clocks may differ, so ``t`` cannot tell."""

    def message(self) -> bytes:
        """As JSON, to send to the coordinator."""
        return json.dumps(asdict(self), separators=(",", ":")).encode()

    @classmethod
    def read(cls, payload: bytes) -> Detection:
        """The inverse of :meth:`message` (``ValueError`` when it is not one).
        It comes from another process: every field is checked for the type
        :meth:`message` writes, so that one read cannot fail later, when the
        coordinator acts on it (after a switch, say)."""
        data = loads(payload)
        if not isinstance(data, dict):
            raise ValueError("not a detection")
        if data.get("kind") not in get_args(Kind):
            raise ValueError(f"not a kind of detection: {data.get('kind')!r}")
        for name in ("robot", "label", "other", "how", "detail"):
            if not isinstance(data.get(name, ""), str):
                raise ValueError(f"{name} of a detection is a string")
        for name in ("t", "limit"):
            value = data.get(name, 0.0)
            if not is_number(value) or not math.isfinite(value):
                raise ValueError(f"{name} of a detection is a finite number")
        whole(data.get("config", -1), "a configuration id")
        data["instance"] = names(data.get("instance", []))
        for name in ("added", "removed"):
            facts = data.get(name, [])
            if not isinstance(facts, list):
                raise ValueError(f"{name} of a detection is a list of facts")
            data[name] = tuple(names(f) for f in facts)
        try:
            return cls(**data)
        except TypeError as exc:
            raise ValueError(f"not a detection: {exc}") from None

    def describe(self) -> str:
        """What the console prints."""
        if self.kind in ("failure", "recovery"):
            how = f" ({self.how})" if self.how else ""
            return f"{self.kind} of {term_text(self.instance)}{how}"
        if self.kind in ("lost", "seen"):
            return f"robot {self.other} {self.kind}"
        if self.kind == "facts":
            shown = [f"+{atom_text(f)}" for f in self.added]
            shown += [f"-{atom_text(f)}" for f in self.removed]
            return f"state update ({self.how}): {' '.join(shown)}"
        return f"{self.kind} {self.label} on {self.other or self.robot}"


@dataclass
class _Probe:
    wrapper: Wrapper | None  # a sensing resource's wrapper, kept to call it
    how: str
    hold: float
    working_since: float | None = None
    last: float = 0.0
    reported: bool = False


class Prober:
    """Probes the failed resources of one robot (a :attr:`Robot.before` hook)."""

    def __init__(self, robot: Robot, report: Monitor, hold: float = HOLD, every: float = PROBE):
        self.robot = robot
        self.monitor = report
        self.hold = hold
        self.every = every
        self.failures: dict[Term, int] = {}  # how often each instance failed
        self.probes: dict[Term, _Probe] = {}
        robot.before.append(self)

    def failed(self, instance: Term, wrapper: Wrapper | None, how: str) -> None:
        """``instance`` failed: probe it (again), with a doubled hold."""
        count = self.failures.get(instance, 0) + 1
        self.failures[instance] = count
        self.probes[instance] = _Probe(wrapper, how, doubled_hold(self.hold, count))

    def __call__(self, robot: Robot) -> None:
        now = robot.now
        for instance, probe in list(self.probes.items()):
            if probe.reported or now - probe.last < self.every:
                continue
            probe.last = now
            works = self._works(instance, probe)
            if not works:
                probe.working_since = None
            elif probe.working_since is None:
                probe.working_since = now
            elif now - probe.working_since >= probe.hold:
                probe.reported = True
                self.monitor.detect(
                    Detection(
                        "recovery",
                        robot.name,
                        time.time(),
                        instance=instance,
                        how="probe" if probe.wrapper is not None else "injected",
                        detail=f"worked for {probe.hold:g} s",
                    )
                )
                del self.probes[instance]

    def _works(self, instance: Term, probe: _Probe) -> bool:
        if instance in self.robot.faults:
            return False
        if probe.wrapper is not None:
            probe.wrapper.injected = None  # a scripted fault, if any, was lifted
            return probe.wrapper.probe()
        return probe.how == "injected"  # a computation: back when its scripted fault is


@dataclass
class Monitor:
    """Watches one or more robots (a listener) and collects :class:`Detection` s."""

    hold: float = HOLD
    detections: deque[Detection] = field(default_factory=deque)
    probers: dict[str, Prober] = field(default_factory=dict)
    robots: dict[str, Robot] = field(default_factory=dict)
    _failed: set[Term] = field(default_factory=set)

    def watch(self, robot: Robot) -> None:
        """Listen to ``robot`` and probe its failed resources."""
        self.robots[robot.name] = robot
        self.probers[robot.name] = Prober(robot, self, self.hold)
        robot.subscribe(self)

    def presence(self, robot: str) -> Callable[[str, bool], None]:
        """A transport's presence listener: every robot of the society lost or
        back, as seen from ``robot`` (partners or not)."""

        def report(other: str, alive: bool) -> None:
            self.detect(Detection("seen" if alive else "lost", robot, time.time(), other=other))

        return report

    def detect(self, detection: Detection) -> None:
        if detection.kind == "recovery":
            self._failed.discard(detection.instance)
        self.detections.append(detection)

    def drain(self) -> list[Detection]:
        """The detections since the last drain, oldest first."""
        out = list(self.detections)
        self.detections.clear()
        return out

    def __call__(self, event: Event) -> None:
        if isinstance(event, Call):
            self._call(event)
        elif isinstance(event, Staleness):
            self.detect(
                Detection(
                    "stale" if event.state == "stale" else "fresh",
                    event.robot,
                    event.t,
                    label=event.channel.source,
                    other=event.source_robot,
                    detail=str(event.channel),
                    limit=event.limit,
                )
            )
        elif isinstance(event, Presence):
            self.detect(
                Detection(
                    "seen" if event.alive else "lost", event.robot, event.t, other=event.other
                )
            )
        elif isinstance(event, Adaptation) and event.what == "inject":
            self._injected(event)

    def _call(self, event: Call) -> None:
        if event.achieved:
            self.detect(Detection("achieved", event.robot, event.t, event.instance, event.label))
            return
        if not event.failure or event.instance in self._failed:
            return
        self._failed.add(event.instance)
        robot = self.robots.get(event.robot)
        wrapper = None
        if robot is not None and not event.inputs:  # a sensing resource: it can be probed
            wrapper = next((w for w in robot.wrappers if w.label == event.label), None)
        prober = self.probers.get(event.robot)
        if prober is not None:
            prober.failed(event.instance, wrapper, event.failure)
        self.detect(
            Detection(
                "failure",
                event.robot,
                event.t,
                instance=event.instance,
                label=event.label,
                how=event.failure,
                detail=event.error,
            )
        )

    def _injected(self, event: Adaptation) -> None:
        """A state update scripted with ``--inject`` (``assert``/``retract``)."""
        action, fact = event.field("action"), event.field("target")
        if action in ("assert", "retract") and isinstance(fact, tuple):
            self.detect(
                Detection(
                    "facts",
                    event.robot,
                    event.t,
                    how="operator",
                    added=(fact,) if action == "assert" else (),
                    removed=(fact,) if action == "retract" else (),
                )
            )
