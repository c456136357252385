"""A run's trace as an MCAP file: what Foxglove opens (issue 37).

The trace of ``cfgplan run --trace FILE`` (or a robot program's, or a
simulation's ``trace.jsonl``) is one JSON object per event
(:mod:`cfgplan.runtime.schema`). Each line becomes one message, its bytes as
they are (message encoding ``json``), on the channel of its kind of event
(:data:`TOPICS`): a robot's wrapper calls (5.2.1), the values it sent or
received on each global channel (5.2.2), its stale and fresh inputs (3.2);
the society's presence, failures, recoveries and switches (5.5, 7.2). Each
channel's schema is the JSON Schema of the pydantic model of that kind
(schema encoding ``jsonschema``): the models are the one description of a
trace line, and a line that does not validate against them is refused with
its file and line. A message's log time is the event's ``t`` in nanoseconds;
its publish time is the same, but for a received value, the sender's ``t``.

The file is the same bytes for the same trace: schemas are registered in the
order of :data:`TOPICS`, channels in the order of their topics, messages in
the order of the trace (FILE.1 before FILE for a rotated trace), and the
header names cfgplan's version, no clock. Building it needs the ``mcap``
package (``pip install 'cfgplan[record]'``).
"""

from __future__ import annotations

import io
import json
import math
import os
import stat
import unicodedata
from collections import Counter
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Literal

from mcap.writer import CompressionType, Writer
from pydantic import BaseModel, ValidationError

from cfgplan import __version__
from cfgplan.runtime import schema as s
from cfgplan.runtime.errors import RunError

__all__ = [
    "MESSAGE_ENCODING",
    "SCHEMA_ENCODING",
    "TOPICS",
    "Entry",
    "RecordOptions",
    "Recording",
    "TraceLine",
    "convert",
    "entry",
    "nanoseconds",
    "read_lines",
    "record",
    "schema_name",
    "schema_of",
    "segment",
    "trace_files",
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
}
"""The topic of each kind of event (a model of :data:`cfgplan.runtime.schema.TraceEvent`),
in the order their schemas are registered. ``{robot}`` and ``{channel}`` are the
event's, each one topic segment (:func:`segment`)."""

MAX_NS = (1 << 64) - 1


@dataclass(frozen=True)
class RecordOptions:
    """How the MCAP file is written: chunks of ``chunk_size`` bytes, each
    compressed with ``compression`` (the readers Foxglove uses know zstd and lz4)."""

    compression: Literal["zstd", "lz4", "none"] = "zstd"
    chunk_size: int = 1 << 20


@dataclass(frozen=True)
class TraceLine:
    """One line of a trace file, as read (without its line break)."""

    file: str
    number: int
    text: bytes


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


@dataclass
class Recording:
    """What was written: the messages on each topic (in channel order), the
    schemas registered (in order), and the trace files read."""

    messages: dict[str, int] = field(default_factory=dict)
    schemas: list[str] = field(default_factory=list)
    files: list[str] = field(default_factory=list)

    @property
    def total(self) -> int:
        return sum(self.messages.values())


def trace_files(path: Path) -> list[Path]:
    """The files of the trace ``path``: ``path.1`` first when a capped trace
    rotated (:mod:`cfgplan.runtime.tracefile`: it holds the events just before
    those in ``path``), then ``path``."""
    rotated = path.with_name(path.name + ".1")
    return [rotated, path] if rotated.is_file() else [path]


def read_lines(paths: Sequence[Path]) -> Iterator[TraceLine]:
    """The non-blank lines of the files, in order; :class:`RunError` for a
    file that is missing, not a regular file, or unreadable."""
    for path in paths:
        name = str(path)
        try:
            mode = os.stat(path).st_mode
        except FileNotFoundError:
            raise RunError(f"no such trace file: {name}") from None
        except OSError as exc:
            raise RunError(f"cannot read the trace file {name}: {exc.strerror}") from None
        if stat.S_ISDIR(mode):
            raise RunError(f"{name} is a directory, not a trace file")
        if not stat.S_ISREG(mode):
            raise RunError(f"{name} is not a regular file; cfgplan reads only regular files")
        try:
            with open(path, "rb") as stream:
                for number, raw in enumerate(stream, 1):
                    text = raw.rstrip(b"\r\n")
                    if text.strip():
                        yield TraceLine(name, number, text)
        except OSError as exc:
            raise RunError(f"cannot read the trace file {name}: {exc.strerror}") from None


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


def _problem(exc: ValidationError, kind: object) -> str:
    """The first thing wrong, at its key (``label: Field required``); the
    union's tag, which pydantic puts first, left out."""
    first = exc.errors(include_url=False)[0]
    loc = list(first["loc"])
    if loc and loc[0] == kind:
        loc = loc[1:]
    where = ".".join(str(part) for part in loc)
    return f"{where}: {first['msg']}" if where else str(first["msg"])


