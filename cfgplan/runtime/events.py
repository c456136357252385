"""What a running robot did: one event per call, message, change of staleness or presence.

Every event has the robot it happened on, the robot's cycle and ``t``, the
time in seconds since the epoch, and turns into one JSON object with
:meth:`Event.record` — a line of ``--trace FILE`` (the schema is
:mod:`cfgplan.runtime.schema`). Events reach whoever subscribed to the robot
(:meth:`cfgplan.runtime.Robot.subscribe`) as they happen: the console
printer, the trace file and, later, a monitor (5.5).

* :class:`Call` — a wrapper call of 5.2.1 and its outcome (``status``);
* :class:`Transfer` — a message sent or received on a global channel (5.2.2);
* :class:`Staleness` — an input that has not been refreshed for too long
  (``stale``), or is again (``fresh``), judged by its sender's period (3.2);
* :class:`Presence` — another robot appeared (``robot-seen``) or was lost
  (``robot-lost``);
* :class:`Lifecycle` — the robot started or stopped, or a message could not
  be read (``start``, ``stop``, ``error``);
* :class:`Adaptation` — monitoring and reconfiguration (5.5): faults
  injected, failures and recoveries detected, state changes, switches,
  installs, and the safe stop when nothing is admissible.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from cfgplan.runtime.transport import ChannelKey
from cfgplan.runtime.values import jsonable

__all__ = [
    "STORY_KINDS",
    "Adaptation",
    "Call",
    "Data",
    "Event",
    "Lifecycle",
    "Presence",
    "Staleness",
    "Status",
    "Transfer",
]

Data = tuple[str, ...]
"""An instantiated data descriptor, e.g. ``("pos", "Pippi", "Door1")``."""

Status = Literal["ran", "waiting", "precondition", "stale", "error", "timeout", "busy"]
"""What a wrapper call did: ran the function; waited for fresh input; found
the precondition false; refused stale input; the function failed (raised,
exited, returned what cannot be written); it overran its time budget; it is
still running since an earlier call overran."""


@dataclass(frozen=True, slots=True, kw_only=True)
class Event:
    """What every event has."""

    robot: str
    cycle: int = 0
    t: float = 0.0

    @property
    def kind(self) -> str:
        raise NotImplementedError

    def record(self) -> dict[str, object]:
        """The trace line of this event, as a JSON-ready dict."""
        return {"event": self.kind, "robot": self.robot, "t": self.t, "cycle": self.cycle}


def _pairs(pairs: tuple[tuple[Data, object], ...]) -> list[dict[str, object]]:
    return [{"data": list(d), "value": jsonable(v)} for d, v in pairs]


@dataclass(frozen=True, slots=True, kw_only=True)
class Call(Event):
    """One call of a wrapper (5.2.1).

    ``inputs`` pairs each input's descriptor with the value read (``ran``);
    ``waiting`` lists the descriptors without fresh data, ``stale`` those
    whose data is too old; ``outputs`` pairs each output's descriptor with
    the value written (``None``: not written); ``error`` says what failed.
    ``failure`` is set when the call failed because the resource did
    (``reported``: the implementation raised
    :class:`~cfgplan.runtime.faults.ResourceFailure`; ``injected``: a
    scripted fault); ``achieved`` when an action said its task is done.
    """

    label: str
    name: str
    args: tuple[str, ...]
    status: Status
    inputs: tuple[tuple[Data, object], ...] = ()
    waiting: tuple[Data, ...] = ()
    stale: tuple[Data, ...] = ()
    outputs: tuple[tuple[Data, object], ...] = ()
    action: bool = False
    error: str = ""
    duration: float | None = None
    failure: Literal["", "reported", "injected"] = ""
    achieved: bool = False

    @property
    def kind(self) -> str:
        return "call"

    @property
    def instance(self) -> tuple[str, ...]:
        """The functionality instance, e.g. ``("compass", "Emil")``."""
        return (self.name, *self.args)

    def record(self) -> dict[str, object]:
        out = Event.record(self)
        out.update(
            label=self.label,
            functionality=self.name,
            args=list(self.args),
            status=self.status,
            inputs=_pairs(self.inputs),
            outputs=_pairs(self.outputs),
        )
        if self.waiting:
            out["waiting"] = [list(d) for d in self.waiting]
        if self.stale:
            out["stale"] = [list(d) for d in self.stale]
        if self.error:
            out["error"] = self.error
        if self.duration is not None:
            out["duration"] = self.duration
        if self.failure:
            out["failure"] = self.failure
        if self.achieved:
            out["achieved"] = True
        return out


@dataclass(frozen=True, slots=True, kw_only=True)
class Transfer(Event):
    """A message on a global channel: ``send`` to ``other``, or ``receive`` from it."""

    direction: Literal["send", "receive"]
    channel: ChannelKey
    other: str
    value: object
    seq: int
    sent: float | None = None  # receive: the sender's clock

    @property
    def kind(self) -> str:
        return self.direction

    def record(self) -> dict[str, object]:
        out = Event.record(self)
        out.update(channel=str(self.channel), data=list(self.channel.data), seq=self.seq)
        out["to" if self.direction == "send" else "from"] = self.other
        out["value"] = jsonable(self.value)
        if self.sent is not None:
            out["sent"] = self.sent
        return out


@dataclass(frozen=True, slots=True, kw_only=True)
class Staleness(Event):
    """Input ``channel`` of functionality ``label`` went ``stale`` (no new data
    for ``age`` seconds, over ``limit`` = periods x the sender's ``period``),
    or is ``fresh`` again."""

    state: Literal["stale", "fresh"]
    label: str
    channel: ChannelKey
    source_robot: str
    age: float
    period: float
    limit: float

    @property
    def kind(self) -> str:
        return self.state

    def record(self) -> dict[str, object]:
        out = Event.record(self)
        out.update(
            label=self.label,
            channel=str(self.channel),
            data=list(self.channel.data),
            **{"from": self.source_robot},
            age=round(self.age, 6),
            period=round(self.period, 6),
            limit=round(self.limit, 6),
        )
        return out


@dataclass(frozen=True, slots=True, kw_only=True)
class Presence(Event):
    """A robot this one exchanges data with appeared, or was lost."""

    other: str
    alive: bool

    @property
    def kind(self) -> str:
        return "robot-seen" if self.alive else "robot-lost"

    def record(self) -> dict[str, object]:
        out = Event.record(self)
        out["other"] = self.other
        return out


@dataclass(frozen=True, slots=True, kw_only=True)
class Lifecycle(Event):
    """``start`` (``info``: transport, society, partners, rate), ``stop``
    (``info``: why), or ``error`` (``info``: a message that could not be read;
    on the coordinator also a helper's failed call,
    :class:`~cfgplan.runtime.protocol.CallError`)."""

    what: Literal["start", "stop", "error"]
    info: tuple[tuple[str, object], ...] = ()

    @property
    def kind(self) -> str:
        return self.what

    def record(self) -> dict[str, object]:
        out = Event.record(self)
        out.update({k: jsonable(v) for k, v in self.info})
        return out


STORY_KINDS = (
    "inject",
    "failure",
    "recovery",
    "facts",
    "switch",
    "no-configuration",
    "abort",
    "achieved",
)
"""The adaptations a run's story tells, in no particular order: what a
simulation's recording keeps (:mod:`cfgplan.sim.record`) and the live
page's timeline shows (:mod:`cfgplan.live.model`); ``install`` is told
apart, by who installed."""


@dataclass(frozen=True, slots=True, kw_only=True)
class Adaptation(Event):
    """A step of monitoring and reconfiguration (5.5), on the robot that saw
    or did it: ``what`` is the trace event's name and ``info`` its fields.

    * ``inject`` — a scripted fault took effect (``spec``);
    * ``failure`` — a resource failed (``resource``, ``kind``, ``how``:
      ``reported``, ``injected``, ``stale``, ``lost``; ``detail``; on the
      coordinator also ``withdrawn``, the facts the failure takes away);
    * ``recovery`` — a resource works again (``resource``, ``kind``, ``how``);
    * ``facts`` — the state changed (``added``, ``removed``, ``how``);
    * ``switch`` — the society switched configurations (``id``, ``from_cost``,
      ``to_cost``, ``kept``, ``stopped``, ``started``, ``latency``, ...);
    * ``no-configuration`` — nothing admissible is left: the action is
      stopped safely (``why``: the planner's explanation);
    * ``install`` — this robot installed its part of configuration ``id``;
    * ``achieved`` — an action said its task is accomplished;
    * ``takeover`` — this robot coordinates from now on, its coordinator
      gone (``epoch``, ``after``, ``step``, ``goal``, ``waited``);
    * ``step-down`` — this coordinator follows the one that took over
      (``leader``, ``epoch``, ``was``).
    """

    what: str
    info: tuple[tuple[str, object], ...] = ()

    @property
    def kind(self) -> str:
        return self.what

    def field(self, name: str) -> object:
        """The value of field ``name`` (``None`` when absent)."""
        return dict(self.info).get(name)

    def record(self) -> dict[str, object]:
        out = Event.record(self)
        out.update({k: jsonable(v) for k, v in self.info})
        return out
