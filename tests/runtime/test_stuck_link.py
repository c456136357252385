"""A client whose link is stuck (a lossy link's TCP window shut) must not
stall a healthy client of the same router (:mod:`cfgplan.runtime.router`,
:data:`cfgplan.runtime.zenoh_config.STUCK_LINK`).

Zenoh's router sends a declaration on to every client on the thread that
reads the link it came on, and waits for room in a full client's queue, up to
``wait_before_close``: with Zenoh's 5 s, a healthy robot whose declarations
went to a client behind a bad link had its own link left unread past its
lease, and was dropped (``python -m benchmarks.link_loss``). Here, in two
network namespaces joined by :class:`benchmarks.lossy_link.NetnsLink`:
``cfgplan router`` and a healthy process (two clients: one publishing a beat
and declaring tokens, one watching both) on one side; on the other a client
that subscribes to the tokens and announces a long lease, so the router keeps
its link while every packet on it is dropped. Its queue fills with the
tokens; the beat must go on (no gap near the lease) and the healthy client's
token must never go. Needs root, ``/dev/net/tun`` and ``ip``: skipped where
missing, a failure under CI.
"""

from __future__ import annotations

import json
import os
import selectors
import subprocess
import sys
from collections.abc import Iterator

import pytest

from benchmarks.lossy_link import LinkUnavailable, NetnsLink
from benchmarks.reconfigure import ROOT
from cfgplan.runtime.zenoh_config import DEFAULT_LEASE

PORT = 7447  # inside the namespaces nobody else listens
LIMIT = 60.0  # seconds for any process to answer

STUCK = """
import sys, time, zenoh
from cfgplan.runtime.zenoh_config import ZenohOptions, zenoh_config
session = zenoh.open(zenoh_config(ZenohOptions(router=(sys.argv[1],), lease=60.0)))
tokens = session.liveliness().declare_subscriber("stuck/**", lambda sample: None)
print("ready", flush=True)
sys.stdin.readline()
"""

HEALTHY = """
import json, sys, threading, time, zenoh
from cfgplan.runtime.zenoh_config import ZenohOptions, zenoh_config
options = ZenohOptions(router=(sys.argv[1],))
seconds, count = float(sys.argv[2]), int(sys.argv[3])
sender, watcher = zenoh.open(zenoh_config(options)), zenoh.open(zenoh_config(options))
beats, gone = [], []
watcher.declare_subscriber("stuck/beat", lambda sample: beats.append(time.monotonic()))
def seen(sample):
    if sample.kind == zenoh.SampleKind.DELETE:
        gone.append(str(sample.key_expr))
watcher.liveliness().declare_subscriber("stuck/alive/**", seen)
alive = sender.liveliness().declare_token("stuck/alive/healthy")
beat = sender.declare_publisher("stuck/beat")
stop = threading.Event()
def beating():
    while not stop.is_set():
        beat.put(b"beat")
        time.sleep(0.02)
threading.Thread(target=beating, daemon=True).start()
deadline = time.monotonic() + 30
while len(beats) < 10 and time.monotonic() < deadline:
    time.sleep(0.05)
print("ready" if beats else "no beat", flush=True)
sys.stdin.readline()
began = time.monotonic()
flood = [
    sender.liveliness().declare_token(f"stuck/flood/{k:05d}/" + "x" * 100) for k in range(count)
]
time.sleep(max(0.0, began + seconds - time.monotonic()))
ended = time.monotonic()
stop.set()
times = [began] + [t for t in beats if began <= t <= ended] + [ended]
gap = max(b - a for a, b in zip(times, times[1:]))
print(json.dumps({"gap": gap, "gone": gone, "beats": len(times) - 2}), flush=True)
"""


@pytest.fixture
def link() -> Iterator[NetnsLink]:
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


def _start(link: NetnsLink, side: int, args: list[str]) -> subprocess.Popen[str]:
    return subprocess.Popen(
        link.wrap(side, [sys.executable, *args]),
        cwd=ROOT,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )


def _line(process: subprocess.Popen[str]) -> str:
    """The process's next line of output, within :data:`LIMIT` seconds."""
    assert process.stdout is not None
    with selectors.DefaultSelector() as selector:
        selector.register(process.stdout, selectors.EVENT_READ)
        if not selector.select(LIMIT):
            raise AssertionError(f"no answer within {LIMIT:g} s from {process.args!r}")
    return process.stdout.readline().strip()


@pytest.mark.slow
def test_a_client_on_a_stuck_link_does_not_stall_a_healthy_one(link: NetnsLink) -> None:
    router = f"tcp/{link.addresses[0]}:{PORT}"
    seconds = 4 * DEFAULT_LEASE
    started: list[subprocess.Popen[str]] = []
    try:
        serving = _start(link, 0, ["-m", "cfgplan", "router", "--listen", router])
        started.append(serving)
        assert "listening" in _line(serving)
        stuck = _start(link, 1, ["-c", STUCK, router])
        started.append(stuck)
        assert _line(stuck) == "ready"
        healthy = _start(link, 0, ["-c", HEALTHY, router, f"{seconds:g}", "4000"])
        started.append(healthy)
        assert _line(healthy) == "ready"
        link.set(loss=1.0)  # the stuck client's link: its TCP window shuts, the router keeps it
        assert healthy.stdin is not None
        healthy.stdin.write("go\n")
        healthy.stdin.flush()
        seen = json.loads(_line(healthy))
    finally:
        link.set()
        for process in started:
            process.kill()
        for process in started:
            process.wait(LIMIT)
    assert seen["gone"] == [], seen  # the router never dropped the healthy client
    assert seen["gap"] < DEFAULT_LEASE / 2, seen  # its link was never left unread for long
    assert seen["beats"] > 10 * seconds, seen
