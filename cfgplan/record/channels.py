"""The channels and schemas of a recorded or served run: one definition.

A trace line (:mod:`cfgplan.runtime.schema`) is one message, its JSON bytes as
they are (message encoding ``json``), on the topic of its kind of event
(:data:`TOPICS`): a robot's wrapper calls (5.2.1), the values it sent or
received on each global channel (5.2.2), its stale and fresh inputs (3.2);
the society's presence, failures, recoveries and switches (5.5, 7.2). Each
topic's schema is the JSON Schema of the pydantic model of that kind (schema
encoding ``jsonschema``). A message's log time is the event's ``t`` in
nanoseconds; its publish time the same, but for a received value, the
sender's ``t``.

Three writers use this module and nothing else to name channels and schemas:
``cfgplan record`` (:mod:`~cfgplan.record.mcap_export`, a trace afterwards),
``--record FILE.mcap`` (:mod:`~cfgplan.record.live`, as the run goes) and
``--foxglove`` (:mod:`~cfgplan.record.foxglove_live`, served live). It
imports neither ``mcap`` nor ``foxglove``.
"""

from __future__ import annotations

import functools
import json
import math
import unicodedata
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any, Protocol

from pydantic import BaseModel

from cfgplan import __version__
from cfgplan.runtime import schema as s

__all__ = [
    "MESSAGE_ENCODING",
    "SCHEMA_ENCODING",
    "TOPICS",
    "Entry",
    "Registrar",
    "entry_of",
    "nanoseconds",
    "run_metadata",
    "schema_name",
    "schema_of",
    "segment",
]

SCHEMA_ENCODING = "jsonschema"
MESSAGE_ENCODING = "json"

TOPICS: dict[type[BaseModel], str] = {
    s.CallEvent: "/cfgplan/{robot}/calls",
    s.Send: "/cfgplan/{robot}/channels/{channel}/sent",
    s.Receive: "/cfgplan/{robot}/channels/{channel}/received",
    s.Staleness: "/cfgplan/{robot}/freshness",
    s.InstallEvent: "/cfgplan/{robot}/installs",
    s.Presence: "/cfgplan/presence",
    s.Start: "/cfgplan/starts",
    s.Stop: "/cfgplan/stops",
    s.Message: "/cfgplan/errors",
    s.Inject: "/cfgplan/injections",
    s.Failure: "/cfgplan/failures",
    s.Recovery: "/cfgplan/recoveries",
    s.Facts: "/cfgplan/facts",
    s.Achieved: "/cfgplan/achievements",
    s.Finish: "/cfgplan/finishes",
    s.SwitchEvent: "/cfgplan/switches",
    s.NoConfiguration: "/cfgplan/no-configuration",
    s.Abort: "/cfgplan/aborts",
    s.Takeover: "/cfgplan/takeovers",
    s.StepDown: "/cfgplan/step-downs",
}
"""The topic of each kind of event (a model of :data:`cfgplan.runtime.schema.TraceEvent`),
in the order their schemas are registered. ``{robot}`` and ``{channel}`` are the
event's, each one topic segment (:func:`segment`)."""

MAX_NS = (1 << 64) - 1


@dataclass(frozen=True)
class Entry:
    """A trace line ready to be written: its kind, topic and times."""

    model: type[BaseModel]
    robot: str
    topic: str
    metadata: tuple[tuple[str, str], ...]
    log_time: int
    publish_time: int
    data: bytes


def segment(text: str) -> str:
    """``text`` as one topic segment: white space as ``_``; ``/``, ``%`` and
    unprintable characters percent-encoded (``F7->F3 (pos Emil Door1)`` is
    ``F7->F3_(pos_Emil_Door1)``); the empty text as ``_``."""
    out: list[str] = []
    for char in text:
        if char.isspace():
            out.append("_")
        elif char in "/%" or unicodedata.category(char)[0] == "C":
            out.append("".join(f"%{b:02X}" for b in char.encode("utf-8", "surrogatepass")))
        else:
            out.append(char)
    return "".join(out) or "_"


