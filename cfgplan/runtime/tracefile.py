"""``--trace FILE``: the full record of a run, one JSON object per line
(schema: :mod:`cfgplan.runtime.schema`).

The file is created new: an existing file is overwritten only with
``--force``; a symbolic link whose target does not exist is never written
through (that would create a file wherever it points); a directory, a device
or a FIFO is refused; a file that cannot be written is a clear error. Lines
are written as events happen and flushed once per cycle, so a trace can be
followed while the robot runs (``tail -f``) and survives the process being
killed. When writing fails later (a full disk), tracing stops, the robot
goes on, and the failure is reported. A trace holds every value of the run:
it is created (or truncated) readable by its owner only, mode 0600. Every
line is JSON: a float that is not finite (a NaN an implementation computed,
in one process) is written as a string, ``"NaN"``, ``"Infinity"`` or
``"-Infinity"`` (:func:`~cfgplan.runtime.wire.finite`); across processes
such a value does not travel at all (:func:`~cfgplan.runtime.values.encode`).

Bounded: a value whose JSON is longer than ``elide`` characters
(:data:`ELIDE`, 4096) is recorded by its size and digest
(:func:`~cfgplan.runtime.values.elide`, the rule the simulator's trace
follows too), and the file is capped at ``max_bytes`` (:data:`MAX_BYTES`,
64 MiB; ``--trace-max-bytes``, 0: no cap): when a line would take it past the
cap, FILE is renamed FILE.1 (replacing the one an earlier rotation made) and
a new FILE begins. So at most twice the cap is kept on disk: the newest
events in FILE, those just before them in FILE.1; older ones are dropped. A
FILE.1 already there when the run starts is, like FILE, overwritten (removed
at once) only with ``--force``.
"""

from __future__ import annotations

import contextlib
import json
import os
import stat
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import TextIO

from cfgplan.runtime.errors import RunError
from cfgplan.runtime.events import Call, Data, Event, Transfer
from cfgplan.runtime.values import elide
from cfgplan.runtime.wire import finite

__all__ = [
    "ELIDE",
    "MAX_BYTES",
    "TraceFile",
    "create",
    "elided",
    "open_output",
    "open_trace",
    "rotated_path",
    "trace_files",
]

ELIDE = 4096
"""Characters of JSON beyond which a value is recorded by its size and digest."""

MAX_BYTES = 64 << 20
"""The default cap of a trace file (``--trace-max-bytes``): 64 MiB, then FILE.1."""


def elided(event: Event, limit: int) -> Event:
    """``event`` with each value of a call or a message longer than ``limit``
    characters of JSON in place by its size and digest (0: as they are)."""
    if not limit:
        return event
    if isinstance(event, Call) and (event.inputs or event.outputs):
        return replace(
            event, inputs=_pairs(event.inputs, limit), outputs=_pairs(event.outputs, limit)
        )
    if isinstance(event, Transfer):
        return replace(event, value=elide(event.value, limit))
    return event


def _pairs(pairs: tuple[tuple[Data, object], ...], limit: int) -> tuple[tuple[Data, object], ...]:
    return tuple((data, elide(value, limit)) for data, value in pairs)


def open_trace(
    path: str | Path, force: bool = False, *, max_bytes: int = MAX_BYTES, elide: int = ELIDE
) -> TraceFile:
    """A new trace file at ``path``, capped at ``max_bytes`` (0: no cap), values
    over ``elide`` characters recorded by size and digest (0: whole);
    :class:`RunError` when it may or cannot be written."""
    p = Path(path)
    fd = open_output(p, force, what="trace file", rotates=bool(max_bytes))
    return TraceFile(p, _text(fd), max_bytes=max_bytes, elide=elide)


def open_output(p: Path, force: bool, *, what: str, rotates: bool) -> int:
    """The descriptor of a new output file at ``p`` (a trace, a recording:
    ``what``), refused with :class:`RunError` where it may or cannot be
    written: an existing file, or ``p``.1 where it ``rotates`` when full,
    only with ``force`` (the latter removed: it would hold an earlier run's
    events until the first rotation); never through a dangling symbolic link,
    never a directory or a special file."""
    if p.is_symlink() and not p.exists():
        raise RunError(
            f"{what} {p} is a symbolic link to {os.readlink(p)}, which does not exist; "
            "refusing to create a file through it"
        )
    if p.is_dir():
        raise RunError(f"{what} {p} is a directory")
    if p.exists():
        if not force:
            raise RunError(f"{what} {p} exists; pass --force to overwrite it")
        if not stat.S_ISREG(p.stat().st_mode):
            raise RunError(f"{what} {p} exists and is not a regular file")
    rotated = rotated_path(p)
    if rotates and (rotated.exists() or rotated.is_symlink()):
        if not force:
            raise RunError(
                f"{what} {rotated} (where {p} rotates when full) exists; "
                "pass --force to overwrite it"
            )
        if rotated.is_dir():
            raise RunError(f"{what} {rotated} (where {p} rotates when full) is a directory")
        try:
            rotated.unlink()
        except OSError as exc:
            raise RunError(f"cannot remove the {what} {rotated}: {exc.strerror}") from None
    try:
        return create(p, force)
    except FileExistsError:
        raise RunError(f"{what} {p} exists; pass --force to overwrite it") from None
    except OSError as exc:
        raise RunError(f"cannot write the {what} {p}: {exc.strerror}") from None


