"""Reading the run ``cfgplan report`` draws: trace files or an MCAP recording.

* JSON-lines traces (``cfgplan run --trace``, a simulation's ``trace.jsonl``,
  a robot program's): each non-blank line must be an event of
  :mod:`cfgplan.runtime.schema`; when a capped trace rotated, ``FILE.1`` (the
  events just before) is read first. Several traces (one per robot of a
  society over Zenoh) are merged by time.
* A folder: the ``trace.jsonl`` that ``cfgplan simulate --out`` wrote in it.
* An MCAP recording (``cfgplan record``, ``--record``): read through the
  ``mcap`` package's reader; every JSON message on a ``/cfgplan/...`` topic is
  one trace event (the recording keeps each line's bytes); other topics
  (poses, scenes) are counted, not read.

A simulation's ``summary.json`` beside the run (its steps, title, world
changes, and what to replay: :mod:`cfgplan.report.replay`) is read too.
Anything else — a missing or unreadable file, a line that is not an event, no
event at all — is a :class:`~cfgplan.runtime.errors.RunError` naming the file
(and line).
"""

from __future__ import annotations

import json
import os
import stat
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from cfgplan.runtime.errors import RunError
from cfgplan.runtime.tracefile import trace_files

__all__ = ["MCAP_MAGIC", "Source", "read_run"]

MCAP_MAGIC = b"\x89MCAP0\r\n"
"""The first bytes of every MCAP file."""


@dataclass
class Source:
    """A run as read: its events (trace lines as objects), in order of time."""

    records: list[dict[str, Any]]
    files: list[Path]
    summary: dict[str, Any] | None = None
    mcap: bool = False
    other_topics: dict[str, int] = field(default_factory=dict)

    @property
    def text(self) -> bytes | None:
        """The trace's bytes, as a simulation writes them (for a single trace file)."""
        if self.mcap or len(self.files) != 1:
            return None
        return self.files[0].read_bytes()


def _check_file(path: Path) -> None:
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise RunError(f"no such file: {path}") from None
    except OSError as exc:
        raise RunError(f"cannot read {path}: {exc.strerror}") from None
    if not stat.S_ISREG(mode):
        raise RunError(f"{path} is not a regular file; give a trace or an MCAP recording")


def _event(obj: object, file: str, line: int) -> dict[str, Any]:
    """``obj`` if it is a trace event (:mod:`cfgplan.runtime.schema`), else a :class:`RunError`."""
    from cfgplan.runtime.schema import TRACE_EVENT

    if not isinstance(obj, dict):
        raise RunError("not a trace event: a JSON object is expected", file=file, line=line)
    if not isinstance(obj.get("event"), str):
        raise RunError('not a trace event: it has no "event"', file=file, line=line)
    try:
        TRACE_EVENT.validate_python(obj)
    except ValidationError as exc:
        first = exc.errors(include_url=False)[0]
        loc = [str(p) for p in first["loc"]]
        kind = obj.get("event")
        if loc and loc[0] == kind:
            loc = loc[1:]
        where = ".".join(loc)
        said = f"{where}: {first['msg']}" if where else str(first["msg"])
        named = f" ({kind})" if isinstance(kind, str) else ""
        raise RunError(f"not a trace event{named}: {said}", file=file, line=line) from None
    return obj


def _lines(path: Path) -> list[dict[str, Any]]:
    out = []
    for part in trace_files(path):
        _check_file(part)
        try:
            raw = part.read_bytes()
        except OSError as exc:
            raise RunError(f"cannot read {part}: {exc.strerror}") from None
        if raw.startswith(MCAP_MAGIC):
            raise RunError(f"{part} is an MCAP recording: give it alone")
        for number, line in enumerate(raw.split(b"\n"), 1):
            if not line.strip():
                continue
            try:
                obj = json.loads(line)
            except (UnicodeDecodeError, json.JSONDecodeError) as exc:
                message = (
                    "the line is not UTF-8 text" if isinstance(exc, UnicodeDecodeError) else exc.msg
                )
                raise RunError(f"not JSON: {message}", file=str(part), line=number) from None
            out.append(_event(obj, str(part), number))
    return out


def _mcap(path: Path, source: Source) -> None:
    try:
        from mcap.reader import make_reader
    except ModuleNotFoundError:
        raise RunError(
            f"{path} is an MCAP recording; reading it needs the mcap package",
            hint="install it with: pip install 'cfgplan[record]'",
        ) from None
    number = 0
    try:
        with open(path, "rb") as stream:
            reader = make_reader(stream)
            for _schema, channel, message in reader.iter_messages(log_time_order=True):
                topic = channel.topic
                if channel.message_encoding != "json" or not topic.startswith("/cfgplan/"):
                    source.other_topics[topic] = source.other_topics.get(topic, 0) + 1
                    continue
                number += 1
                try:
                    obj = json.loads(message.data)
                except (UnicodeDecodeError, json.JSONDecodeError):
                    raise RunError(f"{path}: message {number} on {topic} is not JSON") from None
                source.records.append(_event(obj, f"{path} ({topic})", number))
    except RunError:
        raise
    except OSError as exc:  # a seek past the end of a truncated file, too
        raise RunError(f"{path} is not a readable MCAP recording: {exc.strerror}") from None
    except Exception as exc:  # a damaged recording: mcap's own errors, and its decompressors'
        raise RunError(f"{path} is not a readable MCAP recording: {exc}") from None


def _summary(folder: Path) -> dict[str, Any] | None:
    path = folder / "summary.json"
    try:
        found = json.loads(path.read_text("utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return None
    return found if isinstance(found, dict) and "steps" in found else None


def read_run(paths: Sequence[Path]) -> Source:
    """The run in ``paths`` (module docstring)."""
    if not paths:
        raise RunError("give a trace (JSON lines) or an MCAP recording")
    files = [p / "trace.jsonl" if p.is_dir() else p for p in paths]
    source = Source([], files)
    for path in files:
        _check_file(path)
        with open(path, "rb") as stream:
            head = stream.read(len(MCAP_MAGIC))
        if head == MCAP_MAGIC:
            if len(files) > 1:
                raise RunError(f"{path} is an MCAP recording: give it alone")
            source.mcap = True
            _mcap(path, source)
        else:
            source.records += _lines(path)
    if not source.records:
        names = " and ".join(str(p) for p in files)
        raise RunError(f"{names}: no trace events (nothing to report)")
    source.records.sort(key=lambda r: float(r["t"]))  # stable: each file's order kept
    if len(files) == 1:
        source.summary = _summary(files[0].parent)
    return source