def nanoseconds(seconds: float) -> int | None:
    """``seconds`` as whole nanoseconds (the fraction rounded apart from the
    whole seconds, so an epoch time keeps its microseconds); ``None`` when it is
    not a time MCAP can hold (negative, not finite, past 2**64 ns)."""
    if not math.isfinite(seconds) or seconds < 0:
        return None
    whole = math.floor(seconds)
    ns = whole * 1_000_000_000 + round((seconds - whole) * 1e9)
    return ns if ns <= MAX_NS else None


def entry_of(obj: dict[str, Any], data: bytes) -> Entry:
    """The event ``obj`` (whose JSON is ``data``) as a message on its topic;
    pydantic's ``ValidationError`` when it is not an event, ``ValueError`` when
    its time is not a time."""
    event = s.TRACE_EVENT.validate_python(obj)
    log_time = nanoseconds(event.t)
    if log_time is None:
        raise ValueError(f"t: {event.t!r} is not a time (seconds, 0 or more)")
    publish_time = log_time
    if isinstance(event, s.Receive) and event.sent is not None:
        sent = nanoseconds(event.sent)
        publish_time = log_time if sent is None else sent
    model = type(event)
    parts = {"robot": event.robot}
    if isinstance(event, s.Send | s.Receive):
        parts["channel"] = event.channel
    topic = TOPICS[model].format(**{k: segment(v) for k, v in parts.items()})
    metadata = tuple(parts.items()) if "{robot}" in TOPICS[model] else ()
    return Entry(model, event.robot, topic, metadata, log_time, publish_time, data)


def run_metadata(kinds: Counter[type[BaseModel]], robots: Iterable[str]) -> dict[str, str]:
    """The file's ``cfgplan`` metadata record: the version, how many events of
    each kind (in the order of :data:`TOPICS`), which robots."""
    return {
        "cfgplan": __version__,
        "events": str(sum(kinds.values())),
        "robots": " ".join(sorted(set(robots))),
        "kinds": " ".join(f"{k.__name__}={kinds[k]}" for k in TOPICS if kinds[k]),
    }


def schema_name(model: type[BaseModel]) -> str:
    return f"cfgplan.trace.{model.__name__}"


@functools.cache
def schema_of(model: type[BaseModel]) -> bytes:
    """The JSON Schema of a kind of event, as registered: the pydantic model's
    (keys named as in the trace, ``from`` not ``from_``)."""
    return json.dumps(model.model_json_schema(by_alias=True), separators=(",", ":")).encode()


class Writer(Protocol):
    """What :class:`Registrar` needs of an MCAP writer (``mcap.writer.Writer``)."""

    def register_schema(self, name: str, encoding: str, data: bytes) -> int: ...

    def register_channel(
        self, topic: str, message_encoding: str, schema_id: int, metadata: dict[str, str] = ...
    ) -> int: ...


@dataclass
class Registrar:
    """The schemas and channels registered with one MCAP writer, each once,
    when first needed (or ahead, in an order of the caller's)."""

    writer: Writer
    schemas: dict[type[BaseModel], int] = field(default_factory=dict)
    channels: dict[str, int] = field(default_factory=dict)

    def schema(self, model: type[BaseModel]) -> int:
        known = self.schemas.get(model)
        if known is None:
            known = self.writer.register_schema(
                schema_name(model), SCHEMA_ENCODING, schema_of(model)
            )
            self.schemas[model] = known
        return known

    def channel(self, e: Entry) -> int:
        known = self.channels.get(e.topic)
        if known is None:
            known = self.writer.register_channel(
                e.topic, MESSAGE_ENCODING, self.schema(e.model), dict(e.metadata)
            )
            self.channels[e.topic] = known
        return known
