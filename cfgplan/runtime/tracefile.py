"""``--trace FILE``: the full record of a run, one JSON object per line
(schema: :mod:`cfgplan.runtime.schema`).

The file is created new: an existing file is overwritten only with
``--force``; a symbolic link whose target does not exist is never written
through (that would create a file wherever it points); a directory, a device
or a FIFO is refused; a file that cannot be written is a clear error. Lines
are written as events happen and flushed once per cycle, so a trace can be
followed while the robot runs (``tail -f``) and survives the process being
killed. When writing fails later (a full disk), tracing stops, the robot
goes on, and the failure is reported.
"""

from __future__ import annotations

import contextlib
import json
import os
import stat
from collections.abc import Callable
from pathlib import Path
from typing import TextIO

from cfgplan.runtime.errors import RunError
from cfgplan.runtime.events import Event

__all__ = ["TraceFile", "open_trace"]


def open_trace(path: str | Path, force: bool = False) -> TraceFile:
    """A new trace file at ``path``; :class:`RunError` when it may or cannot be written."""
    p = Path(path)
    if p.is_symlink() and not p.exists():
        raise RunError(
            f"trace file {p} is a symbolic link to {os.readlink(p)}, which does not exist; "
            "refusing to create a file through it"
        )
    if p.is_dir():
        raise RunError(f"trace file {p} is a directory")
    if p.exists():
        if not force:
            raise RunError(f"trace file {p} exists; pass --force to overwrite it")
        if not stat.S_ISREG(p.stat().st_mode):
            raise RunError(f"trace file {p} exists and is not a regular file")
    flags = os.O_WRONLY | os.O_CREAT | getattr(os, "O_CLOEXEC", 0)
    if force:
        flags |= os.O_TRUNC
        if not p.is_symlink():
            flags |= getattr(os, "O_NOFOLLOW", 0)
    else:
        flags |= os.O_EXCL  # also refuses any symbolic link, dangling or not
    try:
        fd = os.open(p, flags, 0o644)
    except FileExistsError:
        raise RunError(f"trace file {p} exists; pass --force to overwrite it") from None
    except OSError as exc:
        raise RunError(f"cannot write the trace file {p}: {exc.strerror}") from None
    return TraceFile(p, os.fdopen(fd, "w", encoding="utf-8", newline="\n"))


class TraceFile:
    """Events as JSON lines; a subscriber of the robots it traces."""

    def __init__(self, path: Path, stream: TextIO) -> None:
        self.path = path
        self.failed: str | None = None  # why tracing stopped, if it did
        self._stream: TextIO | None = stream

    def __call__(self, event: Event) -> None:
        self.write(event)

    def write(self, event: Event) -> None:
        if self._stream is None:
            return
        try:
            line = json.dumps(event.record(), separators=(",", ":"))
        except (TypeError, ValueError) as exc:  # pragma: no cover - records are JSON-ready
            line = json.dumps({"event": "error", "robot": event.robot, "message": str(exc)})
        self._guard(lambda s: s.write(line + "\n"))

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
