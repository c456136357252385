"""A run's trace as an MCAP file: what Foxglove opens.

The trace of ``cfgplan run --trace FILE`` (or a robot program's, or a
simulation's ``trace.jsonl``) is one JSON object per event
(:mod:`cfgplan.runtime.schema`). Each line becomes one message, its bytes as
they are, on the channel of its kind of event with that kind's JSON Schema,
as :mod:`cfgplan.record.channels` defines them for every writer (this one,
``--record`` and ``--foxglove``): the models are the one description of a
trace line, and a line that does not validate against them is refused with
its file and line.

The file is the same bytes for the same trace: schemas are registered in the
order of :data:`TOPICS`, channels in the order of their topics, messages in
the order of the trace (FILE.1 before FILE for a rotated trace), and the
header names cfgplan's version, no clock. Building it needs the ``mcap``
package (``pip install 'cfgplan[record]'``).
"""

from __future__ import annotations

import io
import json
import os
import stat
from collections import Counter
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Literal

from mcap.writer import CompressionType, Writer
from pydantic import BaseModel, ValidationError

from cfgplan import __version__
from cfgplan.record.channels import (
    MESSAGE_ENCODING,
    SCHEMA_ENCODING,
    TOPICS,
    Entry,
    Registrar,
    entry_of,
    nanoseconds,
    run_metadata,
    schema_name,
    schema_of,
    segment,
)
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.tracefile import trace_files

__all__ = [
    "COMPRESSION",
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
        return entry_of(obj, line.text)
    except ValidationError as exc:
        kind = obj.get("event")
        named = f" ({kind})" if isinstance(kind, str) else ""
        raise refuse(f"not a trace event{named}: {_problem(exc, kind)}") from None
    except ValueError as exc:
        raise refuse(str(exc)) from None


COMPRESSION = {
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
    for e in entries:
        known = models.setdefault(e.topic, e.model)
        assert known is e.model, f"two kinds of event on {e.topic}"
    writer = Writer(
        out, chunk_size=options.chunk_size, compression=COMPRESSION[options.compression]
    )
    writer.start(profile="", library=f"cfgplan {__version__}")
    done = Recording()
    registered = Registrar(writer)
    for model in TOPICS:  # schemas in a fixed order, then channels by topic
        if model in models.values():
            registered.schema(model)
            done.schemas.append(schema_name(model))
    firsts = {e.topic: e for e in reversed(entries)}
    for topic in sorted(models):
        registered.channel(firsts[topic])
        done.messages[topic] = 0
    for e in entries:
        done.messages[e.topic] += 1
        sequence = done.messages[e.topic] & 0xFFFFFFFF
        writer.add_message(registered.channel(e), e.log_time, e.data, e.publish_time, sequence)
    kinds = Counter(e.model for e in entries)
    writer.add_metadata("cfgplan", run_metadata(kinds, {e.robot for e in entries}))
    writer.finish()  # type: ignore[no-untyped-call]
    return done


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
