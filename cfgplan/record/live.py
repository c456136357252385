"""``--record FILE.mcap``: a run written to MCAP as it happens.

A :class:`LiveRecorder` is a listener of the society (``Society.subscribe``)
on ``cfgplan run``, or the other end of a simulation's trace (:class:`Tee`,
``cfgplan simulate --record``). Each event becomes the JSON line the trace
would have (:mod:`cfgplan.runtime.tracefile`, its long values elided the
same way) and one message on the channel :mod:`cfgplan.record.channels`
names, with the schema it gives: the file holds what ``cfgplan record`` makes
of the trace, in chunks written as the run goes.

What the ``mcap`` writer guarantees (``mcap.writer.Writer``, read at its
source, version 1.6): with chunking on, messages stay in memory in the chunk
being built until it passes ``chunk_size`` bytes or :meth:`Writer.flush` is
called, which finishes the chunk (compressed, with its message index) and
writes it to the stream and flushes the stream — without ``fsync``; the
schemas and channels are inside the chunk of their first message. So a
process killed by SIGKILL leaves every chunk flushed before it (the operating
system writes them even though the process died; a power cut may lose what
was not yet on the disk), and the file then lacks its summary, its index and
its footer: a reader that starts from the footer refuses it, a streaming
reader reads every whole chunk (:func:`salvage`; ``mcap recover`` rewrites it
whole). The flushing and the cap are :class:`~cfgplan.record.policy.Policy`'s.
"""

from __future__ import annotations

import contextlib
import json
import os
import threading
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

from mcap.reader import NonSeekingReader
from mcap.records import Channel, Message, Schema
from mcap.writer import Writer
from pydantic import BaseModel, ValidationError

from cfgplan import __version__
from cfgplan.record.channels import Entry, Registrar, entry_of, run_metadata
from cfgplan.record.mcap_export import COMPRESSION
from cfgplan.record.policy import Policy
from cfgplan.runtime import schema as s
from cfgplan.runtime.events import Event
from cfgplan.runtime.tracefile import create, elided, open_output, rotated_path

__all__ = ["AT_ONCE", "LiveRecorder", "Tee", "open_recording", "salvage"]

AT_ONCE: frozenset[type[BaseModel]] = frozenset(
    {
        s.Inject,
        s.Failure,
        s.Recovery,
        s.SwitchEvent,
        s.NoConfiguration,
        s.Abort,
        s.Facts,
        s.Achieved,
        s.Finish,
        s.Presence,
        s.Stop,
        s.InstallEvent,
        s.Takeover,
        s.StepDown,
    }
)
"""Kinds of event whose chunk is written at once: what the society does (5.5)."""

_MESSAGE_OVERHEAD = 31  # a message record's header in a chunk, and its index entry
_INDEX_PER_CHUNK = 96  # a chunk index in the summary, about, plus 10 bytes per channel


def open_recording(
    path: str | Path, force: bool = False, policy: Policy | None = None
) -> LiveRecorder:
    """A new recording at ``path``; :class:`RunError` when it may or cannot be
    written (the same rules as ``--trace``: an existing file, or FILE.1 where
    it rotates, only with ``force``; never through a dangling link)."""
    policy = policy or Policy()
    p = Path(path)
    fd = open_output(p, force, what="recording", rotates=bool(policy.max_bytes))
    stream = os.fdopen(fd, "wb")
    return LiveRecorder(p, stream, policy)


