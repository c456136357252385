"""Fixtures of the runtime's network tests: a lossy link between two network
namespaces (:class:`benchmarks.lossy_link.NetnsLink`) and the processes run in
them, each answering within :data:`LIMIT` seconds."""

from __future__ import annotations

import os
import selectors
import subprocess
import sys
from collections.abc import Iterator

import pytest

from benchmarks.lossy_link import LinkUnavailable, NetnsLink
from benchmarks.reconfigure import ROOT

LIMIT = 60.0  # seconds for any process to answer


@pytest.fixture
def netns_link() -> Iterator[NetnsLink]:
    """Two namespaces joined by a forwarder that can drop packets; skipped
    where namespaces cannot be made (needs root), a failure under CI."""
    try:
        made = NetnsLink(seed=5)
    except LinkUnavailable as error:
        reason = f"no network namespaces here ({error}); .ci/run runs as root"
        if os.environ.get("CI"):
            pytest.fail(f"{reason}, and CI must not skip this test", pytrace=False)
        pytest.skip(reason)
    try:
        yield made
    finally:
        made.close()


def start_in(link: NetnsLink, side: int, args: list[str]) -> subprocess.Popen[str]:
    """``python ARGS`` in namespace ``side``, its stdin and stdout piped; Zenoh's
    runtime threads its own (no ``ZENOH_RUNTIME`` passed down from this process)."""
    env = {k: v for k, v in os.environ.items() if k != "ZENOH_RUNTIME"}
    return subprocess.Popen(
        link.wrap(side, [sys.executable, *args]),
        cwd=ROOT,
        env=env,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )


def next_line(process: subprocess.Popen[str]) -> str:
    """The process's next line of output, within :data:`LIMIT` seconds."""
    assert process.stdout is not None
    with selectors.DefaultSelector() as selector:
        selector.register(process.stdout, selectors.EVENT_READ)
        if not selector.select(LIMIT):
            raise AssertionError(f"no answer within {LIMIT:g} s from {process.args!r}")
    return process.stdout.readline().strip()


def say(process: subprocess.Popen[str], text: str = "go") -> None:
    """Write one line to the process."""
    assert process.stdin is not None
    process.stdin.write(text + "\n")
    process.stdin.flush()


def stop_all(started: list[subprocess.Popen[str]]) -> None:
    """Kill every process started, each by its own pid, and reap it."""
    for process in started:
        process.kill()
    for process in started:
        process.wait(LIMIT)
