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
import subprocess

import pytest

from benchmarks.lossy_link import NetnsLink
from cfgplan.runtime.zenoh_config import DEFAULT_LEASE
from tests.runtime.conftest import next_line, say, start_in, stop_all

PORT = 7447  # inside the namespaces nobody else listens

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


@pytest.mark.slow
def test_a_client_on_a_stuck_link_does_not_stall_a_healthy_one(netns_link: NetnsLink) -> None:
    link = netns_link
    router = f"tcp/{link.addresses[0]}:{PORT}"
    seconds = 4 * DEFAULT_LEASE
    started: list[subprocess.Popen[str]] = []
    try:
        serving = start_in(link, 0, ["-m", "cfgplan", "router", "--listen", router])
        started.append(serving)
        assert "listening" in next_line(serving)
        stuck = start_in(link, 1, ["-c", STUCK, router])
        started.append(stuck)
        assert next_line(stuck) == "ready"
        healthy = start_in(link, 0, ["-c", HEALTHY, router, f"{seconds:g}", "4000"])
        started.append(healthy)
        assert next_line(healthy) == "ready"
        link.set(loss=1.0)  # the stuck client's link: its TCP window shuts, the router keeps it
        say(healthy)
        seen = json.loads(next_line(healthy))
    finally:
        link.set()
        stop_all(started)
    assert seen["gone"] == [], seen  # the router never dropped the healthy client
    assert seen["gap"] < DEFAULT_LEASE / 2, seen  # its link was never left unread for long
    assert seen["beats"] > 10 * seconds, seen