class LiveRecorder:
    """An MCAP file written as the events come (module docstring). Thread-safe:
    robots on several threads may call it."""

    def __init__(self, path: Path, stream: IO[bytes], policy: Policy) -> None:
        self.path = path
        self.policy = policy
        self.failed: str | None = None
        """Why recording stopped, if it did (a full disk): the run goes on."""
        self.rotations = 0
        self.refused = 0
        """Events that were not trace events (none, unless the runtime and schema drift)."""
        self.kinds: Counter[type[BaseModel]] = Counter()
        self.robots: set[str] = set()
        self._lock = threading.Lock()
        self._stream: IO[bytes] | None = None
        self._open(stream)

    # -- what the run calls --------------------------------------------------

    def __call__(self, event: Event) -> None:
        """A robot's event (``Society.subscribe``)."""
        try:
            obj = elided(event, self.policy.elide).record()
            data = json.dumps(obj, separators=(",", ":")).encode()
        except (TypeError, ValueError):  # pragma: no cover - records are JSON-ready
            self.refused += 1
            return
        self.add(obj, data)

    def add(self, obj: dict[str, Any], data: bytes) -> None:
        """One trace line (``obj``, its JSON ``data``) as a message."""
        try:
            e = entry_of(obj, data)
        except (ValidationError, ValueError):
            self.refused += 1
            return
        with self._lock:
            if self._stream is None:
                return
            try:
                self._add(e)
            except OSError as exc:
                self._fail(f"cannot write the recording {self.path}: {exc.strerror}")

    def flush(self) -> None:
        """Write the chunk being built now."""
        with self._lock:
            if self._stream is not None:
                try:
                    self._flush()
                except OSError as exc:
                    self._fail(f"cannot write the recording {self.path}: {exc.strerror}")

    def close(self) -> None:
        """Finish the file (its summary and footer) and close it; idempotent."""
        with self._lock:
            if self._stream is not None:
                try:
                    self._finish()
                except OSError as exc:
                    self._fail(f"cannot write the recording {self.path}: {exc.strerror}")

    @property
    def total(self) -> int:
        return sum(self.kinds.values())

    # -- under the lock ------------------------------------------------------

    def _open(self, stream: IO[bytes]) -> None:
        p = self.policy
        self._stream = stream
        compression = COMPRESSION[p.compression]
        self._writer = Writer(stream, chunk_size=p.chunk_size, compression=compression)
        self._writer.start(profile="", library=f"cfgplan {__version__}")
        self._registrar = Registrar(self._writer)
        self._sequences: Counter[str] = Counter()
        self._file_kinds: Counter[type[BaseModel]] = Counter()
        self._file_robots: set[str] = set()
        self._pending = 0  # bytes in the chunk being built, about
        self._told = stream.tell()
        self._chunks = 0
        self._flushed = time.monotonic()

    def _size(self, more: int) -> int:
        """What the file would be with ``more`` bytes of messages, its summary included."""
        told = self._stream.tell() if self._stream is not None else 0
        if told != self._told:  # the writer finished a chunk of its own accord
            self._told, self._pending = told, 0
            self._chunks += 1
        index = self._chunks * (_INDEX_PER_CHUNK + 10 * len(self._registrar.channels))
        return told + self._pending + more + index + 4096

    def _add(self, e: Entry) -> None:
        cap = self.policy.max_bytes
        more = len(e.data) + len(e.topic) + _MESSAGE_OVERHEAD
        if cap and self._file_kinds and self._size(more) > cap:
            self._rotate()
            if self._stream is None:
                return
        channel = self._registrar.channel(e)
        self._sequences[e.topic] += 1
        sequence = self._sequences[e.topic] & 0xFFFFFFFF
        self._writer.add_message(channel, e.log_time, e.data, e.publish_time, sequence)
        self._pending += more
        self.kinds[e.model] += 1
        self._file_kinds[e.model] += 1
        self.robots.add(e.robot)
        self._file_robots.add(e.robot)
        due = time.monotonic() - self._flushed >= self.policy.flush_every
        if e.model in AT_ONCE or due:
            self._flush()

    def _flush(self) -> None:
        assert self._stream is not None
        if self._pending:
            self._chunks += 1
        self._writer.flush()  # type: ignore[no-untyped-call]
        self._told, self._pending = self._stream.tell(), 0
        self._flushed = time.monotonic()

    def _finish(self) -> None:
        stream = self._stream
        assert stream is not None
        self._writer.add_metadata("cfgplan", run_metadata(self._file_kinds, self._file_robots))
        self._writer.finish()  # type: ignore[no-untyped-call]
        self._stream = None
        stream.close()

    def _rotate(self) -> None:
        """FILE, finished, becomes FILE.1 (replacing the one an earlier rotation
        made) and a new FILE begins."""
        self._finish()
        try:
            os.replace(self.path, rotated_path(self.path))
            stream = os.fdopen(create(self.path, force=False), "wb")
        except OSError as exc:
            self.failed = (
                f"cannot rotate the recording {self.path}: {exc.strerror}; recording stopped"
            )
            return
        self.rotations += 1
        self._open(stream)

    def _fail(self, why: str) -> None:
        self.failed = f"{why}; recording stopped"
        stream, self._stream = self._stream, None
        if stream is not None:
            with contextlib.suppress(OSError):
                stream.close()


class Tee:
    """A text stream that writes what it is given to ``stream`` and each whole
    line (a trace line) to ``recorder`` too: a simulation's trace, recorded."""

    def __init__(self, stream: IO[str], recorder: LiveRecorder) -> None:
        self.stream = stream
        self.recorder = recorder
        self._rest = ""

    def write(self, text: str) -> int:
        written = self.stream.write(text)
        lines = (self._rest + text).split("\n")
        self._rest = lines.pop()
        for line in lines:
            if line.strip():
                try:
                    obj = json.loads(line)
                except json.JSONDecodeError:
                    self.recorder.refused += 1
                    continue
                if isinstance(obj, dict):
                    self.recorder.add(obj, line.encode())
        return written

    def flush(self) -> None:
        self.stream.flush()


def salvage(stream: IO[bytes]) -> Iterator[tuple[Schema | None, Channel, Message]]:
    """The messages of an MCAP file read from its start, in the order written,
    up to where it ends: a whole file, or one whose writer was killed (no
    footer) — every whole chunk then."""
    reader = NonSeekingReader(stream)
    # A chunk cut by the kill ends the file: mcap's errors, struct's, and its
    # decompressors' (zstandard, lz4) for a chunk written half.
    with contextlib.suppress(Exception):
        yield from reader.iter_messages(log_time_order=False)