def rotated_path(p: Path) -> Path:
    """Where an output file capped in size rotates to: FILE.1."""
    return p.with_name(p.name + ".1")


def trace_files(path: Path) -> list[Path]:
    """The files of the trace (or recording) ``path``, in the order written:
    ``path``.1 first when a capped one rotated (it holds the events just
    before those in ``path``), then ``path``."""
    rotated = rotated_path(path)
    return [rotated, path] if rotated.is_file() else [path]


def create(p: Path, force: bool) -> int:
    """A new file's descriptor: with ``force`` truncated if it exists (not
    through a link it would follow), else created only if nothing, not even
    a symbolic link, is there."""
    flags = os.O_WRONLY | os.O_CREAT | getattr(os, "O_CLOEXEC", 0)
    if force:
        flags |= os.O_TRUNC
        if not p.is_symlink():
            flags |= getattr(os, "O_NOFOLLOW", 0)
    else:
        flags |= os.O_EXCL  # also refuses any symbolic link, dangling or not
    fd = os.open(p, flags, 0o600)
    os.fchmod(fd, 0o600)  # a file truncated keeps its mode: a trace is the run's own
    return fd


def _text(fd: int) -> TextIO:
    return os.fdopen(fd, "w", encoding="utf-8", newline="\n")


class TraceFile:
    """Events as JSON lines; a subscriber of the robots it traces."""

    def __init__(
        self, path: Path, stream: TextIO, *, max_bytes: int = MAX_BYTES, elide: int = ELIDE
    ) -> None:
        self.path = path
        self.failed: str | None = None  # why tracing stopped, if it did
        self.max_bytes = max_bytes
        self.elide = elide
        self.written = 0  # bytes in the current file
        self.rotations = 0
        self._stream: TextIO | None = stream

    def __call__(self, event: Event) -> None:
        self.write(event)

    def write(self, event: Event) -> None:
        if self._stream is None:
            return
        record = elided(event, self.elide).record()
        try:
            try:
                line = json.dumps(record, separators=(",", ":"), allow_nan=False) + "\n"
            except ValueError:  # a NaN or an infinity (a value, a time): JSON has neither
                line = json.dumps(finite(record), separators=(",", ":"), allow_nan=False) + "\n"
        except (TypeError, ValueError) as exc:  # pragma: no cover - records are JSON-ready
            line = json.dumps({"event": "error", "robot": event.robot, "message": str(exc)}) + "\n"
        size = len(line)  # ASCII: json.dumps escapes the rest
        if self.max_bytes and self.written and self.written + size > self.max_bytes:
            self._rotate()
        self._guard(lambda s: s.write(line))
        self.written += size

    def _rotate(self) -> None:
        """FILE becomes FILE.1 (replacing the one an earlier rotation of this
        run made: :func:`open_trace` cleared any other) and a new FILE begins."""
        self.close()
        if self.failed is not None:
            return
        try:
            os.replace(self.path, rotated_path(self.path))
            self._stream = _text(create(self.path, force=False))
        except OSError as exc:
            self.failed = (
                f"cannot rotate the trace file {self.path}: {exc.strerror}; tracing stopped"
            )
            return
        self.written = 0
        self.rotations += 1

    def flush(self) -> None:
        self._guard(lambda s: s.flush())

    def close(self) -> None:
        self.flush()
        if self._stream is not None:
            stream, self._stream = self._stream, None
            try:
                stream.close()
            except OSError as exc:
                self.failed = (
                    self.failed or f"cannot write the trace file {self.path}: {exc.strerror}"
                )

    def _guard(self, act: Callable[[TextIO], object]) -> None:
        if self._stream is None:
            return
        try:
            act(self._stream)
        except OSError as exc:
            self.failed = (
                f"cannot write the trace file {self.path}: {exc.strerror}; tracing stopped"
            )
            stream, self._stream = self._stream, None
            with contextlib.suppress(OSError):
                stream.close()
