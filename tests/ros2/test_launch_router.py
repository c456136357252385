"""``cfgplan launch ... --ros2 --connect ROUTER`` behind a Zenoh router (slow).

rmw_zenoh's peers meet through a router (``rmw_zenohd``) and find each other
by gossip: the router tells each peer the others' locators. Launch's own
Zenoh configuration had gossip off, so a ROS 2 peer behind the router saw no
token and no message of the society. Here a Zenoh router (zenoh-python in
router mode, rmw_zenohd's mode, standing for it) listens on a free loopback
port, a ROS-side peer (rmw_zenoh's session settings: peer, gossip on,
connected to the router only) subscribes to every topic and liveliness token,
and ``cfgplan launch`` runs cross-door step 1 with the ROS 2 map, ``--ros2``
and ``--connect`` to the router. The peer must see the robots' ``@ros2_lv``
tokens and messages on ``/door_estimate`` and ``/cfgplan/events`` or the
channel topics. The fault: the router is frozen (SIGSTOP) and let go
(SIGCONT); the messages still arrive after it runs again. Hermetic: loopback,
free ports, multicast off, bounded waits; every process stopped by its pid.
"""

from __future__ import annotations

import json
import os
import signal
import threading
import time
from pathlib import Path

import pytest

from tests.backends.support import DOMAINS, EXAMPLE_IMPL, ROOT
from tests.runtime.netutil import endpoint, free_port, processes

zenoh = pytest.importorskip("zenoh")
pytest.importorskip("rosbags")

pytestmark = pytest.mark.slow

MAP = ROOT / "examples" / "cross-door" / "ros2-map.toml"
STEP1 = [
    str(DOMAINS / "cross-door/domain.lisp"),
    str(DOMAINS / "cross-door/state-6.2.2-step1.lisp"),
]
LIMIT = 60.0  # seconds: interpreters, a plan, Zenoh handshakes, on a loaded machine
ROUTER = """
import json, sys, time, zenoh
c = zenoh.Config()
c.insert_json5("mode", '"router"')
c.insert_json5("listen/endpoints", json.dumps([sys.argv[1]]))
c.insert_json5("scouting/multicast/enabled", "false")
s = zenoh.open(c)
print("ready", flush=True)
time.sleep(float(sys.argv[2]))
s.close()
"""


class RosPeer:
    """A peer as rmw_zenoh opens one: gossip on, connected to the router only."""

    def __init__(self, router: str) -> None:
        conf = zenoh.Config()
        conf.insert_json5("mode", '"peer"')
        conf.insert_json5("listen/endpoints", json.dumps([endpoint(free_port())]))
        conf.insert_json5("connect/endpoints", json.dumps([router]))
        conf.insert_json5("scouting/multicast/enabled", "false")
        conf.insert_json5("scouting/gossip/enabled", "true")
        self.session = zenoh.open(conf)
        self.lock = threading.Lock()
        self.tokens: set[str] = set()
        self.keys: list[str] = []
        self.session.liveliness().declare_subscriber("@ros2_lv/**", self.on_token, history=True)
        self.session.declare_subscriber("0/**", self.on_message)

    def on_token(self, sample: object) -> None:
        with self.lock:
            self.tokens.add(str(sample.key_expr))  # type: ignore[attr-defined]

    def on_message(self, sample: object) -> None:
        with self.lock:
            self.keys.append(str(sample.key_expr))  # type: ignore[attr-defined]

    def count(self, topic: str) -> int:
        with self.lock:
            return sum(1 for k in self.keys if k.startswith(f"0/{topic}/"))


def _until(what: str, holds: object, limit: float = LIMIT) -> None:
    deadline = time.monotonic() + limit
    while not holds():  # type: ignore[operator]
        assert time.monotonic() < deadline, f"not within {limit} s: {what}"
        time.sleep(0.1)


def test_a_ros_peer_behind_a_router_sees_the_launched_society(tmp_path: Path) -> None:
    router = endpoint(free_port())
    with processes() as running:
        zenohd = running.start(["-c", ROUTER, router, "300"], tmp_path / "router.log")
        _until("the router ready", lambda: "ready" in (tmp_path / "router.log").read_text())
        peer = RosPeer(router)
        try:
            launch = running.start(
                ["-m", "cfgplan", "launch", *STEP1, "--impl", str(EXAMPLE_IMPL), "--ros2",
                 "--ros2-map", str(MAP), "--connect", router, "--duration", "200"],
                tmp_path / "launch.log",
            )  # fmt: skip
            _until(
                "the robots' nodes and /door_estimate at the ROS peer",
                lambda: (
                    any("/NN/" in t and "cfgplan_Pippi" in t for t in peer.tokens)
                    and any("/NN/" in t and "cfgplan_Emil" in t for t in peer.tokens)
                    and peer.count("door_estimate") >= 5
                ),
            )
            assert any("/MP/" in t and "%door_estimate/" in t for t in peer.tokens), peer.tokens
            os.kill(zenohd.pid, signal.SIGSTOP)  # the router frozen ...
            time.sleep(3.0)
            os.kill(zenohd.pid, signal.SIGCONT)  # ... and let go
            after = peer.count("door_estimate")
            _until(
                "/door_estimate flowing again after the router ran again",
                lambda: peer.count("door_estimate") >= after + 5,
            )
            assert peer.count("cfgplan/channel/pos/Pippi/Door1") > 0, sorted(set(peer.keys))[:9]
            assert launch.poll() is None, "the launch ended early"
            launch.send_signal(signal.SIGTERM)  # the launch stops its robots
            assert launch.wait(timeout=30) == 0
        finally:
            peer.session.close()  # the router is stopped by its pid with the rest
