"""Hermetic network tests: loopback endpoints on free ports, scouting off, every
wait bounded, every process started stopped by its pid."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

from tests.backends.support import ROOT

Record = dict[str, object]

HERMETIC = """{
  // tests: no multicast, no gossip; peers meet only through the endpoints given
  scouting: { multicast: { enabled: false }, gossip: { enabled: false } },
}
"""


def free_port() -> int:
    """A TCP port on 127.0.0.1 that nobody listens on right now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def endpoint(port: int) -> str:
    return f"tcp/127.0.0.1:{port}"


def hermetic_config(folder: Path) -> Path:
    path = folder / "zenoh-hermetic.json5"
    path.write_text(HERMETIC)
    return path


def read_trace(path: Path) -> list[Record]:
    """The complete lines of a trace that may still be growing."""
    if not path.exists():
        return []
    out = []
    for line in path.read_text(encoding="utf-8").split("\n")[:-1]:
        out.append(json.loads(line))
    return out


def wait_for(
    what: str, found: Callable[[], Record | None], limit: float, poll: float = 0.02
) -> Record:
    """Poll ``found`` until it returns a record; fail after ``limit`` seconds."""
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        got = found()
        if got is not None:
            return got
        time.sleep(poll)
    raise AssertionError(f"not seen within {limit} s: {what}")


def first(path: Path, match: Callable[[Record], bool]) -> Callable[[], Record | None]:
    """A ``found`` for :func:`wait_for`: the first line of the trace that matches."""

    def look() -> Record | None:
        return next((r for r in read_trace(path) if match(r)), None)

    return look


class Processes:
    """Processes a test starts; each stopped by its pid when the test ends."""

    def __init__(self) -> None:
        self.started: list[subprocess.Popen[str]] = []
        self.logs: list[Path] = []

    def start(self, args: list[str], log: Path) -> subprocess.Popen[str]:
        self.logs.append(log)
        out = open(log, "w", encoding="utf-8")  # noqa: SIM115  (closed by the process ending)
        process = subprocess.Popen(
            [sys.executable, *args],
            cwd=ROOT,
            stdout=out,
            stderr=subprocess.STDOUT,
            text=True,
            env={**os.environ, "PYTHONUNBUFFERED": "1"},
        )
        out.close()
        self.started.append(process)
        return process

    def stop_all(self) -> None:
        for process in self.started:
            if process.poll() is None:
                with contextlib.suppress(ProcessLookupError):
                    os.kill(process.pid, signal.SIGKILL)
                process.wait(timeout=30)

    def tails(self, lines: int = 25) -> str:
        """The last lines of every process's output, to say why a test failed."""
        out = []
        for log in self.logs:
            text = log.read_text(encoding="utf-8", errors="replace") if log.exists() else ""
            out.append(f"--- {log.name} (last {lines} lines)")
            out.extend(text.splitlines()[-lines:])
        return "\n".join(out)


@contextlib.contextmanager
def processes() -> Iterator[Processes]:
    """Processes started for a test, stopped when it ends; a failed assertion
    carries the end of each one's output."""
    running = Processes()
    try:
        yield running
    except AssertionError as failure:
        running.stop_all()  # so that their output is whole before it is read
        raise AssertionError(f"{failure}\n{running.tails()}") from failure
    finally:
        running.stop_all()
