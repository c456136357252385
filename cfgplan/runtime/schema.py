"""The lines of ``cfgplan run --trace FILE``, as models: one JSON object per event.

The events themselves are :mod:`cfgplan.runtime.events` (their
:meth:`~cfgplan.runtime.events.Event.record` writes the line); these pydantic
models describe the lines for the documentation (their JSON Schema is the
reference page "Trace events") and for the tests, which validate the trace of a
real run, reconfiguration included, against them: every model forbids keys it
does not name, so neither can drift from the other. The runtime never imports
this module (a robot runs without pydantic).

Calls are the wrapper calls of 5.2.1, ``send``/``receive`` the global channels
of 5.2.2, staleness is judged by the sender's period (3.2), and the
reconfiguration events are monitoring and reconfiguration (5.5, 7.2).
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, JsonValue, TypeAdapter

from cfgplan.documents import Closed, Number
from cfgplan.runtime.faults import Action

__all__ = [
    "TRACE_EVENT",
    "Abort",
    "Achieved",
    "CallEvent",
    "Facts",
    "Failure",
    "Finish",
    "Inject",
    "InstallEvent",
    "Message",
    "NoConfiguration",
    "Presence",
    "Receive",
    "Recovery",
    "Send",
    "Staleness",
    "Start",
    "StepDown",
    "Stop",
    "SwitchEvent",
    "Takeover",
    "TraceEvent",
]

Data = list[str]
"""A data descriptor, e.g. ``["pos", "Pippi", "Door1"]``."""


class Base(Closed):
    """What every line has."""

    robot: str = Field(description="The robot it happened on.")
    t: float = Field(description="Seconds since the epoch (simulated time in a simulation).")
    cycle: int = Field(description="The robot's cycle.")


class Value(Closed):
    """A value read or written on a channel (not JSON: `{"$type", "$repr"}`)."""

    data: Data
    value: JsonValue = Field(description="`null` for an output not written.")


class CallEvent(Base):
    """A call of a wrapper (5.2.1) and its outcome."""

    event: Literal["call"]
    label: str
    functionality: str
    args: list[str]
    status: Literal["ran", "waiting", "precondition", "stale", "error", "timeout", "busy"]
    inputs: list[Value]
    outputs: list[Value]
    waiting: list[Data] | None = Field(default=None, description="Inputs without fresh data.")
    stale: list[Data] | None = Field(default=None, description="Inputs whose data is too old.")
    error: str | None = Field(default=None, description="What failed.")
    duration: float | None = Field(default=None, description="Seconds the function took.")
    failure: Literal["reported", "injected"] | None = Field(
        default=None,
        description="When its resource failed: raised by the implementation, or a scripted fault.",
    )
    achieved: Literal[True] | None = Field(
        default=None, description="An action said its task is accomplished."
    )


class Send(Base):
    """A message sent on a global channel (5.2.2)."""

    event: Literal["send"]
    channel: str = Field(description='e.g. `"F7->F3 (pos Pippi Door1)"`.')
    data: Data
    seq: int
    to: str = Field(description="The other robot.")
    value: JsonValue


class Receive(Base):
    """A message received on a global channel (5.2.2)."""

    event: Literal["receive"]
    channel: str
    data: Data
    seq: int
    from_: str = Field(alias="from", description="The other robot.")
    value: JsonValue
    sent: float | None = Field(default=None, description="The sender's `t`.")


class Staleness(Base):
    """An input not refreshed for too long, or fresh again (3.2)."""

    event: Literal["stale", "fresh"]
    label: str = Field(description="The receiving functionality.")
    channel: str
    data: Data
    from_: str = Field(alias="from", description="The sending robot.")
    age: float = Field(description="Seconds since the last refresh.")
    period: float = Field(description="The sender's period.")
    limit: float


class Presence(Base):
    """Another robot appeared or was lost."""

    event: Literal["robot-seen", "robot-lost"]
    other: str


class Start(Base):
    """The robot started."""

    event: Literal["start"]
    transport: str
    partners: list[str] = Field(description="The robots it exchanges data with.")
    rate: float
    cost: Number | None = Field(
        default=None,
        description="The cost of the configuration it starts with (`cfgplan run`, "
        "`cfgplan launch`, `cfgplan simulate`; not the emitted programs, which do not know it).",
    )


class Stop(Base):
    """The robot stopped."""

    event: Literal["stop"]
    reason: str = Field(
        description="`cycles`, `duration`, `terminated` (SIGTERM), `interrupted` (Ctrl-C), "
        "`stopped` (from a program), `achieved` (the task is done), `killed` (a scripted kill)."
    )


class Message(Base):
    """A message that could not be read, or, on the coordinator, what a helper's
    functionality said when its call failed (the switch protocol's `call-error`)."""

    event: Literal["error"]
    message: str
    channel: str | None = Field(
        default=None, description="A message over the value limit: the channel it came on."
    )
    bytes: int | None = Field(default=None, description="Its size, never read.")
    limit: int | None = Field(default=None, description="The limit (`--max-value-bytes`).")


class Inject(Base):
    """A scripted fault took effect (``--inject``)."""

    event: Literal["inject"]
    spec: str = Field(description="The fault as written, e.g. `fail compass(Emil) at cycle 20`.")
    action: Action
    target: list[str] = Field(
        description="A functionality instance (`[compass, Emil]`), a robot (`[Emil]`) or a fact."
    )


ResourceKind = Literal["functionality", "robot", "medium"]


class Failure(Base):
    """A resource failed (5.5)."""

    event: Literal["failure"]
    detected_by: str = Field(description="The robot that saw it.")
    resource: str = Field(description="`compass(Emil)` or a robot.")
    kind: ResourceKind
    how: str = Field(description="`reported`, `injected`, `stale`, `lost`, `refused` or `silent`.")
    detail: str
    withdrawn: list[str] = Field(
        description="The facts taken from the state (robots lost together: all on the first)."
    )


class Recovery(Base):
    """A resource works again."""

    event: Literal["recovery"]
    detected_by: str
    resource: str
    kind: ResourceKind
    how: str = Field(description="`probe`, `injected`, `seen` or `retry`.")


class Facts(Base):
    """The state changed."""

    event: Literal["facts"]
    detected_by: str
    added: list[str]
    removed: list[str]
    how: str = Field(description="e.g. `operator`.")


class Achieved(Base):
    """An action said its task is accomplished."""

    event: Literal["achieved"]
    detected_by: str
    label: str
    functionality: str


class Finish(Base):
    """The run ends across processes, the task accomplished: on a member robot,
    the coordinator told it (``from``); on the coordinator, every robot was told
    and answered, or did not in time (``silent``)."""

    event: Literal["finish"]
    id: int
    from_: str | None = Field(default=None, alias="from", description="The coordinator.")
    goal: str | None = Field(default=None, description="The goal accomplished.")
    silent: list[str] | None = Field(
        default=None, description="On the coordinator: robots that did not answer the finish."
    )


class Part(Closed):
    """Functionality instances (``F3: cross-door(Emil, Door1)``) and channels
    (``F7->F3 pos(Emil, Door1)``)."""

    functionalities: list[str]
    channels: list[str]


class SwitchEvent(Base):
    """The society switched configurations (5.5, 7.2)."""

    event: Literal["switch"]
    id: int
    cause: str
    from_cost: Number | None
    to_cost: Number
    source: Literal["fallback", "search"]
    plan_ms: float | None = Field(
        default=None, description="Milliseconds of planning (left out in a simulation's trace)."
    )
    latency: float | None = Field(
        default=None,
        description="Seconds from the detection to the new configuration installed everywhere "
        "(left out in a simulation's trace: it measures the host's clock).",
    )
    kept: Part
    stopped: Part
    started: Part


class NoConfiguration(Base):
    """Nothing admissible is left: the action is stopped safely."""

    event: Literal["no-configuration"]
    id: int
    cause: str
    from_cost: Number | None
    stopped: list[str] = Field(description="The functionalities stopped.")
    why: list[str] = Field(description="The planner's explanation, line by line.")
    latency: float | None = Field(default=None, description="Left out in a simulation's trace.")


class Takeover(Base):
    """This robot coordinates from now on: the coordinator it followed is gone,
    and it is the first robot of the order of succession still alive."""

    event: Literal["takeover"]
    epoch: str = Field(description="Its run: one generation later than the one it followed.")
    after: str = Field(description="The coordinator gone.")
    step: int = Field(description="The step of the sequence it goes on from (0: the first).")
    goal: str = Field(description="That step's goal.")
    waited: float = Field(description="Seconds from the coordinator's token going to now.")
    added: list[str] = Field(
        default_factory=list,
        description="Facts the society had added to the state when it last committed "
        "(the operator's, the postconditions of the steps accomplished), which it plans with.",
    )
    removed: list[str] = Field(
        default_factory=list, description="Facts it had removed from the state, as `added`."
    )
    failed: list[str] = Field(
        default_factory=list,
        description="Functionality instances out of service when it last committed.",
    )


class StepDown(Base):
    """This coordinator follows another from now on: a robot told it that it
    follows a run of a later generation, whose robot is alive and next in
    the order of succession (it took over while this one stood still)."""

    event: Literal["step-down"]
    leader: str = Field(description="The coordinator followed now.")
    epoch: str = Field(description="Its run.")
    was: str = Field(description="This robot's own run, fenced off.")


class Abort(Base):
    """A switch abandoned: robots refused or stayed silent."""

    event: Literal["abort"]
    id: int
    robots: list[str]
    reason: str


class InstallEvent(Base):
    """This robot installed its part of configuration ``id``."""

    event: Literal["install"]
    id: int
    kept: list[str]
    stopped: list[str]
    started: list[str]
    kept_channels: int = Field(description="A count.")
    stopped_channels: list[str]
    started_channels: list[str]
    epoch: str | None = Field(
        default=None,
        description="Across processes: the coordinator's run whose switch this was "
        "(absent when one process runs every robot).",
    )
    leader: str | None = Field(
        default=None,
        description="Across processes: the robot that coordinates that run (absent when "
        "one process runs every robot).",
    )
    problems: list[str] | None = Field(
        default=None,
        description="Stop hooks that raised or overran the call budget (`F11: compass(Pippi): "
        "its stop hook took longer ...`); absent when none did.",
    )


TraceEvent = Annotated[
    CallEvent
    | Send
    | Receive
    | Staleness
    | Presence
    | Start
    | Stop
    | Message
    | Inject
    | Failure
    | Recovery
    | Facts
    | Achieved
    | Finish
    | SwitchEvent
    | NoConfiguration
    | Abort
    | InstallEvent
    | Takeover
    | StepDown,
    Field(discriminator="event"),
]
"""One line of the trace, told apart by ``"event"``."""

TRACE_EVENT: TypeAdapter[TraceEvent] = TypeAdapter(TraceEvent)
"""Validates a line (``TRACE_EVENT.validate_json(line)``) and gives the schema."""