_JSON_TYPES = {list: "an array", str: "a string", int: "a number", float: "a number"}


def entry(line: TraceLine) -> Entry:
    """The line as an MCAP message on its topic; :class:`RunError` (with the
    file and line) when it is not JSON, not an event, or its time is not a time."""

    def refuse(message: str, column: int = 1) -> RunError:
        return RunError(message, file=line.file, line=line.number, column=column)

    try:
        obj = json.loads(line.text.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise refuse("not JSON: the line is not UTF-8 text", exc.start + 1) from None
    except json.JSONDecodeError as exc:
        raise refuse(f"not JSON: {exc.msg}", exc.colno) from None
    if not isinstance(obj, dict):
        what = _JSON_TYPES.get(type(obj), "null" if obj is None else "true or false")
        raise refuse(f"not a trace event: a JSON object is expected, not {what}")
    try:
        event = s.TRACE_EVENT.validate_python(obj)
    except ValidationError as exc:
        kind = obj.get("event")
        named = f" ({kind})" if isinstance(kind, str) else ""
        raise refuse(f"not a trace event{named}: {_problem(exc, kind)}") from None
    log_time = nanoseconds(event.t)
    if log_time is None:
        raise refuse(f"t: {event.t!r} is not a time (seconds, 0 or more)")
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
    return Entry(model, event.robot, topic, metadata, log_time, publish_time, line.text)


def schema_name(model: type[BaseModel]) -> str:
    return f"cfgplan.trace.{model.__name__}"


def schema_of(model: type[BaseModel]) -> bytes:
    """The JSON Schema of a kind of event, as registered: the pydantic model's
    (keys named as in the trace, ``from`` not ``from_``)."""
    return json.dumps(model.model_json_schema(by_alias=True), separators=(",", ":")).encode()


_COMPRESSION = {
    "zstd": CompressionType.ZSTD,
    "lz4": CompressionType.LZ4,
    "none": CompressionType.NONE,
}


def record(
    entries: Iterable[Entry], out: IO[bytes], options: RecordOptions | None = None
) -> Recording:
    """Write ``entries`` to ``out`` as an MCAP file (the stream is not closed)."""
    options = options or RecordOptions()
    entries = list(entries)
    models: dict[str, type[BaseModel]] = {}
    metadata: dict[str, dict[str, str]] = {}
    for e in entries:
        known = models.setdefault(e.topic, e.model)
        assert known is e.model, f"two kinds of event on {e.topic}"
        metadata.setdefault(e.topic, dict(e.metadata))
    writer = Writer(
        out, chunk_size=options.chunk_size, compression=_COMPRESSION[options.compression]
    )
    writer.start(profile="", library=f"cfgplan {__version__}")
    done = Recording()
    schema_ids: dict[type[BaseModel], int] = {}
    for model in TOPICS:
        if model in models.values():
            name = schema_name(model)
            schema_ids[model] = writer.register_schema(name, SCHEMA_ENCODING, schema_of(model))
            done.schemas.append(name)
    channel_ids: dict[str, int] = {}
    for topic in sorted(models):
        channel_ids[topic] = writer.register_channel(
            topic, MESSAGE_ENCODING, schema_ids[models[topic]], metadata[topic]
        )
        done.messages[topic] = 0
    for e in entries:
        done.messages[e.topic] += 1
        sequence = done.messages[e.topic] & 0xFFFFFFFF
        writer.add_message(channel_ids[e.topic], e.log_time, e.data, e.publish_time, sequence)
    robots = sorted({e.robot for e in entries})
    writer.add_metadata(
        "cfgplan",
        {
            "cfgplan": __version__,
            "events": str(len(entries)),
            "robots": " ".join(robots),
            "kinds": " ".join(f"{k.__name__}={n}" for k, n in _kinds(entries)),
        },
    )
    writer.finish()  # type: ignore[no-untyped-call]
    return done


def _kinds(entries: Sequence[Entry]) -> list[tuple[type[BaseModel], int]]:
    counts = Counter(e.model for e in entries)
    return [(model, counts[model]) for model in TOPICS if counts[model]]


def convert(paths: Sequence[Path], options: RecordOptions | None = None) -> tuple[bytes, Recording]:
    """The MCAP file of the trace in ``paths`` (in order), and what it holds;
    :class:`RunError` for a file that cannot be read, a line that is not an
    event, or no event at all."""
    entries = [entry(line) for line in read_lines(paths)]
    if not entries:
        names = " and ".join(str(p) for p in paths)
        raise RunError(f"{names}: no trace events (the file is empty)")
    buffer = io.BytesIO()
    done = record(entries, buffer, options)
    done.files = [str(p) for p in paths]
    return buffer.getvalue(), done
